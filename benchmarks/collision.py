"""Collision figures against the collision issue's goals, on this machine's cores:

* exact self-collision checks of the Panda (example-robot-data meshes, its SRDF), batched
  (goal >= 50,000 configurations/s on 2 cores), and the share the compiled pre-filter
  decides;
* collision-free IK, Panda above a table with a box obstacle, targets from collision-free
  configurations (goals >= 99.5 % solved, >= 10,000 solves/s with ``ik_batch``, and 0
  solutions called free that a check on a separately built model finds colliding);
* the UR5's reachability map on a table with self-collision against the same map without
  collisions, 5 cm voxels, 50 orientations (goal: <= 2x the time).

Prints its figures (best of three for the rates); nothing is asserted.

    python benchmarks/collision.py [--n 20000] [--map-voxel 0.05] [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import toolkit
from toolkit import Scene
from toolkit.robot import checker_for

try:  # run as a script (python benchmarks/collision.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def _cell() -> Scene:
    return (
        Scene()
        .add_floor(0.0)
        .add_box("table", [1.0, 1.2, 0.04], [0.65, 0.0, 0.10])  # clear of the base (0.15 m)
        .add_box("obstacle", [0.15, 0.15, 0.3], [0.45, 0.25, 0.27])
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=20_000)
    parser.add_argument("--map-voxel", type=float, default=0.05, help="[m]; 0 skips the map")
    parser.add_argument("--map-orientations", type=int, default=50)
    args, info = begin(parser)
    panda = toolkit.load_example("panda")
    Q = panda.random_q(args.n, seed=1)
    panda.in_collision(Q[:100])  # build the checker and its pool
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        flags = panda.in_collision(Q)
        times.append(time.perf_counter() - t0)
    rate = args.n / min(times)
    checker = checker_for(panda, None)
    state = checker.bounds.decide(Q) if checker.bounds is not None else np.zeros(len(Q))
    decided = float(np.mean(state > 0))
    t0 = time.perf_counter()
    checker._exact_many(Q)  # coal alone, every configuration
    coal_rate = args.n / (time.perf_counter() - t0)
    print(
        f"Panda self-collision, {args.n:,} configurations: {rate:,.0f} configurations/s "
        f"({flags.mean():.1%} in collision; exact; the compiled pre-filter decided "
        f"{decided:.1%} of them ({np.mean(state == 1):.1%} free, {np.mean(state == 2):.1%} "
        f"colliding), coal the rest; coal alone on all: {coal_rate:,.0f}/s) "
        "(goal >= 50,000/s)"
    )
    cell = _cell()
    pool = panda.random_q(4 * args.n // 10, seed=2)
    free = pool[~panda.in_collision(pool, cell)][: args.n // 10]
    targets = panda.fk(free)
    panda.ik_batch(targets[:100], scene=cell)  # load
    t0 = time.perf_counter()
    res = panda.ik_batch(targets, scene=cell, seed=3)
    dt = time.perf_counter() - t0
    fresh = toolkit.load_example("panda")  # a separately built model and checker
    called_free = res.q[res.success]
    false_free = int(fresh.in_collision(called_free, cell).sum()) if len(called_free) else 0
    print(
        f"collision-free ik_batch, {len(targets):,} targets: {res.success.mean():.2%} solved, "
        f"{len(targets) / dt:,.0f} solves/s, {false_free} called free but colliding "
        "(goals >= 99.5 %, >= 10,000/s, 0)"
    )
    figures = {
        **info,
        "self_collision_per_s": rate,
        "prefilter_decided": decided,
        "coal_alone_per_s": coal_rate,
        "collision_fraction": float(flags.mean()),
        "ik_batch_free_success": float(res.success.mean()),
        "ik_batch_free_per_s": len(targets) / dt,
        "false_free": false_free,
    }
    if args.map_voxel > 0:
        figures.update(_map_ratio(args.map_voxel, args.map_orientations))
    write_json(args.json, figures)


def _map_ratio(voxel: float, orientations: int) -> dict[str, float]:
    """The UR5 on a table: its map with self-collision and the table, and without."""
    from toolkit import maps

    ur5 = toolkit.load_example("ur5")
    table = Scene().add_box("table", [1.6, 1.6, 0.04], [0.0, 0.0, -0.021], support=True)
    kwargs = {"voxel": voxel, "orientations": orientations}
    maps.reachability(ur5, voxel=0.3, orientations=2, scene=table)  # compile, build checkers
    t0 = time.perf_counter()
    bare = maps.reachability(ur5, collision_free=False, **kwargs)
    t_bare = time.perf_counter() - t0
    t0 = time.perf_counter()
    safe = maps.reachability(ur5, scene=table, **kwargs)
    t_safe = time.perf_counter() - t0
    reached_bare, reached_safe = int((bare.index > 0).sum()), int((safe.index > 0).sum())
    print(
        f"UR5 map, {voxel * 100:g} cm voxels, {orientations} orientations, "
        f"{bare.index.size:,} voxels: without collisions {t_bare:.1f} s ({reached_bare:,} "
        f"reached), with self-collision and a table {t_safe:.1f} s ({reached_safe:,} "
        f"reached): {t_safe / t_bare:.2f}x (goal <= 2x)"
    )
    return {
        "map_voxels": float(bare.index.size),
        "map_seconds_free_space": t_bare,
        "map_seconds_collision_free": t_safe,
        "map_time_ratio": t_safe / t_bare,
        "map_reached_free_space": float(reached_bare),
        "map_reached_collision_free": float(reached_safe),
    }


if __name__ == "__main__":
    main()
