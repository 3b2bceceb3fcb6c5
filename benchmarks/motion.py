"""Time-optimal timing (``motion.time_optimal``, TOPP-RA through toppra) against the
profiles within the same limits: the Katana 6M180, random waypoint sets, the description's
velocity limits and 2 rad/s^2; durations relative to the quintic and trapezoidal profiles,
the seconds a solve takes, and the largest ratio of any joint's speed or acceleration to
its limit when sampled at 10 kHz (at most 1: held; near 1: used).

Then a UR5 path through 1,000 waypoints (``ik_path`` along a tool circle of radius 0.15 m
that rises and falls by 5 cm twice): the toolkit's call beside toppra's bare call on the
same spline and limits (its default grid, and a grid of 4,000 points and every knot), each
answer's duration, seconds, and largest ratio to a limit sampled at 1 kHz; and the
per-segment trapezoidal timing's duration on the same waypoints.

    python benchmarks/motion.py [--n 20] [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import toolkit
from toolkit import motion

try:  # run as a script (python benchmarks/motion.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=20, help="random waypoint sets")
    args, info = begin(parser)
    katana = toolkit.load("katana_6m180")
    vmax, amax = np.asarray(katana.model.velocityLimit), 2.0
    motion.time_optimal(katana, katana.random_q(3, seed=0), acceleration=amax)  # imports
    rows = []
    for seed in range(1, args.n + 1):
        W = katana.random_q(4, seed=seed)
        start = time.perf_counter()
        fast = motion.time_optimal(katana, W, acceleration=amax)
        took = time.perf_counter() - start
        t = np.linspace(0.0, fast.duration, int(fast.duration * 10_000) + 1)
        _, qd, qdd = fast.evaluate(t)
        peak = max(float((np.abs(qd) / vmax).max()), float((np.abs(qdd) / amax).max()))
        rows.append((fast.duration / motion.quintic(katana, W, acceleration=amax).duration,
                     fast.duration / motion.trapezoidal(katana, W, acceleration=amax).duration,
                     took, peak))  # fmt: skip
    r = np.array(rows)
    figures = {
        "sets": args.n,
        "vs_quintic_median": float(np.median(r[:, 0])),
        "vs_trapezoidal_median": float(np.median(r[:, 1])),
        "solve_s_median": float(np.median(r[:, 2])),
        "peak_ratio_max": float(r[:, 3].max()),
        "peak_ratio_min": float(r[:, 3].min()),
    }
    f = figures
    print(f"time-optimal / quintic {f['vs_quintic_median']:.2f}, / trapezoidal "
          f"{f['vs_trapezoidal_median']:.2f} (medians), solve {f['solve_s_median']:.3f} s, "
          f"peak speed or acceleration / limit {f['peak_ratio_min']:.4f}.."
          f"{f['peak_ratio_max']:.6f}")  # fmt: skip
    figures["ur5_1000_waypoints"] = long_path()
    write_json(args.json, {"machine": info, "figures": figures})


def _peak(evaluate, duration: float, v: np.ndarray, a: np.ndarray) -> float:
    """The largest ratio of a joint's speed or acceleration to its limit, sampled at 1 kHz."""
    t = np.append(np.arange(0.0, duration, 1e-3), duration)
    qd, qdd = evaluate(t)
    return max(float((np.abs(qd) / v).max()), float((np.abs(qdd) / a).max()))


def long_path(amax: float = 2.0) -> dict[str, float]:
    """The UR5 through 1,000 waypoints: ours, toppra's bare calls, the trapezoidal timing."""
    import toppra

    ur5 = toolkit.load_example("ur5")
    q0 = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.4])
    s = np.linspace(0.0, 1.0, 1000)
    targets = np.repeat(ur5.fk(q0)[None], len(s), axis=0)
    targets[:, 0, 3] += 0.15 * (np.cos(2 * np.pi * s) - 1.0)
    targets[:, 1, 3] += 0.15 * np.sin(2 * np.pi * s)
    targets[:, 2, 3] += 0.05 * np.sin(4 * np.pi * s)
    W = np.asarray(ur5.ik_path(targets, q0, method="numeric").q)
    v, a = np.asarray(ur5.model.velocityLimit), np.full(ur5.joints.nv, amax)
    motion.time_optimal(ur5, W[:20], acceleration=amax)  # imports
    start = time.perf_counter()
    ours = motion.time_optimal(ur5, W, acceleration=amax)
    took = time.perf_counter() - start
    peak = _peak(lambda t: ours.evaluate(t)[1:], ours.duration, v, a)
    f = {"toolkit_s": ours.duration, "toolkit_call_s": took, "toolkit_peak_ratio": peak}
    chord = np.linalg.norm(np.diff(W, axis=0), axis=1)
    knots = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    fine = np.union1d(np.linspace(0, 1, 4000), knots)
    for label, grid in (("toppra_default_grid", None), ("toppra_4000_grid", fine)):
        start = time.perf_counter()
        path = toppra.SplineInterpolator(knots, W, bc_type="clamped")
        kinds = toppra.constraint
        limits = [kinds.JointVelocityConstraint(np.stack([-v, v], axis=1)),
                  kinds.JointAccelerationConstraint(np.stack([-a, a], axis=1))]  # fmt: skip
        solver = toppra.algorithm.TOPPRA(limits, path, gridpoints=grid,
                                         parametrizer="ParametrizeConstAccel")  # fmt: skip
        answer = solver.compute_trajectory(0.0, 0.0)
        f[f"{label}_call_s"] = time.perf_counter() - start
        f[f"{label}_s"] = float(answer.duration)
        f[f"{label}_peak_ratio"] = _peak(lambda t, x=answer: (x(t, 1), x(t, 2)),
                                         float(answer.duration), v, a)  # fmt: skip
    f["trapezoidal_s"] = motion.trapezoidal(ur5, W, acceleration=amax).duration
    print(f"UR5, 1,000 waypoints: toolkit {f['toolkit_s']:.3f} s (call {f['toolkit_call_s']:.2f} s"
          f", peak {f['toolkit_peak_ratio']:.5f} of a limit at 1 kHz); toppra's bare call "
          f"{f['toppra_default_grid_s']:.3f} s (call {f['toppra_default_grid_call_s']:.3f} s, "
          f"peak {f['toppra_default_grid_peak_ratio']:.3f}), on 4,000 grid points "
          f"{f['toppra_4000_grid_s']:.3f} s (call {f['toppra_4000_grid_call_s']:.2f} s, peak "
          f"{f['toppra_4000_grid_peak_ratio']:.3f}); per-segment trapezoidal "
          f"{f['trapezoidal_s']:.1f} s ({f['toolkit_s'] / f['trapezoidal_s']:.3f}x)")  # fmt: skip
    return f


if __name__ == "__main__":
    main()
