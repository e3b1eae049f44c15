"""Shared fixtures of the Python module's tests: the repository root, the command-line
binary to compare with, and temporary folders."""
import os
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _binary():
    env = os.environ.get("CALBENCH_BIN")
    if env:
        return env
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    for profile in ("debug", "release"):
        b = target / profile / "calbench"
        if b.exists():
            return str(b)
    return shutil.which("calbench")


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def binary():
    """The calbench binary to compare with: $CALBENCH_BIN, else one built under the target
    folder, else one on PATH; its absence skips (fails with CI=true)."""
    b = _binary()
    if b is None or not Path(b).exists():
        if os.environ.get("CI") in ("true", "1"):
            pytest.fail("no calbench binary (set CALBENCH_BIN or build it)")
        pytest.skip("no calbench binary to compare with (set CALBENCH_BIN)")
    return b


@pytest.fixture(scope="session")
def cli(binary):
    """Runs the calbench binary from the repository root; fails on a non-zero exit."""
    b = binary

    def run(*args, ok=True):
        r = subprocess.run([b, *map(str, args)], cwd=ROOT, capture_output=True, text=True)
        if ok and r.returncode != 0:
            raise AssertionError(f"calbench {' '.join(map(str, args))}: {r.stderr}")
        return r

    return run


@pytest.fixture
def ci_guard():
    """A fresh dict of scenarios/ci-guard.toml, the small study the tests run."""
    with open(ROOT / "scenarios" / "ci-guard.toml", "rb") as f:
        return tomllib.load(f)
