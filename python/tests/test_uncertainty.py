"""The uncertainty of a study from Python (docs/python.md "Intervals, paired comparisons and
the regression guard"): the interval columns of ``study.results``, ``study.comparisons`` and
``calbench.compare`` against the command line's summary.json, compare.md and check."""
import json
import math

import pandas as pd
import pytest

import calbench

TRIALS = 30


def same(x, y):
    """Equal numbers, or both missing (NaN / None)."""
    missing = lambda v: v is None or (isinstance(v, float) and math.isnan(v))  # noqa: E731
    return (missing(x) and missing(y)) or x == y


@pytest.fixture(scope="module")
def runs(cli, root, tmp_path_factory):
    """Three CLI runs of ci-guard: seed 42, seed 9, and seed 42 with a tracker ten times
    noisier (a planted regression of the validation error)."""
    d = tmp_path_factory.mktemp("uncertainty")
    text = (root / "scenarios" / "ci-guard.toml").read_text()
    noisy = d / "noisy.toml"
    noisy.write_text(text.replace("[tracker]\n", "[tracker]\nmpe_a_um = 150.0\nmpe_b_um_per_m = 60.0\n"))
    out = {}
    for name, scenario, seed in [("a", root / "scenarios" / "ci-guard.toml", 42),
                                 ("b", root / "scenarios" / "ci-guard.toml", 9),
                                 ("noisy", noisy, 42)]:
        out[name] = d / name
        cli("run", scenario, "--trials", TRIALS, "--seed", seed, "--out", out[name], "--threads", 2)
    out["dir"] = d
    return out


def test_results_split_every_interval_into_lo_and_hi(root, runs):
    study = calbench.run(root / "scenarios" / "ci-guard.toml", trials=TRIALS, threads=2)
    summary = json.loads((runs["a"] / "summary.json").read_text())
    assert study.summary == summary
    df = study.results
    pairs = [c for c in df.columns if c.endswith("_ci95") or c.startswith("param_rmse_ci95.")]
    pairs = [c for c in pairs if not c.endswith(("_lo", "_hi"))]
    for key in ("eta_mean_pct_ci95", "eta_median_pct_ci95", "validation_after_mm.rms_ci95",
                "validation_after_mm.mean_ci95", "eta.a2.mean_ci95", "param_rmse_ci95.d2"):
        assert key in pairs, key
    for col in pairs:
        i = list(df.columns).index(col)
        assert list(df.columns[i + 1:i + 3]) == [f"{col}_lo", f"{col}_hi"]
        assert df[f"{col}_lo"].dtype == float and df[f"{col}_hi"].dtype == float
    for k, entry in enumerate(summary["results"]):
        for col, path in [("eta_mean_pct", ["eta_mean_pct_ci95"]),
                          ("validation_after_mm.rms", ["validation_after_mm", "rms_ci95"])]:
            ci = entry
            for p in path:
                ci = ci[p]
            lo, hi = df.loc[k, f"{col}_ci95_lo"], df.loc[k, f"{col}_ci95_hi"]
            assert (lo, hi) == tuple(ci)
            assert lo < df.loc[k, col] < hi


def test_a_missing_interval_is_nan(root):
    # One trial: no interval (null in summary.json), NaN bounds.
    study = calbench.run(root / "scenarios" / "ci-guard.toml", trials=1)
    assert study.summary["results"][0]["eta_mean_pct_ci95"] is None
    df = study.results
    assert df["eta_mean_pct_ci95_lo"].isna().all() and df["eta_mean_pct_ci95_hi"].isna().all()
    assert df["eta_mean_pct"].notna().all()


def test_comparisons_are_the_summary_s_one_row_each(root, runs):
    study = calbench.run(root / "scenarios" / "ci-guard.toml", trials=TRIALS, threads=2)
    expected = json.loads((runs["a"] / "summary.json").read_text())["comparisons"]
    df = study.comparisons
    assert len(df) == len(expected) == 6
    for key in expected[0]:
        assert key in df.columns, key
    for (_, row), c in zip(df.iterrows(), expected):
        for key, value in c.items():
            got = row[key]
            assert (list(got) == value) if isinstance(value, list) else same(got, value), key
        assert (row["diff_ci95_lo"], row["diff_ci95_hi"]) == tuple(c["diff_ci95"])
    assert set(df["metric"]) == {"validation_after_mm.rms", "eta_mean_pct"}
    # A study of one method has none: an empty frame with the keys as columns.
    scenario = (root / "scenarios" / "ci-guard.toml").read_text().split("[[methods]]")[0]
    one = runs["dir"] / "one.toml"
    one.write_text(scenario + '[[methods]]\nname = "lm"\n')
    empty = calbench.run(one, trials=3).comparisons
    assert len(empty) == 0 and {"a", "b", "metric", "p_holm"} <= set(empty.columns)


def cli_statuses(cli, a, b, out):
    """compare.md's table of `calbench compare A B`: (entry, metric) → (status, compared)."""
    cli("compare", a, b, "--out", out)
    rows = {}
    for line in (out / "compare.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 10 and cells[0] not in ("entry", "---") and not cells[0].startswith("-"):
            rows[(cells[0], cells[1])] = (cells[6], cells[9])
    return rows


@pytest.mark.parametrize("other", ["b", "noisy"])
def test_compare_gives_the_statuses_of_the_command_line(cli, runs, other):
    a, b = runs["a"], runs[other]
    cmp = calbench.compare(a, b)
    expected = cli_statuses(cli, a, b, runs["dir"] / f"cmp-{other}")
    m = cmp.metrics
    assert len(m) == len(expected) > 30
    for _, row in m.iterrows():
        status, compared = expected[(row["entry"], row["metric"])]
        assert status.startswith(row["status"]), (row["entry"], row["metric"], status)
        assert compared == ("paired" if row["paired"] else "unpaired")
        if row["status"] == "unresolved":
            assert row["trials_needed"] > 0
    assert cmp.regressions == (m["status"] == "regression").sum()
    check = cli("check", b / "summary.json", "--baseline", a / "summary.json", ok=False)
    if other == "noisy":
        # check compares one scenario from version to version: the edited tracker is
        # refused by its setting, which the comparison names too.
        assert check.returncode != 0 and "tracker.mpe_a_um" in check.stderr, check.stderr
        assert "tracker.mpe_a_um" in cmp.scenario_note
    else:
        assert (check.returncode != 0) == (cmp.regressions > 0), check.stderr
        assert cmp.scenario_note is None
    # A summary's path is taken as its folder is.
    again = calbench.compare(a / "summary.json", b / "summary.json")
    pd.testing.assert_frame_equal(again.metrics, m)
    assert again.verdict == cmp.verdict


def test_compare_tells_noise_from_a_planted_regression(runs):
    # Another seed: unpaired, nothing regressed.
    other = calbench.compare(runs["a"], runs["b"])
    assert other.regressions == 0
    assert set(other.metrics["status"]) <= {"no change", "unresolved"}
    assert not other.metrics["paired"].any()
    assert other.verdict.startswith("No regression")
    # The tracker ten times noisier on the same seed: the validation error of every entry
    # is a paired regression whose interval excludes zero.
    noisy = calbench.compare(runs["a"], runs["noisy"])
    rms = noisy.metrics[noisy.metrics["metric"] == "validation_after_mm.rms"]
    assert len(rms) == 3
    assert (rms["status"] == "regression").all() and rms["paired"].all()
    assert (rms["diff_ci_lo"] > 0).all() and (rms["diff"] > 0).all()
    assert noisy.regressions >= 3 and "regressed" in noisy.verdict
    # Under one name, the edited tracker is named as the page names it.
    assert noisy.scenario_note.startswith('A and B ran scenario "ci-guard" with other settings (')
    assert "tracker.mpe_a_um: (none) → 150.0" in noisy.scenario_note
    assert other.scenario_note is None
    assert f"{noisy.regressions} regressions" in repr(noisy)


def test_compare_refuses_bad_arguments(runs, tmp_path):
    with pytest.raises(calbench.IoError, match="summary.json"):
        calbench.compare(tmp_path, runs["a"])
    bad = tmp_path / "bad.json"
    bad.write_text('{"results": []}')
    with pytest.raises(calbench.FileError, match="bad.json.*not a calbench summary"):
        calbench.compare(runs["a"], bad)
    # 10**400 is beyond a float: refused as the setting, not a bare OverflowError.
    for tol in (-0.1, float("nan"), float("inf"), 10.5, 1e308, "5 %", True, 10**400, -10**400):
        with pytest.raises(calbench.SettingError, match="tolerance"):
            calbench.compare(runs["a"], runs["b"], tolerance=tol)
    with pytest.raises(calbench.SettingError, match="`a`"):
        calbench.compare(None, runs["b"])
    # A wider tolerance: fewer regressions, never more.
    loose = calbench.compare(runs["a"], runs["noisy"], tolerance=10.0)
    assert loose.regressions == 0 and loose.tolerance == 10.0
