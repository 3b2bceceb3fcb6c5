"""Backlash benchmark: configurations per second for torque + fixed point + FK.

100,000 random commands of the Katana 6M180 (payload 0.5 kg): the torque acting on
each joint, the fixed point theta = q + dtheta(M(theta)) and the tool position, on
the compiled engine (all cores) and (on a sample) one Pinocchio call at a time.
Prints its figures (and writes them with the machine, versions and commit to ``--json``);
nothing is asserted.

    python benchmarks/backlash.py [--n 100000] [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin

import toolkit
from toolkit import backlash as bl

try:  # run as a script (python benchmarks/backlash.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    args, info = begin(parser)
    robot = toolkit.load("katana_6m180")
    layer = bl.Backlash(robot, payload=0.5)
    q = robot.random_q(args.n, seed=0)

    layer.tips(layer.solve(q[:64]).theta)  # load the compiled kernels
    t0 = time.perf_counter()
    out = layer.solve(q)
    tips = layer.tips(out.theta)
    dt = time.perf_counter() - t0
    print(
        f"compiled engine: {args.n / dt:,.0f} configurations/s "
        f"({1e6 * dt / args.n:.2f} us each); fixed point: up to {out.iterations} iterations, "
        f"max residual {out.residual.max():.1e} rad, {out.in_gap.any(axis=1).mean():.2%} "
        "with a joint inside its gap"
    )
    t0 = time.perf_counter()
    for _ in range(5):
        layer.torques(q)
    grav = (time.perf_counter() - t0) / 5
    print(f"  one batch gravity evaluation: {args.n / grav:,.0f} configurations/s")

    sample = q[:2000]
    t0 = time.perf_counter()
    for row in sample:
        pin.computeGeneralizedGravity(layer.model, layer.data, row)
        pin.forwardKinematics(layer.model, layer.data, row)
    per_call = (time.perf_counter() - t0) / len(sample)
    print(f"one Pinocchio gravity + FK call from Python: {1e6 * per_call:.2f} us")
    single = np.empty(500)
    for i, row in enumerate(sample[:500]):
        t0 = time.perf_counter()
        layer.output_angles(row)
        single[i] = time.perf_counter() - t0
    print(
        f"output_angles of a single configuration: median {1e6 * np.median(single):.1f} us, "
        f"mean {1e6 * single.mean():.1f} us"
    )
    err = np.linalg.norm(tips - layer.tips(q), axis=1)
    print(f"tool error from backlash: mean {1e3 * err.mean():.2f} mm, max {1e3 * err.max():.2f} mm")
    figures = {
        **info,
        "commands": args.n,
        "compiled_per_s": args.n / dt,
        "max_iterations": out.iterations,
        "max_residual_rad": float(out.residual.max()),
        "in_gap_share": float(out.in_gap.any(axis=1).mean()),
        "gravity_batch_per_s": args.n / grav,
        "pinocchio_call_us": 1e6 * per_call,
        "single_median_us": 1e6 * float(np.median(single)),
        "single_mean_us": 1e6 * float(single.mean()),
    }
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
