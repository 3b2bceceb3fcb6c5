"""The IK's default restart budget, measured on a corpus: for each robot, how many of N
random reachable targets (FK of random configurations) ``Robot.ik`` leaves unsolved with
50, 200 and 500 restarts, and what a target out of reach costs (every restart spent).

    python benchmarks/budget.py [--n 20000] [--json budget.json]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from machine import begin, write_json

import toolkit

ROBOTS = ("panda", "ur5", "ur10", "z1", "katana_6m90a", "katana_6m90b")
BUDGETS = (50, 200, 500)


def _robot(name: str) -> toolkit.Robot:
    return toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=20_000, help="reachable targets per robot")
    args, info = begin(parser)
    rows = {}
    for name in ROBOTS:
        robot = _robot(name)
        robot.ik(
            robot.fk(robot.joints.neutral()), method="numeric"
        )  # compiled before the clock starts
        T = robot.fk(robot.random_q(args.n, seed=5))
        far = np.eye(4)
        far[:3, 3] = [5.0, 0.0, 0.0]  # beyond every arm here
        row: dict[str, object] = {}
        for restarts in BUDGETS:
            unsolved = sum(not robot.ik(t, restarts=restarts, method="numeric").success for t in T)
            times = []
            for _ in range(20):
                start = time.perf_counter()
                robot.ik(far, restarts=restarts, method="numeric")
                times.append(time.perf_counter() - start)
            row[str(restarts)] = {
                "unsolved": unsolved,
                "unreachable_ms": 1e3 * statistics.median(times),
            }
            print(
                f"{name:14s} restarts {restarts:4d}: {unsolved:4d} of {args.n} unsolved; "
                f"a target out of reach {1e3 * statistics.median(times):.2f} ms"
            )
        rows[name] = row
    write_json(args.json, {"machine": info, "targets": args.n, "robots": rows})


if __name__ == "__main__":
    main()
