"""The paired comparisons of a study's summary.json (docs/formats.md "comparisons") against
scipy: the mean per-trial difference, the Wilcoxon signed-rank p-value and Holm's adjustment,
from the per-trial values of trials.csv, to 1e-9 relative."""
import json
import math

import pandas as pd
import pytest
from scipy import stats

FAILED = {"diverged", "singular", "invalid-input"}


def close(a, b, rel=1e-9):
    return math.isclose(a, b, rel_tol=rel, abs_tol=1e-300)


def per_trial(df):
    """Each row's validation RMS after and mean η over the parameters (base left out), NaN
    for a failed identification, by entry label and trial."""
    params = [c[len("true_"):] for c in df.columns if c.startswith("true_")]
    out = {}
    for _, row in df.iterrows():
        label = f"{row['method']} / {row['poses']}"
        ok = row["termination"] not in FAILED and math.isfinite(row["after_rms_mm"])
        etas = []
        for p in params:
            if p.startswith("base."):
                continue
            x, y = row[f"true_{p}"], row[f"identified_{p}"]
            if x != 0.0:
                etas.append((1.0 - abs(x - y) / abs(x)) * 100.0)
        eta = sum(etas) / len(etas) if (ok and etas) else math.nan
        rms = row["after_rms_mm"] if ok else math.nan
        out.setdefault(label, {})[int(row["trial"])] = {
            "validation_after_mm.rms": rms,
            "eta_mean_pct": eta,
        }
    return out


def holm(p):
    order = sorted(range(len(p)), key=lambda i: (p[i], i))
    m, running, out = len(p), 0.0, [0.0] * len(p)
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p[i]))
        out[i] = running
    return out


@pytest.mark.parametrize("trials", [30, 60])
def test_comparisons_match_scipy(cli, tmp_path, trials):
    out = tmp_path / "run"
    cli("run", "scenarios/ci-guard.toml", "--trials", trials, "--out", out)
    summary = json.loads((out / "summary.json").read_text())
    values = per_trial(pd.read_csv(out / "trials.csv"))
    comps = summary["comparisons"]
    # Three methods on one strategy: every pair, two metrics each.
    assert len(comps) == 6
    p_scipy = []
    for c in comps:
        a, b = values[c["a"]], values[c["b"]]
        d = [
            b[t][c["metric"]] - a[t][c["metric"]]
            for t in sorted(a)
            if math.isfinite(a[t][c["metric"]]) and math.isfinite(b[t][c["metric"]])
        ]
        assert c["n"] == len(d)
        assert close(c["diff_mean"], sum(d) / len(d)), c
        p = stats.wilcoxon(d).pvalue
        assert close(c["p_value"], p), (c, p)
        p_scipy.append(p)
        lower = c["metric"].startswith("validation")
        wins = sum(1 for x in d if (x < 0 if lower else x > 0)) / len(d)
        assert close(c["win_rate"], wins)
        lo, hi = c["diff_ci95"]
        assert lo < c["diff_mean"] < hi
    for c, h in zip(comps, holm(p_scipy)):
        assert close(c["p_holm"], h), (c, h)
