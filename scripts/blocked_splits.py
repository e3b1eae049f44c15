#!/usr/bin/env python3
"""Writes the blocked splits of the IPA UR10 Series A and D tasks (docs/formats.md § 9.2).

Series D (ISO 9283 cubes): the rows come in cycles of nine (a cube's centre, then its eight
corners), each cube measured at three sizes; a *site* is every cycle whose centre lies within
5 mm of the first cycle of the site, in order of first appearance. Every third site (the 3rd,
6th, ...) validates, whole: no validation pose repeats, or lies inside a cube of, a calibration cycle.

Series A (grid): each grid point (the commanded position, to 1 mm) is measured in several
orientations. The grid's coordinates are numbered per axis; a *region* is a block of 2 x 2 x 2
grid points, and the regions whose block indices sum to a multiple of 3 validate, whole: a
validation point is never a calibration point seen in another orientation.

The commanded positions are the exports' `Goal x/y/z` columns (m); only the standard library
is used, so `python3 scripts/blocked_splits.py` rewrites both files byte for byte.
"""

import csv
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def goals(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f, delimiter=";"))
    head, body = rows[0], rows[1:]
    cols = [head.index(c) for c in ("Goal x", "Goal y", "Goal z")]
    return [tuple(round(float(r[c].replace(",", ".")) * 1000) for c in cols) for r in body]


def ranges(rows, part):
    out, start = [], None
    for i, r in enumerate(rows + [None]):
        if r == part and start is None:
            start = i
        if r != part and start is not None:
            out.append((start, i - 1))
            start = None
    return out


def write(path, header, labels):
    n = len(labels)
    lines = ["# " + h for h in header] + ["rows %d" % n]
    spans = []
    for part in ("calibration", "validation"):
        spans += [(a, b, part) for a, b in ranges(labels, part)]
    for a, b, part in sorted(spans):
        lines.append("%s %s" % (part, str(a) if a == b else "%d-%d" % (a, b)))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    cal = labels.count("calibration")
    return cal, n - cal


def series_d():
    data = "data/ipa-ur10-series-d/measurements_iso_cubes.csv"
    g = goals(os.path.join(ROOT, data))
    sites, centres = [], []
    for start in range(0, len(g), 9):
        centre = g[start]
        near = [k for k, c in enumerate(centres) if max(abs(a - b) for a, b in zip(c, centre)) <= 5]
        if near:
            k = near[0]
        else:
            k = len(sites)
            sites.append([])
            centres.append(centre)
        sites[k].extend(range(start, min(start + 9, len(g))))
    labels = [None] * len(g)
    for k, rows in enumerate(sites):
        for r in rows:
            labels[r] = "validation" if k % 3 == 2 else "calibration"
    cal, val = write(
        os.path.join(ROOT, "tasks/ipa-ur10-series-d-blocked.split"),
        [
            "The blocked split of %s (ISO cubes, %d rows), by cube site:" % (data, len(g)),
            "0-based data rows (the header not counted); FIRST-LAST includes both ends. The rows",
            "come in cycles of nine (centre, eight corners); a site is every cycle whose centre lies",
            "within 5 mm of its first cycle's (%d sites, in order of first appearance); every" % len(sites),
            "third site validates, whole.",
            "Written by scripts/blocked_splits.py.",
        ],
        labels,
    )
    print("series D: %d sites, %d calibrate, %d validate" % (len(sites), cal, val))


def series_a():
    data = "data/ipa-ur10-series-a/measurements_grid.csv"
    g = goals(os.path.join(ROOT, data))
    axes = [sorted({p[k] for p in g}) for k in range(3)]
    labels = []
    for p in g:
        block = sum(axes[k].index(p[k]) // 2 for k in range(3))
        labels.append("validation" if block % 3 == 0 else "calibration")
    cal, val = write(
        os.path.join(ROOT, "tasks/ipa-ur10-series-a-blocked.split"),
        [
            "The blocked split of %s (a grid, %d rows), by grid region:" % (data, len(g)),
            "0-based data rows (the header not counted); FIRST-LAST includes both ends. A grid",
            "point is the commanded position (to 1 mm), measured in several orientations; its",
            "coordinates numbered per axis, a region is a block of 2 x 2 x 2 grid points, and",
            "the regions whose block indices sum to a multiple of 3 validate, whole.",
            "Written by scripts/blocked_splits.py.",
        ],
        labels,
    )
    print("series A: %d grid points, %d calibrate, %d validate" % (len(set(g)), cal, val))


if __name__ == "__main__":
    series_d()
    series_a()
