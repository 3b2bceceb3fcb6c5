"""Time-optimal timing (``motion.time_optimal``, TOPP-RA through toppra) against the
profiles within the same limits: the Katana 6M180, random waypoint sets, the description's
velocity limits and 2 rad/s^2; durations relative to the quintic and trapezoidal profiles,
the seconds a solve takes, and the largest ratio of any joint's speed or acceleration to
its limit when sampled at 10 kHz (at most 1: held; near 1: used).

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
    write_json(args.json, {"machine": info, "figures": figures})


if __name__ == "__main__":
    main()
