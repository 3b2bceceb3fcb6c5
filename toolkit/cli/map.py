"""``toolkit map``: a workspace map of a robot (:mod:`toolkit.maps`) from the command line,
here or on a Dask scheduler, into a Zarr store and a PNG of its slices."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..errors import InvalidParameterError
from .inputs import SCENE_HELP, robot_from_args, scene_of
from .inputs import add_model_arguments as _add_set

__all__ = ["add_map", "writable_png"]


def _client(address: str | None) -> Any:
    if address is None:
        return None
    try:
        from distributed import Client
    except ImportError as exc:
        raise InvalidParameterError(
            "--scheduler needs dask.distributed: pip install 'manipulator-toolkit[maps]'"
        ) from exc
    try:
        return Client(address, timeout=10)
    except Exception as exc:  # distributed raises many kinds for a bad or silent address
        raise InvalidParameterError(
            f"no Dask scheduler answers at {address!r} ({type(exc).__name__}: {exc}); give "
            "--scheduler tcp://HOST:PORT of a running dask scheduler"
        ) from None


def writable_png(path: str | None) -> Path | None:
    """The --png file, checked before the map is computed (not after minutes of work)."""
    if path is None:
        return None
    out = Path(path)
    if out.is_dir() or not out.parent.is_dir():
        raise InvalidParameterError(f"--png {path!r}: not a file in an existing folder")
    existed = out.exists()
    try:
        with open(out, "ab"):
            pass
    except OSError as exc:
        raise InvalidParameterError(f"--png {path!r} cannot be written: {exc.strerror}") from None
    if not existed:
        out.unlink()
    return out


def _cmd_map(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import maps

    robot = robot_from_args(args)
    png = writable_png(args.png)
    orientations = args.orientations  # 0 is refused by the map
    client = _client(args.scheduler)
    common = {
        "voxel": args.voxel, "store": args.store, "client": client, "resume": args.resume,
        "seed": args.seed, "progress": not args.quiet, "position_only": args.position_only,
        "mask": args.mask, "workers": args.workers, "collision_free": not args.no_collisions,
        "scene": scene_of(robot, args.scene),
    }  # fmt: skip
    try:
        if args.kind == "reach":
            result: Any = maps.reachability(robot, orientations=orientations, **common)
            reached = result.index > 0
            print(
                f"{robot.name}: {result.index.size:,} voxels of {args.voxel:g} m, "
                f"{int(reached.sum()):,} reached; mean index over them "
                f"{result.index[reached].mean() if reached.any() else 0:.3f}"
            )
        else:
            from ..papers.backlash import Backlash

            layer = Backlash(robot, delta=args.delta, payload=0.0)
            result = maps.backlash_accuracy(
                layer, orientations=orientations, payloads=args.payload,
                k_h=None if args.k_h is None else list(args.k_h), compensate=args.compensate,
                **common,
            )  # fmt: skip
            for i, payload in enumerate(result.payloads):
                for j, k_h in enumerate(result.k_h):
                    print(
                        f"{robot.name}, payload {payload:g} kg, k_H {k_h[0]:g}: tool position "
                        f"error from backlash, mean {1e3 * np.nanmean(result.mean[i, j]):.2f} mm, "
                        f"worst voxel p95 {1e3 * np.nanmax(result.p95[i, j]):.2f} mm"
                    )
                    if result.compensated_mean is not None:
                        print(
                            f"  after compensation: mean "
                            f"{1e3 * np.nanmean(result.compensated_mean[i, j]):.3g} mm, worst "
                            f"voxel max {1e3 * np.nanmax(result.compensated_max[i, j]):.3g} mm"
                        )
        figures = result.figures
        rate = figures["solves"] / figures["seconds"] if figures["seconds"] > 0 else 0.0
        print(f"{figures['chunks']:.0f} chunks, {figures['solves']:,.0f} IK solves, "
              f"{figures['seconds']:.1f} s ({rate:,.0f} solves/s)")  # fmt: skip
        if png is not None:
            _map_png(result, png)
    except KeyboardInterrupt:
        kept = f"; the finished chunks are in {args.store}: add --resume" if args.store else ""
        print(f"\ntoolkit: map interrupted{kept}", file=sys.stderr)
        return 130
    finally:
        if client is not None:
            client.close()
    return 0


def _map_png(result: Any, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from ..maps import draw_slices

    axes = draw_slices(result)
    axes[0].figure.savefig(path, dpi=100)
    print(f"wrote {path}")


def _common(p: argparse.ArgumentParser) -> None:
    """The options both maps take."""
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("--voxel", type=float, default=0.05, help="voxel edge [m] (default 0.05)")
    p.add_argument("--position-only", action="store_true", help="positions only")
    p.add_argument("--mask", nargs=6, type=float, metavar="W", help="IK weights, as for ik")
    p.add_argument("--store", help="a Zarr folder: results are written chunk by chunk")
    p.add_argument("--resume", action="store_true", help="finish the map in --store")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="a dask.distributed cluster")
    p.add_argument("--workers", type=int, help="local threads (default: one per core)")
    p.add_argument("--seed", type=int, default=0, help="seed of the IK restarts")
    p.add_argument("--png", help="write the slices (XZ through the base axis, XY) here")
    p.add_argument("--scene", metavar="FILE", help=SCENE_HELP)
    p.add_argument(
        "--no-collisions", action="store_true", help="the arm alone in space: no collision checks"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    _add_set(p)


def add_map(sub: Any) -> None:
    """The ``map`` subcommand and its two kinds, ``map reach`` and ``map backlash``."""
    p = sub.add_parser(
        "map", help="reachability or backlash-accuracy map of the workspace",
        description="A workspace map into a Zarr store and a PNG: 'toolkit map reach "
        "--help' or 'toolkit map backlash --help' for each kind's options.",
    )  # fmt: skip
    kinds = p.add_subparsers(dest="kind", required=True, metavar="KIND")
    texts = {
        "reach": ("reachability: the fraction of tool orientations IK reaches per voxel",
                  "Reachability map: per voxel, the fraction of --orientations tool "
                  "orientations that the IK reaches (free of collision unless "
                  "--no-collisions).", 50),
        "backlash": ("[P1]'s backlash tool error per voxel, per payload and k_H",
                     "Backlash-accuracy map ([P1]): per voxel, the tool position error "
                     "that joint backlash causes, for each payload and k_H.", 20),
    }  # fmt: skip
    parsers = {}
    for kind, (short, long, orientations) in texts.items():
        sub_p = parsers[kind] = kinds.add_parser(kind, help=short, description=long)
        sub_p.add_argument("--orientations", type=int, default=orientations,
                           help=f"tool orientations per voxel ({orientations})")  # fmt: skip
    reach, back = parsers["reach"], parsers["backlash"]
    _common(reach)
    back.add_argument("--payload", nargs="+", type=float, default=[0.0, 0.5], help="[kg]")
    back.add_argument("--k-h", nargs="+", type=float, help="k_H values (default: the layer's)")
    back.add_argument("--delta", type=float, default=0.035, help="backlash gap [rad]")
    back.add_argument("--compensate", action="store_true", help="also the error after compensation")
    _common(back)
    for kind in (reach, back):
        kind.set_defaults(func=_cmd_map)
