"""``toolkit place``: where to put a robot's base so that its tool reaches the tasks of a CSV
file (:func:`toolkit.maps.placement`), with a PNG of the region's heat map.

The CSV file has a header row: ``x``, ``y``, ``z`` the tool position [m] in the world and,
for full poses, ``roll``, ``pitch``, ``yaw`` [rad] its orientation (fixed axes X, Y, Z, as
a URDF ``rpy``). Without the angle columns the tasks are positions alone.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported when the command runs, not for ``--help``
    import numpy as np

from ..errors import InvalidParameterError
from .inputs import SCENE_HELP, add_model_arguments, csv_column, read_csv, robot_from_args, scene_of
from .map import writable_png

__all__ = ["add_place", "read_tasks"]

ANGLES = ("roll", "pitch", "yaw")


def read_tasks(path: str) -> np.ndarray:
    """The tasks of a CSV file (module doc): poses (N, 4, 4) or positions (N, 3)."""
    import numpy as np
    import pinocchio as pin

    header, rows = read_csv(path)
    known = {"x", "y", "z", *ANGLES}
    unknown = [h for h in header if h not in known]
    if unknown or not {"x", "y", "z"} <= set(header):
        raise InvalidParameterError(
            f"{path}: the header must name x, y, z (and roll, pitch, yaw for poses); got {header}"
        )
    angles = [a for a in ANGLES if a in header]
    if angles and len(angles) != 3:
        raise InvalidParameterError(f"{path}: give all of roll, pitch, yaw or none of them")
    cols = {h: csv_column(rows, k, h, path) for k, h in enumerate(header)}
    for name, values in cols.items():
        if np.isnan(values).any():
            row = int(np.flatnonzero(np.isnan(values))[0]) + 2
            raise InvalidParameterError(f"{path}, row {row}: no value in column {name!r}")
    xyz = np.column_stack([cols["x"], cols["y"], cols["z"]])
    if not angles:
        return xyz
    poses = np.tile(np.eye(4), (len(xyz), 1, 1))
    for i, (r, p, y) in enumerate(zip(cols["roll"], cols["pitch"], cols["yaw"], strict=True)):
        poses[i, :3, :3] = pin.rpy.rpyToMatrix(r, p, y)
    poses[:, :3, 3] = xyz
    return poses


def _cmd_place(args: argparse.Namespace) -> int:
    import matplotlib

    from .. import maps

    robot = robot_from_args(args)
    png = writable_png(args.png)
    tasks = read_tasks(args.tasks)
    scene = scene_of(robot, args.scene)
    target: Any = robot
    if args.score == "backlash":
        from ..papers.backlash import Backlash

        target = Backlash(robot, delta=args.delta, payload=0.0)
    (x0, y0), (x1, y1) = args.region[:2], args.region[2:]
    yaw_range = (math.radians(args.yaw_range[0]), math.radians(args.yaw_range[1]))
    result = maps.placement(
        target, tasks, [[x0, y0], [x1, y1]], height=args.height, step=args.step,
        yaws=args.yaws, yaw_range=yaw_range, scene=scene, score=args.score,
        payload=args.payload, verify=args.verify, collision_free=not args.no_collisions,
        progress=not args.quiet, voxel=args.voxel, angles=args.angles,
        reach_map=None if args.store is None else Path(args.store),
    )  # fmt: skip
    kind = "positions" if result.position_only else "poses"
    print(f"{robot.name}: {len(tasks)} task {kind}, {len(result.xs) * len(result.ys):,} base "
          f"positions x {args.yaws} yaws; {result.method}")  # fmt: skip
    _print_ranks(result, args.score)
    f = result.figures
    print(f"structure {f['structure_s']:.1f} s, estimate {f['estimate_s']:.2f} s, "
          f"verification {f['verify_s']:.2f} s")  # fmt: skip
    if png is not None:
        matplotlib.use("Agg")
        result.draw(png)
        print(f"wrote {png}")
    return 0


SCORE_COLUMNS = {
    "manipulability": ("manipulability", 1.0, "8.4f"),
    "backlash": ("backlash error [mm]", 1e3, "8.3f"),
}


def fixed(value: float, spec: str) -> str:
    """``value`` formatted by ``spec`` (such as ``"7.3f"``) without a negative zero."""
    digits = int(spec.rpartition(".")[2].rstrip("f") or 0)
    return format(round(float(value), digits) + 0.0, spec)


def _print_ranks(result: Any, score: str) -> None:
    """The verified candidates that reach a task, best first, with the score ranked by."""
    column = SCORE_COLUMNS.get(score)
    head = f"  {column[0]}" if column else ""
    print(f"rank  x [m]    y [m]    z [m]   yaw [deg]  reached (verified)  estimated{head}")
    shown = 0
    for k, (base, reach, est, value) in enumerate(
        zip(result.bases, result.reach, result.estimate, result.score, strict=True)
    ):
        if reach <= 0.0:
            continue
        shown += 1
        extra = f"  {fixed(value * column[1], column[2])}" if column else ""
        print(f"{k + 1:4d} {fixed(base[0], '7.3f')}  {fixed(base[1], '7.3f')}  "
              f"{fixed(base[2], '6.3f')}  {fixed(math.degrees(base[3]), '8.1f')}  "
              f"{fixed(100 * reach, '8.1f')} %          {fixed(100 * est, '5.1f')} %"
              f"{extra}")  # fmt: skip
    hidden = len(result.bases) - shown
    if not shown:
        print("     no verified candidate reaches any task: widen the region or move the tasks")
    elif hidden:
        print(f"     ({hidden} more verified candidate(s) reach none of the tasks)")


def add_place(sub: Any) -> None:
    """The ``place`` subcommand's arguments."""
    p = sub.add_parser("place", help="where to put the base so that the tool reaches the tasks")
    p.add_argument("name", help="catalogue model, example robot, or .urdf/.xacro file")
    p.add_argument("tasks", help="CSV of tasks: x, y, z [m] (and roll, pitch, yaw [rad])")
    p.add_argument("--region", nargs=4, type=float, required=True,
                   metavar=("X_MIN", "Y_MIN", "X_MAX", "Y_MAX"),
                   help="where the base may stand [m]")  # fmt: skip
    p.add_argument("--height", type=float, default=0.0, help="the base's height [m] (0)")
    p.add_argument("--step", type=float, default=0.02, help="grid step of the region [m] (0.02)")
    p.add_argument("--yaws", type=int, default=36, help="yaw angles tried (36)")
    p.add_argument("--yaw-range", nargs=2, type=float, default=(-180.0, 180.0),
                   metavar=("LOW", "HIGH"), help="allowed yaw [deg] (-180 180)")  # fmt: skip
    p.add_argument("--scene", metavar="FILE", help=SCENE_HELP)
    p.add_argument(
        "--score",
        choices=["reach", "manipulability", "backlash"],
        default="reach",
        help="rank bases reaching as many tasks by this too: reach (the fraction alone), "
        "manipulability (largest mean), backlash (smallest mean tool error of [P1]'s model, "
        "with --delta and --payload); printed as a column (default: reach)",
    )
    p.add_argument(
        "--delta", type=float, default=0.035, help="backlash gap [rad] (--score backlash)"
    )
    p.add_argument("--payload", type=float, default=0.0, help="payload [kg] (--score backlash)")
    p.add_argument("--verify", type=int, default=10, help="candidates verified and listed (10)")
    p.add_argument("--no-collisions", action="store_true", help="no collision checks")
    p.add_argument("--voxel", type=float, default=0.03, help="the structure's cell [m] (0.03)")
    p.add_argument("--angles", type=int, default=30, help="the structure's axis angles (30)")
    p.add_argument(
        "--store",
        metavar="FOLDER",
        help="keep the inverse-reachability structure in this Zarr folder: built on the "
        "first call, read back (verified) by the next ones with the same robot and settings",
    )
    p.add_argument("--png", help="write the heat map of the region here")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    add_model_arguments(p)
    p.set_defaults(func=_cmd_place)
