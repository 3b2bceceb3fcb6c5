"""The toolkit's ``Robot.plan`` alone on every MotionBenchMaker Panda problem (the seven
scenarios of 100, as ``planning_mbm.py`` reads them), each with several seeds: how many it
solves, how long the slowest take (the issue's goal: every problem within 1 s), and how many
paths an independent check at 1 degree finds colliding. The peers' comparison is
``planning_mbm.py`` (their time on all 700 problems would be hours: OMPL's cage median is
seconds, pyroboplan's times out at 10 s).

    python benchmarks/planning_mbm_all.py mbm/problems [--per 100] [--seeds 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import contextlib
import math
import time
from pathlib import Path

import numpy as np

import toolkit

try:  # run as a script (python benchmarks/planning_mbm_all.py) or from the benchmarks folder
    from machine import begin, write_json
    from planning import dense
    from planning_mbm import FINGERS, SCENARIOS, load_problem, load_request, load_scene
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json
    from benchmarks.planning import dense
    from benchmarks.planning_mbm import (
        FINGERS,
        SCENARIOS,
        load_problem,
        load_request,
        load_scene,  # fmt: skip
    )

SECOND = 1.0
"""[s] The goal: every problem solved within it."""


def _scenario(panda: toolkit.Robot, folder: Path, per: int, seeds: int, limit: float) -> dict:
    """Every valid problem of one scenario planned with ``seeds`` seeds (problem k, seed s:
    k + 1000 s), each path re-checked at 1 degree on the exact shapes."""
    times: list[float] = []
    solved = colliding = invalid = over = 0
    worst = ("", 0.0)
    for k in range(1, per + 1):
        if not (folder / f"scene{k:04d}.yaml").exists():
            break
        problem = load_problem(folder, k, panda)
        if problem is None:
            invalid += 1
            continue
        scene, start, goal, checker = problem
        for s in range(seeds):
            t0 = time.perf_counter()
            r = panda.plan(start, goal, scene=scene, hold=list(FINGERS), seed=k + 1000 * s,
                           time_limit=limit)  # fmt: skip
            took = time.perf_counter() - t0
            times.append(took)
            over += took > SECOND or not r.success
            if took > worst[1]:
                worst = (f"problem {k}, seed {k + 1000 * s}", took)
            if r.success:
                solved += 1
                colliding += any(checker.first_collision(q) is not None
                                 for q in dense(r.path, math.radians(1.0)))  # fmt: skip
    t = np.array(times) * 1e3 if times else np.array([np.nan])
    return {"valid_problems": (len(times) // max(seeds, 1)), "invalid_problems": invalid,
            "plans": len(times), "solved": solved, "median_ms": float(np.median(t)),
            "p95_ms": float(np.percentile(t, 95)), "max_ms": float(t.max()),
            "slowest": worst[0], "over_1s_or_unsolved": over,
            "paths_colliding_at_1deg": colliding}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problems", help="the folder of MBM's *_panda problem folders")
    parser.add_argument("--per", type=int, default=100, help="problems per scenario")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per problem")
    parser.add_argument("--limit", type=float, default=10.0, help="seconds per attempt")
    parser.add_argument("--scenarios", nargs="*", default=list(SCENARIOS))
    args, info = begin(parser)
    panda = toolkit.load_example("panda")
    toolkit.warmup()  # every kernel compiled or loaded before any clock (an escape's exact
    # checks compiled inside a timed plan took 2 s once the cache was fresh)
    first = Path(args.problems) / f"{args.scenarios[0]}_panda"  # warm: kernels loaded, untimed
    start, goal = load_request(first / "request0001.yaml", panda)
    with contextlib.suppress(toolkit.errors.ToolkitError):
        panda.plan(start, goal, scene=load_scene(first / "scene0001.yaml"), hold=list(FINGERS))
    figures: dict[str, dict] = {}
    for scenario in args.scenarios:
        f = _scenario(panda, Path(args.problems) / f"{scenario}_panda", args.per, args.seeds,
                      args.limit)  # fmt: skip
        figures[scenario] = f
        print(f"{scenario:17s} {f['solved']}/{f['plans']} plans solved ({f['valid_problems']} "
              f"valid problems x {args.seeds} seeds, {f['invalid_problems']} invalid here), "
              f"median {f['median_ms']:.1f} ms, p95 {f['p95_ms']:.0f} ms, max "
              f"{f['max_ms']:.0f} ms ({f['slowest']}), over 1 s or unsolved "
              f"{f['over_1s_or_unsolved']}, {f['paths_colliding_at_1deg']} paths colliding at "
              "1 deg")  # fmt: skip
    write_json(args.json, {"machine": info, "figures": figures})


if __name__ == "__main__":
    main()
