#!/usr/bin/env python3
"""A scipy reference for calbench's identification speed.

It solves, many times over, the problem `benches/h2h.toml` has calbench solve, and reports the
time per identification of `scipy.optimize.least_squares` (method "lm": MINPACK's
Levenberg-Marquardt, with an analytic Jacobian). `benches/scipy_ratio.sh` runs it and the
calbench study in one sitting and prints their ratio.

The problem (the same shape as `benches/h2h.toml`, written independently of calbench's code):

- robot: the ABB IRB2600 in standard Denavit-Hartenberg form, calbench's built-in `irb2600`
  (Li 2018, table 1): joint i moves the frame by Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i);
  the tool point is the flange centre (tool offset 0), the base frame is known;
- data: 50 poses drawn uniformly within the joint limits, the tool point's position measured
  by a laser tracker at (2500, 0, 0) mm with per-axis noise sigma = (15 um + 6 um/m * range) / 2
  (an AT960-class maximum permissible error read as a two-sigma bound);
- truth: the paper error set, +0.5 mm on every identified length and +0.05 rad on every
  identified angle;
- unknowns: the errors of the parameters that position data determine, chosen in calbench's
  order (theta, d, a, alpha of joints 1 to 6, then the tool's x, y, z) by keeping each
  parameter whose Jacobian column is not a combination of the columns kept before it. On the
  IRB2600 that leaves 20 of the 27: the same 20 calbench identifies;
- the fit starts from the nominal robot, least_squares' default tolerances, x_scale="jac";
- after the fit, the validation RMS at 50 fresh poses (against the true robot, noise-free)
  shows that each fit converged to the truth.

Only the least_squares call is timed (set-up and validation are not). BLAS is held to one
thread, as calbench's study runs with `--threads 1`.

usage: python3 benches/scipy_ref.py [TRIALS (default 100)] [--poses 50] [--seed 0]
prints `key value` lines; scipy_ratio.sh reads `scipy_lm_s_per_identification`.
Needs numpy and scipy.
"""

import argparse
import os
import sys
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

try:
    import numpy as np
    from scipy.optimize import least_squares
except ImportError as e:  # scipy_ratio.sh checks this first; a direct call gets the same word
    sys.exit(f"scipy_ref.py needs numpy and scipy: {e}")

# IRB2600 standard DH: (theta offset deg, d mm, a mm, alpha deg, joint limits deg)
DH = [
    (0.0, 445.0, 150.0, -90.0, (-180.0, 180.0)),
    (-90.0, 0.0, 900.0, 0.0, (-95.0, 155.0)),
    (0.0, 0.0, 150.0, -90.0, (-180.0, 75.0)),
    (0.0, 938.0, 0.0, 90.0, (-175.0, 175.0)),
    (0.0, 0.0, 0.0, -90.0, (-120.0, 120.0)),
    (180.0, 200.0, 0.0, 0.0, (-400.0, 400.0)),
]
NJ = len(DH)
KINDS = ("theta", "d", "a", "alpha")
# the full parameter vector: theta, d, a, alpha per joint (rad, mm, mm, rad), then tool x, y, z
NAMES = [f"{k}{j + 1}" for j in range(NJ) for k in KINDS] + ["tool.x", "tool.y", "tool.z"]
ANGULAR = np.array([n.startswith(("theta", "alpha")) for n in NAMES])
LIMITS = np.radians(np.array([row[4] for row in DH]))
TRACKER = np.array([2500.0, 0.0, 0.0])


def nominal():
    x = []
    for theta, d, a, alpha, _ in DH:
        x += [np.radians(theta), d, a, np.radians(alpha)]
    return np.array(x + [0.0, 0.0, 0.0])


def random_poses(rng, n):
    return rng.uniform(LIMITS[:, 0], LIMITS[:, 1], size=(n, NJ))


def chain(x, q):
    """Walk the chain for every pose at once. Returns the tool points (N, 3) and, per frame
    0..6, the origins, z axes and x axes (each (N, 3)) plus the flange rotation (N, 3, 3)."""
    n = q.shape[0]
    rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    pos = np.zeros((n, 3))
    origins, zs, xs = [pos], [rot[:, :, 2]], [rot[:, :, 0]]
    for j in range(NJ):
        theta, d, a, alpha = x[4 * j : 4 * j + 4]
        ct, st = np.cos(q[:, j] + theta), np.sin(q[:, j] + theta)
        ca, sa = np.cos(alpha), np.sin(alpha)
        # Rz(theta) Tz(d) Tx(a) Rx(alpha): rotation and translation in the previous frame
        local = np.zeros((n, 3, 3))
        local[:, 0, 0], local[:, 0, 1], local[:, 0, 2] = ct, -st * ca, st * sa
        local[:, 1, 0], local[:, 1, 1], local[:, 1, 2] = st, ct * ca, -ct * sa
        local[:, 2, 1], local[:, 2, 2] = sa, ca
        step = np.stack([a * ct, a * st, np.full(n, d)], axis=1)
        pos = pos + (rot @ step[:, :, None])[:, :, 0]
        rot = rot @ local
        origins.append(pos)
        zs.append(rot[:, :, 2])
        xs.append(rot[:, :, 0])
    tool = pos + rot @ x[4 * NJ :]
    return tool, origins, zs, xs, rot


def tool_points(x, q):
    return chain(x, q)[0]


def cross(u, v):
    """Row-wise cross products of two (N, 3) arrays (np.cross's axis handling costs more than
    the arithmetic at this size)."""
    return np.stack(
        [
            u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        ],
        axis=1,
    )


def jacobian(x, q):
    """d(tool point)/d(parameters), (3N, 27), rows pose by pose (x, y, z)."""
    p, origins, zs, xs, rot = chain(x, q)
    n = q.shape[0]
    jac = np.empty((n, 3, len(NAMES)))
    for j in range(NJ):
        z_prev, o_prev = zs[j], origins[j]  # joint j+1 turns and slides along frame j's z
        x_next, o_next = xs[j + 1], origins[j + 1]  # a and alpha act along frame j+1's x
        jac[:, :, 4 * j + 0] = cross(z_prev, p - o_prev)
        jac[:, :, 4 * j + 1] = z_prev
        jac[:, :, 4 * j + 2] = x_next
        jac[:, :, 4 * j + 3] = cross(x_next, p - o_next)
    jac[:, :, 4 * NJ :] = rot  # the tool offset, in the flange frame
    return jac.reshape(3 * n, len(NAMES))


def identifiable(x, rng, poses=200, tol=1e-8):
    """Indices of the parameters kept in order: a column is kept when its part orthogonal to
    the columns kept before it is more than tol of its (unit) norm."""
    jac = jacobian(x, random_poses(rng, poses))
    norms = np.linalg.norm(jac, axis=0)
    basis = np.zeros((jac.shape[0], 0))
    kept = []
    for k in range(jac.shape[1]):
        if norms[k] <= 1e-12 * norms.max():
            continue
        c = jac[:, k] / norms[k]
        for _ in range(2):  # twice: Gram-Schmidt loses orthogonality once
            c = c - basis @ (basis.T @ c)
        if np.linalg.norm(c) > tol:
            kept.append(k)
            basis = np.column_stack([basis, c / np.linalg.norm(c)])
    return np.array(kept)


def measure(rng, points):
    sigma = (0.015 + 6e-6 * np.linalg.norm(points - TRACKER, axis=1)) / 2.0
    return points + rng.standard_normal(points.shape) * sigma[:, None]


def identify(x_nom, free, q, measured):
    """least_squares LM on the errors of the free parameters, from zero errors."""

    def full(dx):
        x = x_nom.copy()
        x[free] += dx
        return x

    def residual(dx):
        return (tool_points(full(dx), q) - measured).ravel()

    def jac(dx):
        return jacobian(full(dx), q)[:, free]

    return least_squares(residual, np.zeros(len(free)), jac=jac, method="lm", x_scale="jac")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("trials", nargs="?", type=int, default=100)
    ap.add_argument("--poses", type=int, default=50, help="calibration and validation poses")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    x_nom = nominal()
    free = identifiable(x_nom, np.random.default_rng(12345))
    errors = np.zeros(len(NAMES))
    errors[free] = np.where(ANGULAR[free], 0.05, 0.5)
    x_true = x_nom + errors

    fit_s, rms, nfev, njev, failures = 0.0, [], [], [], 0
    start = time.perf_counter()
    for k in range(args.trials):
        rng = np.random.default_rng(args.seed + k)
        q, q_val = random_poses(rng, args.poses), random_poses(rng, args.poses)
        measured = measure(rng, tool_points(x_true, q))
        t0 = time.perf_counter()
        r = identify(x_nom, free, q, measured)
        fit_s += time.perf_counter() - t0
        failures += r.status <= 0
        nfev.append(r.nfev)
        njev.append(r.njev)
        x = x_nom.copy()
        x[free] += r.x
        d = tool_points(x, q_val) - tool_points(x_true, q_val)
        rms.append(np.sqrt(np.mean(np.sum(d * d, axis=1))))
    total_s = time.perf_counter() - start

    n = args.trials
    print(f"scipy_lm_s_per_identification {fit_s / n:.6e}")
    print(f"scipy_total_s_per_trial {total_s / n:.6e}")
    print(f"scipy_val_rms_after_mm {np.mean(rms):.5f}")
    print(f"params {len(free)} {' '.join(NAMES[i] for i in free)}")
    print(f"evaluations_mean {np.mean(nfev):.1f} jacobians_mean {np.mean(njev):.1f}")
    print(f"failures {failures} of {n}")


if __name__ == "__main__":
    main()
