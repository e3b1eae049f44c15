#!/usr/bin/env python3
"""The error rates of the regression guard (docs/guard.md), measured with `calbench check`.

Runs scenarios/ci-guard.toml at the guard's trial count on 2 x PAIRS seeds (a baseline run
and a candidate run per pair), writes each baseline with `calbench baseline` (per-trial values,
so that a run of the same seed pairs), and counts how often `calbench check --tolerance T`
fails:

- false alarms, over PAIRS pairs of unchanged runs:
  - `different seeds`: the candidate is a run of another seed (compared unpaired);
  - `same seed, moved draws`: the candidate is that run with the baseline's seed written in
    its summary, which is what `check` sees after a change of the code that moves every draw
    but not the result (compared trial by trial, on independent draws);
- detections of a change planted in validation_after_mm (+0.5, 1, 2, 5, 10 % by default):
  - `paired, same draws`: planted on the baseline's own run (a change that keeps the draws);
  - `paired, moved draws`: planted on the moved-draws candidate;
  - `unpaired`: planted on the run of another seed.

A detection is a failing check that names validation_after_mm. The change is planted on the
numbers `check` reads: each trial's validation errors in trials.csv (after_mean_mm,
after_rms_mm, after_max_mm) and the summary's validation_after_mm figures and their 95 %
intervals, all multiplied by 1 + change. That is what a code change making every validation
error that much larger produces, exactly, and nothing else: no other metric moves, so the
detection rate is that of validation_after_mm alone (a real regression usually moves several
metrics at once, which only helps the guard).

usage: scripts/guard-calibration.py [--calbench target/release/calbench] [--trials N]
       [--pairs P] [--tolerance T,...] [--changes 0.5,1,2,5,10] [--work DIR] [--jobs J]
Prints a Markdown table per tolerance, and with --json FILE writes the figures as JSON.
"""

import argparse
import concurrent.futures
import csv
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(ROOT, "scenarios", "ci-guard.toml")
PLANTED_COLUMNS = ["after_mean_mm", "after_rms_mm", "after_max_mm"]
PLANTED_METRIC = "validation_after_mm"


def sh(args):
    return subprocess.run(args, capture_output=True, text=True)


def run(calbench, trials, seed, out):
    if os.path.isfile(os.path.join(out, "summary.json")):
        return
    if os.path.isdir(out):
        shutil.rmtree(out)
    o = sh([calbench, "run", SCENARIO, "--trials", str(trials), "--seed", str(seed),
            "--threads", "1", "--out", out])
    if o.returncode != 0:
        sys.exit(f"calbench run failed: {o.stderr}")


def copy_run(src, dst, seed=None, scale=1.0):
    """A copy of run folder `src` at `dst` (summary.json, trials.csv), its seed replaced by
    `seed` and validation_after_mm multiplied by `scale`."""
    if os.path.isdir(dst):
        shutil.rmtree(dst)
    os.makedirs(dst)
    with open(os.path.join(src, "summary.json")) as f:
        s = json.load(f)
    if seed is not None:
        s["seed"] = seed
    if scale != 1.0:
        for e in s["results"]:
            for k in (PLANTED_METRIC, PLANTED_METRIC + "_ci95"):
                m = e.get(k)
                if isinstance(m, dict):
                    for key, v in m.items():
                        if isinstance(v, list):
                            m[key] = [x * scale if x is not None else None for x in v]
                        elif isinstance(v, (int, float)):
                            m[key] = v * scale
    with open(os.path.join(dst, "summary.json"), "w") as f:
        json.dump(s, f, indent=2)
    with open(os.path.join(src, "trials.csv"), newline="") as f:
        rows = list(csv.reader(f))
    cols = [i for i, h in enumerate(rows[0]) if h in PLANTED_COLUMNS]
    for r in rows[1:]:
        for i in cols:
            if r[i] not in ("", "NaN", "nan"):
                r[i] = repr(float(r[i]) * scale)
    with open(os.path.join(dst, "trials.csv"), "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def check(calbench, candidate, baseline, tolerance):
    """(failed, named validation_after_mm, paired) of `calbench check`."""
    o = sh([calbench, "check", os.path.join(candidate, "summary.json"), "--baseline",
            baseline, "--tolerance", str(tolerance)])
    if o.returncode not in (0, 1):
        sys.exit(f"calbench check failed to run: {o.stderr}")
    regressed = [l for l in o.stderr.splitlines() if l.startswith("regression: ")]
    named = any(f": {PLANTED_METRIC}." in l for l in regressed)
    paired = "unpaired: " not in o.stdout
    return o.returncode != 0, named, paired


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calbench", default=os.path.join(ROOT, "target", "release", "calbench"))
    ap.add_argument("--trials", type=int, default=None,
                    help="trials per run (default: the scenario's `trials`)")
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--tolerance", default="0.02,0.05")
    ap.add_argument("--changes", default="0.5,1,2,5,10,20,50", help="planted changes, per cent")
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "guard-calibration"))
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    trials = a.trials
    if trials is None:
        with open(SCENARIO) as f:
            trials = next(int(l.split("=")[1]) for l in f if l.startswith("trials"))
    tolerances = [float(t) for t in a.tolerance.split(",")]
    changes = [float(c) for c in a.changes.split(",")]
    work = os.path.join(a.work, f"trials-{trials}")
    os.makedirs(work, exist_ok=True)
    # Seeds 1000 + 2i (baseline) and 1000 + 2i + 1 (candidate).
    seeds = [(1000 + 2 * i, 1001 + 2 * i) for i in range(a.pairs)]
    runs = os.path.join(work, "runs")
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        list(ex.map(lambda s: run(a.calbench, trials, s, os.path.join(runs, str(s))),
                    [s for p in seeds for s in p]))

    def baseline(i):
        sa = seeds[i][0]
        path = os.path.join(work, "baselines", f"{sa}.json")
        if not os.path.isfile(path):
            os.makedirs(os.path.dirname(path), exist_ok=True)
            o = sh([a.calbench, "baseline", os.path.join(runs, str(sa)), "--out", path])
            if o.returncode != 0:
                sys.exit(f"calbench baseline failed: {o.stderr}")
        return path

    def one_pair(i, tol):
        sa, sb = seeds[i]
        base = baseline(i)
        cand = os.path.join(work, "cand", f"{tol}-{i}")
        out = {}
        res = check(a.calbench, os.path.join(runs, str(sb)), base, tol)
        out["false alarm, different seeds"] = (res[0], res[2])
        copy_run(os.path.join(runs, str(sb)), cand, seed=sa)
        res = check(a.calbench, cand, base, tol)
        out["false alarm, same seed, moved draws"] = (res[0], res[2])
        for c in changes:
            scale = 1.0 + c / 100.0
            for kind, src, seed in [
                ("paired, same draws", sa, None),
                ("paired, moved draws", sb, sa),
                ("unpaired", sb, None),
            ]:
                copy_run(os.path.join(runs, str(src)), cand, seed=seed, scale=scale)
                failed, named, paired = check(a.calbench, cand, base, tol)
                out[f"{kind} +{c:g} %"] = (failed and named, paired)
        shutil.rmtree(cand, ignore_errors=True)
        return out

    figures = {"trials": trials, "pairs": a.pairs, "tolerances": {}}
    for tol in tolerances:
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
            results = list(ex.map(lambda i: one_pair(i, tol), range(a.pairs)))
        rates = {}
        for key in results[0]:
            flagged = sum(r[key][0] for r in results)
            paired = sum(r[key][1] for r in results)
            rates[key] = {"flagged": flagged, "of": len(results), "paired": paired}
        figures["tolerances"][str(tol)] = rates
        print(f"\n{trials} trials per run, tolerance {tol}, {a.pairs} pairs\n")
        print("| comparison | flagged | rate | compared paired |")
        print("|---|---|---|---|")
        for key, r in rates.items():
            print(f"| {key} | {r['flagged']} / {r['of']} | "
                  f"{100.0 * r['flagged'] / r['of']:.1f} % | {r['paired']} / {r['of']} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figures, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
