"""A sweep with a method written in Python, benchmarked beside the built-in ones on the same
draws: scenarios/ci-guard.toml with the number of outliers swept, a numpy Gauss-Newton
registered as "gauss-newton", the results as a pandas DataFrame, and a plot of eta against
the outlier count when matplotlib is installed.

usage: python examples/python/sweep.py [OUT_DIR]   (from the repository root)
"""
import sys
import tomllib
from pathlib import Path

import numpy as np

import calbench


def gauss_newton(problem):
    """Plain Gauss-Newton on the weighted residual: the fixed point of the built-in `ls`."""
    x = problem.x0
    for _ in range(50):
        dx = np.linalg.lstsq(problem.jacobian(x), -problem.residual(x), rcond=None)[0]
        x = x + dx
        if np.max(np.abs(dx)) < 1e-10:
            return x, "converged"
    return x, "max-iterations"


out = Path(sys.argv[1] if len(sys.argv) > 1 else "results/python-sweep")
with open("scenarios/ci-guard.toml", "rb") as f:
    scenario = tomllib.load(f)
scenario["sweep"] = {"key": "outliers.count", "values": [0, 2, 4]}

study = calbench.run(scenario, trials=8, methods={"gauss-newton": gauss_newton})
df = study.results[["sweep_value", "method", "eta_mean_pct", "validation_after_mm.rms", "failures"]]
print(df.to_string(index=False))
study.write(out / "study")

try:
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no plot")
else:
    fig, ax = plt.subplots(figsize=(6, 4))
    for method, rows in df.groupby("method"):
        ax.plot(rows["sweep_value"], rows["eta_mean_pct"], marker="o", label=method)
    ax.set_xlabel("outliers in the calibration measurement")
    ax.set_ylabel("mean η (%)")
    ax.legend()
    fig.savefig(out / "eta.png", dpi=100)
    print(f"plot: {out / 'eta.png'}")
