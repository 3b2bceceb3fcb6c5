"""Collision-free planning figures (``Robot.plan``: RRT-Connect in joint values, edges
checked at 1 degree on the exact shapes), on problems whose straight line collides:

* the UR5 around a wall (one start and goal, many seeds);
* the Panda (example-robot-data meshes, its SRDF) in a cell with a table and a box: random
  collision-free start and goal pairs.

Every returned path is checked again here at 0.25 degree, configuration by configuration
(coal on every pair, without the batch's pre-filter): the count of colliding paths is a
figure, not an assertion. Prints success, median and 95th percentile times, checks and
path lengths; peers (OMPL, pyroboplan, VAMP) are not run by this script yet.

    python benchmarks/planning.py [--n 20] [--json out.json]
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

import toolkit
from toolkit import Scene

try:  # run as a script (python benchmarks/planning.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def dense(path: np.ndarray, step: float) -> np.ndarray:
    """Every configuration of a path's straight segments, joints at most ``step`` apart."""
    out = [path[0]]
    for p, q in itertools.pairwise(path):
        k = max(1, math.ceil(float(np.abs(q - p).max()) / step))
        out += [p + (q - p) * t for t in np.arange(1, k + 1) / k]
    return np.array(out)


def _timed(
    robot: toolkit.Robot, a: np.ndarray, b: np.ndarray, scene: Scene, seed: int, **options: float
) -> tuple[toolkit.planning.PlanResult, float]:  # fmt: skip
    """One whole ``Robot.plan`` call (its checks of the ends included) and its seconds."""
    t0 = time.perf_counter()
    result = robot.plan(a, b, scene=scene, seed=seed, **options)
    return result, time.perf_counter() - t0


def _run(robot: toolkit.Robot, scene: Scene, pairs: list, time_limit: float) -> dict:
    times, checks, lengths, colliding, solved, covers, swept, escaped = [], [], [], 0, 0, 0, 0, 0
    for seed, (a, b) in enumerate(pairs):
        r, took = _timed(robot, a, b, scene, seed, time_limit=time_limit)
        times.append(took)
        checks.append(r.checks)
        if r.success:
            solved += 1
            covers += r.search == "covers"
            swept += r.swept
            escaped += r.swept and r.escapes > 0
            lengths.append(r.length)
            D = dense(r.path, math.radians(0.25))
            colliding += any(robot.collision_checker(scene).collisions(q) for q in D)
    t = np.array(times) * 1e3
    return {
        "problems": len(pairs), "solved": solved, "median_ms": float(np.median(t)),
        "p95_ms": float(np.percentile(t, 95)), "median_checks": float(np.median(checks)),
        "median_length_rad": float(np.median(lengths)) if lengths else None,
        "paths_colliding_at_0.25deg": colliding, "found_on_covers": covers, "swept": swept,
        "swept_but_escapes": escaped,
    }  # fmt: skip


def _pairs(robot: toolkit.Robot, scene: Scene, n: int, seed: int) -> list:
    """n (start, goal) pairs, both free, whose straight line collides."""
    rng, out = np.random.default_rng(seed), []
    while len(out) < n:
        Q = robot.random_q(64, seed=rng)
        Q = Q[~np.asarray(robot.in_collision(Q, scene), dtype=bool)]
        for a, b in zip(Q[0::2], Q[1::2], strict=False):
            if len(out) < n and np.asarray(robot.in_collision(np.linspace(a, b, 40), scene)).any():
                out.append((a, b))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=20, help="problems per robot")
    args, info = begin(parser)
    ur5 = toolkit.load_example("ur5")
    wall = Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4]).add_floor(-0.01)
    a = np.array([-1.4, -1.0, 1.5, -1.9, -1.57, 0.0])
    b = np.array([1.4, -1.0, 1.5, -1.9, -1.57, 0.0])
    ur5.plan(a, b, scene=wall)  # compile and build the checker once
    panda = toolkit.load_example("panda")
    cell = (Scene().add_floor(0.0).add_box("table", [1.0, 1.2, 0.04], [0.65, 0.0, 0.10])
            .add_box("obstacle", [0.15, 0.15, 0.3], [0.45, 0.25, 0.27]))  # fmt: skip
    figures = {
        "ur5 around a wall": _run(ur5, wall, [(a, b)] * args.n, 10.0),
        "panda in a cell": _run(panda, cell, _pairs(panda, cell, args.n, 7), 10.0),
    }
    for name, f in figures.items():
        print(f"{name}: {f['solved']}/{f['problems']} solved, median {f['median_ms']:.0f} ms "
              f"(p95 {f['p95_ms']:.0f} ms), {f['median_checks']:.0f} checks, "
              f"{f['paths_colliding_at_0.25deg']} paths colliding at 0.25 deg, "
              f"{f['found_on_covers']} found on the covers, "
              f"{f['swept']} certified over their whole motion ({f['swept_but_escapes']} with "
              "an escape's segment certified on the exact shapes)")  # fmt: skip
    figures["plan_many"] = _many(panda, cell, _pairs(panda, cell, 24, 11))
    figures["sphere_covers"] = _covers(panda, cell, _pairs(panda, cell, args.n, 7))
    figures["compiled_search"] = _compiled(panda, cell, _pairs(panda, cell, args.n, 7))
    write_json(args.json, {"machine": info, "figures": figures})


def _many(robot: toolkit.Robot, scene: Scene, pairs: list) -> dict:
    """``planning.plan_many`` of the same problems on 1 worker and on every core, in forked
    processes and in threads, alternating, the median of 3 each; the answers compared."""
    import os
    import statistics
    import time

    from toolkit import planning

    cores = os.cpu_count() or 1
    runs = {"one": (1, "fork"), "fork": (cores, "fork"), "threads": (cores, "threads")}
    times: dict[str, list[float]] = {name: [] for name in runs}
    answers = {}
    for _ in range(3):
        for name, (w, pool) in runs.items():
            t0 = time.perf_counter()
            answers[name] = planning.plan_many(robot, pairs, scene=scene, workers=w, pool=pool,
                                               time_limit=10.0, hold=None)  # fmt: skip
            times[name].append(time.perf_counter() - t0)
    same = all(np.array_equal(a.path, b.path) and np.array_equal(a.path, c.path)
               for a, b, c in zip(answers["one"], answers["fork"], answers["threads"],
                                  strict=True))  # fmt: skip
    one, fork, threads = (statistics.median(times[k]) for k in runs)
    print(f"plan_many, {len(pairs)} Panda problems: {one:.2f} s on 1 worker, on {cores}: "
          f"{fork:.2f} s forked ({one / fork:.2f}x), {threads:.2f} s in threads "
          f"({one / threads:.2f}x); the same plans: {same}")  # fmt: skip
    return {"problems": len(pairs), "one_worker_s": one, "workers": cores, "all_s": fork,
            "speedup": one / fork, "threads_s": threads, "threads_speedup": one / threads,
            "same_plans": same}  # fmt: skip


def _covers(robot: toolkit.Robot, scene: Scene, pairs: list, rounds: int = 3) -> dict:
    """The pre-filter's sphere covers on and off (``Bounds.covers`` emptied), interleaved:
    per round the median plan time of the same problems, and the configurations coal
    checked."""
    from toolkit.collision import bounds
    from toolkit.robot import plans

    real = bounds.Bounds.covers

    def empty(self: bounds.Bounds) -> tuple[np.ndarray, ...]:
        n = len(self.row)
        return np.zeros(n + 1, np.int64), np.zeros((0, 4)), np.zeros((n, 4))

    out: dict[str, list[float]] = {"with_ms": [], "without_ms": []}
    try:
        for _ in range(rounds):
            for key, covers in (("without_ms", empty), ("with_ms", real)):
                bounds.Bounds.covers = covers  # type: ignore[method-assign]
                plans._TESTS.clear()  # the covers' test is kept per checker: made anew
                times = [_timed(robot, a, b, scene, i)[1] for i, (a, b) in enumerate(pairs)]
                out[key].append(1e3 * float(np.median(times)))
    finally:
        bounds.Bounds.covers = real  # type: ignore[method-assign]
    ratio = float(np.median(np.array(out["without_ms"]) / np.array(out["with_ms"])))
    print(
        f"sphere covers in the pre-filter, Panda in a cell: median {np.median(out['with_ms']):.0f}"
        f" ms with, {np.median(out['without_ms']):.0f} ms without ({ratio:.2f}x; per round "
        f"{[round(x) for x in out['with_ms']]} against {[round(x) for x in out['without_ms']]})"
    )
    return {**out, "ratio": ratio}


def _compiled(robot: toolkit.Robot, scene: Scene, pairs: list, rounds: int = 3) -> dict:
    """The compiled search on the covers on and off (``certain_test`` answering None: the
    search on the exact checker only), interleaved: per round the median plan time."""
    from toolkit.robot import plans

    real = plans.certain_test
    out: dict[str, list[float]] = {"with_ms": [], "without_ms": []}
    try:
        for _ in range(rounds):
            for key, test in (("without_ms", lambda *_: None), ("with_ms", real)):
                plans.certain_test = test  # type: ignore[assignment]
                times = [_timed(robot, a, b, scene, i)[1] for i, (a, b) in enumerate(pairs)]
                out[key].append(1e3 * float(np.median(times)))
    finally:
        plans.certain_test = real
    ratio = float(np.median(np.array(out["without_ms"]) / np.array(out["with_ms"])))
    print(
        f"compiled search on the covers, Panda in a cell: median {np.median(out['with_ms']):.1f}"
        f" ms with, {np.median(out['without_ms']):.1f} ms without ({ratio:.1f}x)"
    )
    return {**out, "ratio": ratio}


if __name__ == "__main__":
    main()
