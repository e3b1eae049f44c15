"""What calling calbench from Python costs (docs/performance.md, "From Python"):

1. `calbench.identify` (lm, 50 poses of the default study) against the same identification
   inside Rust: the result's `seconds` is the Rust side's wall time, the rest is the binding;
2. `calbench.run` of the default study against `calbench run` of it, interleaved;
3. a method written in Python per trial: `seconds_per_identification` of a method that returns
   its start (the binding's cost: the problem's copy, the call under the GIL, the assessment)
   and of a numpy Gauss-Newton, beside the built-in `ls`, on ci-guard with 1 and 2 threads.

usage: python benches/python_overhead.py CALBENCH_BINARY [--quick]   (from the repository root)
"""
import json
import statistics as st
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np

import calbench

binary, quick = sys.argv[1], "--quick" in sys.argv[2:]

d = calbench.simulate("scenarios/default.toml", trial=0)
q, p = d["q"], d["points"]
robot = calbench.Robot.builtin("irb2600")
total, rust = [], []
for _ in range(20 if quick else 500):
    t0 = time.perf_counter()
    r = calbench.identify(robot, q, p, method="lm")
    total.append(time.perf_counter() - t0)
    rust.append(r.seconds)
over = [a - b for a, b in zip(total, rust)]
print(
    f"identify lm, {len(q)} poses: median {st.median(total) * 1e6:.1f} µs in all, "
    f"{st.median(rust) * 1e6:.1f} µs in Rust; binding overhead median "
    f"{st.median(over) * 1e6:.1f} µs, p90 {np.percentile(over, 90) * 1e6:.1f} µs"
)

if not quick:
    py_t, cli_t = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        calbench.run("scenarios/default.toml")
        py_t.append(time.perf_counter() - t0)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            subprocess.run([binary, "run", "scenarios/default.toml", "--out", f"{tmp}/o"],
                           check=True, capture_output=True)
            cli_t.append(time.perf_counter() - t0)
    print(
        f"default study: calbench.run {', '.join(f'{x:.2f}' for x in py_t)} s; "
        f"calbench run {', '.join(f'{x:.2f}' for x in cli_t)} s; "
        f"ratio of the medians {st.median(py_t) / st.median(cli_t):.3f}"
    )

with open("scenarios/ci-guard.toml", "rb") as f:
    scenario = tomllib.load(f)


def start(problem):
    return problem.x0


def gauss_newton(problem):
    x = problem.x0
    for _ in range(50):
        dx = np.linalg.lstsq(problem.jacobian(x), -problem.residual(x), rcond=None)[0]
        x = x + dx
        if np.max(np.abs(dx)) < 1e-10:
            break
    return x


for threads in (1, 2):
    study = calbench.run(scenario, trials=8 if quick else 200, threads=threads,
                         methods={"start": start, "gauss-newton": gauss_newton})
    with tempfile.TemporaryDirectory() as tmp:
        study.write(f"{tmp}/o")
        with open(f"{tmp}/o/timing.json") as f:
            timing = json.load(f)
    per = ", ".join(f"{e['method']} {e['seconds_per_identification'] * 1e3:.3f}" for e in timing["results"])
    print(f"{threads} thread(s): run {timing['run_seconds']:.2f} s; ms per identification: {per}")
