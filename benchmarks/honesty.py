"""IK honesty at scale: 100,000 queries, counting successes an independent check refutes.

Every catalogue model and UR5/Panda are audited by ``tests/helpers.py``'s ``audit_ik``
(half reachable poses, a quarter reachable positions, a quarter far out of reach;
yourdfpy recomputes each claimed success from the URDF file, sharing no code with the
solvers). Prints the counts; the
test suite runs the same audit at CI size (``tests/ik/test_honesty.py``).

    python benchmarks/honesty.py [--n 100000]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from helpers import audit_ik

import toolkit


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000, help="queries in all")
    args = parser.parse_args()
    names = [*toolkit.available_models(), "ur5", "panda"]
    per_robot = max(1, args.n // len(names))
    total_false = total = 0
    for name in names:
        models = toolkit.available_models()
        robot = toolkit.load(name) if name in models else toolkit.load_example(name)
        start = time.perf_counter()
        result = audit_ik(robot, n=per_robot, seed=7)
        total += result["queries"]
        total_false += result["false_successes"]
        print(
            f"{name:<16} {result['queries']:>6} queries  {result['successes']:>6} successes  "
            f"{result['false_successes']} false  worst claimed error "
            f"{result['worst_claimed_error']:.2e}  ({time.perf_counter() - start:.1f} s)",
            flush=True,
        )
    print(f"all: {total} queries, {total_false} false successes")


if __name__ == "__main__":
    main()
