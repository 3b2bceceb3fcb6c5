"""Workspace-map throughput: the UR5 reachability map (5 cm voxels, 50 orientations) here,
then on a dask.distributed LocalCluster of 1 and of 2 workers (one thread each).

Prints wall times, IK solves per second and the 2-worker / 1-worker ratio, and the
expected time of a 1 cm map on N workers from the measured per-worker throughput.
Needs the maps extra (pip install ".[maps]"). Usage:

    python benchmarks/maps.py [--voxel 0.05] [--orientations 50] [--json out.json]
"""

from __future__ import annotations

import argparse

import numpy as np

import toolkit
from toolkit import maps

try:  # run as a script (python benchmarks/maps.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def _run(
    robot: toolkit.Robot,
    client: object,
    voxel: float,
    orientations: int,
    workers: int | None = None,
    collision_free: bool = False,
    ik_method: str = "numeric",
) -> dict:
    import time

    start = time.perf_counter()
    result = maps.reachability(
        robot, voxel=voxel, orientations=orientations, client=client, workers=workers,
        collision_free=collision_free, method=ik_method,
    )  # fmt: skip
    wall = time.perf_counter() - start
    solves = result.figures["solves"]
    return {
        "wall_s": wall,
        "solves": solves,
        "solves_per_s": solves / wall,
        "chunks": result.figures["chunks"],
        "voxels": int(result.index.size),
        "index_digest": float(np.nansum(result.index)),
    }


def _methods(voxel: float, orientations: int) -> dict:
    """The same UR5 map by the numeric budget and by every analytic branch, alternating."""
    robot = toolkit.load_example("ur5")
    for method in ("numeric", "auto"):  # load the compiled kernels
        maps.reachability(robot, voxel=0.5, orientations=2, method=method, collision_free=False)
    out: dict[str, list] = {"numeric": [], "auto": []}
    for method in ("numeric", "auto", "numeric", "auto"):
        run = _run(robot, None, voxel, orientations, ik_method=method)
        m = maps.reachability(robot, voxel=voxel, orientations=orientations,
                              collision_free=False, method=method)  # fmt: skip
        reached = m.index > 0
        run["voxels_reached"] = int(reached.sum())
        run["mean_index_reached"] = float(m.index[reached].mean())
        out[method].append(run)
        print(f"{method:8s} {run['wall_s']:5.1f} s, {run['voxels_reached']} voxels reached, "
              f"mean index over them {run['mean_index_reached']:.4f}")  # fmt: skip
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--voxel", type=float, default=0.05)
    parser.add_argument("--orientations", type=int, default=50)
    parser.add_argument(
        "--collisions",
        action="store_true",
        help="the maps' default, self-collision-free (default here: the arm alone in space, "
        "as in docs/maps.md; benchmarks/collision.py compares the two)",
    )
    parser.add_argument(
        "--methods",
        action="store_true",
        help="only compare the numeric budget with every analytic branch (method), "
        "alternating, twice each, embedded",
    )
    args, info = begin(parser)
    if args.methods:
        write_json(args.json, {**info, "methods": _methods(args.voxel, args.orientations)})
        return
    from distributed import Client, LocalCluster

    robot = toolkit.load_example("ur5")
    maps.reachability(robot, voxel=0.5, orientations=2)  # load the compiled kernels
    figures: dict[str, object] = {
        **info,
        "voxel_m": args.voxel,
        "orientations": args.orientations,
    }
    here = _run(robot, None, args.voxel, args.orientations, collision_free=args.collisions)
    figures["embedded"] = here
    print(
        f"embedded default (a local thread per core, no Dask): {here['wall_s']:.1f} s wall, "
        f"{here['solves']:,.0f} IK solves in {here['chunks']:.0f} chunks, "
        f"{here['solves_per_s']:,.0f} solves/s"
    )
    inside = _run(robot, None, args.voxel, args.orientations, 1, args.collisions)
    figures["in_process"] = inside
    print(
        f"one thread (workers=1, the compiled kernels over every core): "
        f"{inside['wall_s']:.1f} s wall, {inside['solves_per_s']:,.0f} solves/s"
    )
    for workers in (1, 2):
        with (
            LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):
            client.run(
                lambda: maps.reachability(toolkit.load_example("ur5"), voxel=0.5, orientations=2)
            )
            run = _run(robot, client, args.voxel, args.orientations, None, args.collisions)
        assert run["index_digest"] == here["index_digest"], "the cluster's map differs"
        figures[f"cluster_{workers}"] = run
        print(
            f"LocalCluster, {workers} worker(s) x 1 thread: {run['wall_s']:.1f} s wall, "
            f"{run['solves_per_s']:,.0f} solves/s (same map: yes)"
        )
    one, two = figures["cluster_1"], figures["cluster_2"]
    ratio = two["solves_per_s"] / one["solves_per_s"]  # type: ignore[index]
    figures["ratio_2_over_1"] = ratio
    print(f"2 workers / 1 worker: {ratio:.2f}x the solves/s")
    per_worker = one["solves_per_s"]  # type: ignore[index]
    fine = here["solves"] * (args.voxel / 0.01) ** 3
    print(f"a 1 cm map: about {fine:,.0f} IK solves; at {per_worker:,.0f} solves/s per worker:")
    for n in (1, 2, 8, 32, 128):
        print(f"  {n:4d} workers: {fine / (per_worker * n) / 60:8.1f} min")
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
