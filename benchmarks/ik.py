"""IK benchmark following the TRAC-IK protocol; prints its figures (never asserts times).

For each robot: N random configurations within the limits -> FK -> target pose; each
target is solved from the mid-range configuration with a 5 ms budget and a 1e-5
tolerance on position [m] and orientation [rad]. Prints success rate, mean and median
time per solve. If roboticstoolbox-python is installed, its ik_LM runs on the same
targets. Then the closed-form solvers' time per target, single and batched.

    python benchmarks/ik.py [--n 10000]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import toolkit
from toolkit import arm5dof, katana


def numeric(name: str, n: int, budget: float, tol: float) -> dict:
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    targets = [robot.fk(q) for q in robot.random_q(n, seed=2024)]
    times, ok = np.empty(n), 0
    for i, T in enumerate(targets):
        t0 = time.perf_counter()
        res = robot.ik(T, tol=tol, restarts=10_000, timeout=budget, seed=i)
        times[i] = time.perf_counter() - t0
        ok += res.success
    print(
        f"{name:<14} success {100 * ok / n:6.2f} %   mean {1e3 * times.mean():.3f} ms   "
        f"median {1e3 * np.median(times):.3f} ms   ({n} targets)"
    )
    rtb_figures = robotics_toolbox(robot, targets, tol)
    if rtb_figures is not None:
        print(
            f"  roboticstoolbox ik_LM: success {rtb_figures['success_percent']:6.2f} %   "
            f"mean {rtb_figures['mean_ms']:.3f} ms   median {rtb_figures['median_ms']:.3f} ms"
            f"   -> ours/theirs median {np.median(times) * 1e3 / rtb_figures['median_ms']:.2f}"
        )
    return {
        "robot": name,
        "targets": n,
        "success_percent": 100 * ok / n,
        "mean_ms": 1e3 * float(times.mean()),
        "median_ms": 1e3 * float(np.median(times)),
        # the distribution of solve times, as percentiles 0, 1, ..., 100
        "percentiles_ms": np.percentile(1e3 * times, np.arange(101)).round(4).tolist(),
        "roboticstoolbox": rtb_figures,
    }


def robotics_toolbox(robot, targets, tol: float) -> dict | None:
    """The same targets through roboticstoolbox-python's C++ ik_LM, if it is installed.

    Its robot is read from the same URDF; success is judged by the same criterion
    (position and orientation errors <= tol, joints within limits, recomputed by our FK).
    """
    try:
        import roboticstoolbox as rtb
        import xacrodoc.packages
    except ImportError:
        return None
    from toolkit.loaders import example_robot_data_dir

    xacrodoc.packages.update_package_cache(
        {"example-robot-data": str(example_robot_data_dir().parent)}
    )
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        other = rtb.Robot.URDF(str(robot.urdf_path))
    names = [link.name for link in other.links]
    end = robot.tip if robot.tip in names else None
    if end is None or other.n != robot.nq:
        print(f"  (roboticstoolbox: cannot map {robot.name}'s tip or joints; skipped)")
        return None
    times, ok = np.empty(len(targets)), 0
    for i, T in enumerate(targets):
        t0 = time.perf_counter()
        # ik_LM stops on E = e^T e / 2 < its tol: tol^2 / 4 keeps both norms below tol
        sol = other.ik_LM(T, end=end, tol=tol * tol / 4, ilimit=30, slimit=100, joint_limits=True)
        times[i] = time.perf_counter() - t0
        q = robot.neutral()
        q[: len(sol.q)] = sol.q  # the chain to the tip comes first (Panda: not the fingers)
        q = np.clip(q, robot.lower, robot.upper) if len(sol.q) < robot.nq else q
        reached = robot.fk(q)
        pos = np.linalg.norm(reached[:3, 3] - T[:3, 3])
        rot = np.linalg.norm(pin.log3(reached[:3, :3].T @ T[:3, :3]))
        ok += bool(pos <= tol and rot <= tol and robot.within_limits(q, tol=1e-9))
    n = len(targets)
    return {
        "success_percent": 100 * ok / n,
        "mean_ms": 1e3 * float(times.mean()),
        "median_ms": 1e3 * float(np.median(times)),
    }


def closed_form(n: int) -> dict:
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, size=(n, 5))
    P = arm5dof.forward(q)
    phi = rng.uniform(-1, 1, size=n)
    t0 = time.perf_counter()
    for i in range(min(n, 20_000)):
        arm5dof.geometric_ik_batch(P[i : i + 1], phi[i : i + 1])
    single = (time.perf_counter() - t0) / min(n, 20_000)
    t0 = time.perf_counter()
    for i in range(min(n, 5_000)):
        arm5dof.geometric_ik(P[i], phi[i])
    listed = (time.perf_counter() - t0) / min(n, 5_000)
    big = 1_000_000
    Pb = np.repeat(P, big // n + 1, axis=0)[:big]
    phib = np.resize(phi, big)
    t0 = time.perf_counter()
    arm5dof.geometric_ik_batch(Pb, phib)
    batched = time.perf_counter() - t0
    t0 = time.perf_counter()
    for i in range(min(n, 5_000)):
        katana.closed_form_ik(P[i] / 100, phi[i])
    kat = (time.perf_counter() - t0) / min(n, 5_000)
    print(f"geometric IK (paper 2), batch of 1:        {1e6 * single:8.2f} us per target")
    print(f"geometric_ik (merged, filtered list):      {1e6 * listed:8.2f} us per target")
    print(f"geometric IK batched, {big} targets:  {big / batched:12.0f} targets/s")
    print(f"katana.closed_form_ik (6M180, limits):     {1e6 * kat:8.2f} us per target")
    return {
        "geometric_ik_us": 1e6 * listed,
        "katana_closed_form_ik_us": 1e6 * kat,
        "batched_targets_per_s": big / batched,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000, help="targets per robot")
    parser.add_argument("--budget", type=float, default=0.005, help="seconds per solve")
    parser.add_argument("--tol", type=float, default=1e-5)
    parser.add_argument(
        "--json", help="also write the figures here (toolkit report shows benchmarks/ik.json)"
    )
    args = parser.parse_args()
    print(f"numeric IK: {args.n} targets, budget {1e3 * args.budget:g} ms, tol {args.tol:g}")
    results = [
        numeric(name, args.n, args.budget, args.tol) for name in ("katana_6m90a", "ur5", "panda")
    ]
    closed = closed_form(args.n)
    if args.json:
        payload = {
            "date": time.strftime("%Y-%m-%d"),
            "budget_ms": 1e3 * args.budget,
            "tol": args.tol,
            "numeric": results,
            "closed_form": closed,
        }
        Path(args.json).write_text(json.dumps(payload), encoding="utf-8")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
