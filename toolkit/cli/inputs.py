"""The command line's model arguments: ``--set``/``--arg``, ``--package-dir``, ``--tip``,
and the robot they name (a catalogue model, an example robot, or a URDF/xacro file); joint
values as the commands take them (:func:`q_of`) and print them (:func:`shown_values`)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InvalidParameterError, UnknownModelError

if TYPE_CHECKING:  # the package loads when a command runs, not for ``--help``
    import numpy as np

    from ..collision import Scene
    from ..robot import Robot

__all__ = [
    "add_model_arguments",
    "csv_column",
    "load_model",
    "moving_joints",
    "parse_sets",
    "q_of",
    "read_csv",
    "robot_from_args",
    "shown_values",
]


def read_csv(path: str | Path) -> Any:
    """:func:`toolkit.common.tables.read_csv` (imported when called)."""
    from ..common import tables

    return tables.read_csv(path)


def csv_column(*args: Any) -> Any:
    """:func:`toolkit.common.tables.csv_column` (imported when called)."""
    from ..common import tables

    return tables.csv_column(*args)


def parse_sets(items: Sequence[str]) -> dict[str, str]:
    params = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InvalidParameterError(f"--set expects NAME=VALUE, got {item!r}")
        params[key.strip()] = value.strip()
    return params


def load_model(
    name: str, sets: Sequence[str], package_dirs: Sequence[str] = (), tip: str | None = None
) -> Robot:
    """A catalogue model, an example robot, or a URDF/xacro file (``--set`` = xacro args).

    Known names come first: a file in the current folder named like a model does not
    shadow it (give it as ``./name``, or with its ``.urdf``/``.xacro`` suffix)."""
    from .. import papers  # noqa: F401 - papers registers its catalogue models
    from ..descriptions import MODELS, example_robots
    from ..robot import load, load_example, load_urdf

    if Path(name).suffix not in (".urdf", ".xacro"):
        if name in MODELS:
            return _with_tip(load(name, **parse_sets(sets)), tip)
        if name in example_robots():
            if sets:
                raise InvalidParameterError(
                    f"--set applies to catalogue models only, not to {name!r}"
                )
            return _with_tip(load_example(name), tip)
        if not Path(name).is_file():
            raise UnknownModelError(name, [*MODELS, *example_robots()])
    dirs = list(package_dirs) or None
    return load_urdf(name, package_dirs=dirs, args=parse_sets(sets), tip=tip)


def add_model_arguments(p: argparse.ArgumentParser, packages: bool = True) -> None:
    """``--set``/``--arg``, and for commands that load a robot ``--package-dir`` and ``--tip``."""
    p.add_argument(
        "--set",
        "--arg",
        dest="set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a xacro argument (repeatable): a catalogue model's, or a .xacro file's",
    )
    if not packages:
        return
    p.add_argument(
        "--package-dir",
        action="append",
        default=[],
        metavar="DIR",
        help="a folder holding ROS packages, for $(find ...) and package:// (repeatable)",
    )
    p.add_argument(
        "--tip",
        default=None,
        metavar="FRAME",
        help="the tool frame (default: the model's; for files, the end of the arm)",
    )
    p.add_argument(
        "--group",
        default=None,
        metavar="NAME",
        help="a planning group of the robot's SRDF (the Panda's 'arm'): only its joints "
        "move, the others stay at their neutral values within their limits",
    )


def _with_tip(robot: Robot, tip: str | None) -> Robot:
    if tip is None:
        return robot
    robot.frames.id(tip)  # an unknown frame lists the valid ones
    return type(robot)(
        robot.model,
        name=robot.name,
        tip=tip,
        urdf_path=robot.urdf_path,
        params=robot.params,
        facts=robot.facts,
        srdf_path=robot.srdf_path,
    )


def robot_from_args(args: argparse.Namespace) -> Robot:
    """The robot of a command's NAME, ``--set``, ``--package-dir``, ``--tip`` and
    ``--group``."""
    robot = load_model(args.name, args.set, args.package_dir, getattr(args, "tip", None))
    group = getattr(args, "group", None)
    return robot.group(group) if group else robot


def moving_joints(robot: Robot, frame: str | None) -> np.ndarray:
    """Mask over the joint values: the joints that move ``frame`` (default: the tip)."""
    import numpy as np

    model = robot.model
    mask = np.zeros(robot.joints.nv, dtype=bool)
    for j in model.supports[model.frames[robot.frames.id(frame)].parentJoint]:
        mask[model.joints[j].idx_v : model.joints[j].idx_v + model.joints[j].nv] = True
    return mask


def q_of(robot: Robot, values: Sequence[float], deg: bool, frame: str | None = None) -> np.ndarray:
    """q from one value per joint; with ``deg`` the revolute joints' values are degrees
    (prismatic strokes stay metres). Joints that do not move ``frame`` (a hand's fingers)
    may be left out: give the values of the moving joints only, in order; the others
    stay at zero."""
    import numpy as np

    moving = moving_joints(robot, frame)
    if len(values) != robot.joints.nv and len(values) == moving.sum():
        full = np.zeros(robot.joints.nv)
        full[moving] = values
        values = list(full)
    elif len(values) != robot.joints.nv:
        fewer = (
            f", or the {int(moving.sum())} that move frame {frame or robot.tip!r}"
            if moving.sum() < robot.joints.nv
            else ""
        )
        raise InvalidParameterError(
            f"{robot.name}: give {robot.joints.nv} joint values ({', '.join(robot.joints.names)})"
            f"{fewer}; got {len(values)}"
        )
    v = robot.joints.check_v(values, "joint values")
    if deg:
        v = np.where(robot.joints.revolute_mask_v, np.radians(v), v)
    return robot.joints.q_from_angles(v)


def shown_values(robot: Robot, q: np.ndarray, deg: bool) -> tuple[np.ndarray, str]:
    """(one value per joint of q (nq,) or rows (N, nq), revolute ones in degrees with
    ``deg``; "name [unit], ..." naming the columns) for printing."""
    import numpy as np

    values = robot.joints.angles(q)
    turns = robot.joints.revolute_mask_v
    if deg:
        values = np.where(turns, np.degrees(values), values)
    units = [("deg" if deg else "rad") if t else "m" for t in turns]
    names = ", ".join(f"{n} [{u}]" for n, u in zip(robot.joints.names, units, strict=True))
    return np.asarray(values), names


SCENE_HELP = "obstacles: a MoveIt planning scene (.yaml) or a toolkit scene (.json)"


def scene_of(robot: Robot, path: str | None) -> Scene | None:
    """The scene of a command's ``--scene``: a MoveIt planning scene (.yaml, .yml; its
    frames the robot's fixed ones) or a toolkit scene (.json), in the base frame."""
    from .. import planning
    from ..collision import Scene

    if path is None:
        return None
    if Path(path).suffix.lower() in (".yaml", ".yml"):
        return planning.read_scene(path, frames=planning.fixed_frames(robot))
    return Scene.load(path)


def trajectory_of(robot: Robot, path: str) -> tuple[Robot, Any]:
    """(the robot it moves, the :class:`~toolkit.motion.Trajectory`) of a trajectory file:
    a MoveIt joint trajectory (.yaml, .yml: the piecewise quintic through its samples where
    it gives velocities and accelerations, else the cubic spline) or a CSV file
    (:func:`toolkit.motion.read_trajectory`). A trajectory of some of the robot's joints
    (a plan of the Panda's arm) moves the group of those joints, the others locked."""
    from .. import motion, planning

    if Path(path).suffix.lower() not in (".yaml", ".yml"):
        return robot, motion.read_trajectory(path, robot)
    read = planning.read_joint_trajectory(path)
    unknown = [n for n in read.names if n not in robot.joints.names]
    if unknown:
        raise InvalidParameterError(
            f"{path}: joints {unknown} are not joints of {robot.name} "
            f"({', '.join(robot.joints.names)})"
        )
    if list(read.names) != list(robot.joints.names):
        robot = robot.group(list(read.names))
        order = [read.names.index(n) for n in robot.joints.names]
    else:
        order = list(range(len(read.names)))
    times = read.times - read.times[0]
    values = read.positions[:, order]
    if read.velocities is not None and read.accelerations is not None:
        return robot, motion.hermite(times, values, read.velocities[:, order],
                                     read.accelerations[:, order])  # fmt: skip
    return robot, motion.cubic(robot, robot.joints.q_from_angles(values), times)
