"""Pinocchio models from descriptions: parsing with the parser's own words kept, the checks
no real robot fails, the default tool frame, and the robots example-robot-data installed.

Nothing here touches the network: example robots are read from the files the
``example-robot-data`` package installed. :mod:`toolkit.robot` wraps these models in a
:class:`~toolkit.robot.Robot` (``load``, ``load_urdf``, ``load_example``).
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import IO

import numpy as np
import pinocchio as pin

from ..errors import (
    InstallationError,
    ModelLoadError,
)
from .files import check_size

__all__ = [
    "EXAMPLE_ROBOTS",
    "ExampleRobot",
    "build_model",
    "check_physics",
    "default_tip",
    "example_robot_data_dir",
    "example_robots",
    "srdf_beside",
    "tip_candidates",
]


def build_model(
    path: Path, text: str, *, mimic: bool, floating: bool, source: str | Path | None = None
) -> pin.Model:
    """Pinocchio's model of URDF ``text`` (read from ``path``, or rendered from ``source``
    by this process: Pinocchio never opens a cache path that could change between check and
    use), checked for what no real robot has (:func:`check_physics`)."""
    root = [pin.JointModelFreeFlyer()] if floating else []
    check_size(text, source if isinstance(source, Path) else path)
    with _stderr_captured() as said:
        try:
            model = pin.buildModelFromXML(text, *root, mimic=mimic)
        except (RuntimeError, ValueError) as exc:
            cause = next((line for line in said() if line.strip()), "")
            detail = f" ({cause.strip()})" if cause else ""
            what = str(path)
            if (
                isinstance(source, Path | str)
                and Path(source) != path
                and "<robot" not in str(source)
            ):
                what = f"{source} (rendered to {path})"
            raise ModelLoadError(f"Pinocchio could not parse {what}: {exc}{detail}") from exc
    check_physics(model, path)
    return model


@contextmanager
def _stderr_captured() -> Iterator[Callable[[], list[str]]]:
    """Capture what C++ code (urdfdom) writes to file descriptor 2 while the block runs
    (in a temporary file; in memory when no temporary folder can be written)."""
    try:
        sink: IO[bytes] = tempfile.TemporaryFile(mode="w+b")
    except OSError:
        try:
            sink = os.fdopen(os.memfd_create("toolkit-stderr"), "w+b")
        except (OSError, AttributeError):  # no temporary folder, no memfd: not captured
            yield lambda: []
            return
    with sink:
        try:
            saved = os.dup(2)
        except OSError:  # pragma: no cover - no stderr to capture
            yield lambda: []
            return
        sys.stderr.flush()
        os.dup2(sink.fileno(), 2)
        try:
            yield lambda: _lines(sink)
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def _lines(sink: IO[bytes]) -> list[str]:
    sink.flush()
    sink.seek(0)
    text: str = sink.read().decode("utf-8", "replace")
    return text.splitlines()


def _moves(model: pin.Model, joint: int) -> int:
    """1 if the joint moves (it has a velocity, or copies one as a mimic joint), else 0."""
    return int(model.joints[joint].nv > 0 or model.joints[joint].shortname() == "JointModelMimic")


def _moving_depth(model: pin.Model, joint: int) -> int:
    depth = 0
    while joint > 0:
        depth += _moves(model, joint)
        joint = int(model.parents[joint])
    return depth


def tip_candidates(model: pin.Model) -> list[str]:
    """Body frames carried by at least one moving joint (what a tip can be)."""
    return [
        f.name
        for f in model.frames
        if f.type == pin.BODY and f.parentJoint > 0 and _moving_depth(model, f.parentJoint) > 0
    ]


_TOOL_NAME = re.compile(
    r"(^|[_\-])(tcp|ee|eef|end_?effector|tool0?|tool_?frame|ee_?link|gripper_?tcp)($|[_\-])",
    re.IGNORECASE,
)
_FINGERS = 2  # a gripper's branches are at most this many moving joints deep


def _deepest_moving(model: pin.Model, joint: int) -> int:
    """Moving joints on the longest path down from ``joint`` (itself excluded)."""
    children = [k for k in range(joint + 1, model.njoints) if model.parents[k] == joint]
    best = 0
    for k in children:
        best = max(best, _moves(model, k) + _deepest_moving(model, k))
    return best


def _arm_end(model: pin.Model, tip_joint: int) -> int:
    """The joint carrying the end of the arm: walking up from a finger tip, the first joint
    within two moving joints where another short moving branch (a second finger, a mimic
    finger) leaves; ``tip_joint`` itself when there is none (no gripper)."""
    passed, j = 0, tip_joint
    while j > 0 and passed <= _FINGERS:
        parent = int(model.parents[j])
        passed += _moves(model, j)
        others = [
            k for k in range(parent + 1, model.njoints) if model.parents[k] == parent and k != j
        ]
        branches = [_moves(model, k) + _deepest_moving(model, k) for k in others]
        fingers = [d for d in branches if 0 < d <= _FINGERS]
        gripper = fingers and len(fingers) == len([d for d in branches if d])
        if gripper and passed <= _FINGERS and _moving_depth(model, parent) > 0:
            return parent
        j = parent
    return tip_joint


def default_tip(model: pin.Model) -> str:
    """The end of the arm: a frame named like a tool point (``tcp``, ``ee``, ``tool0``,
    ``end_effector``, ...) on the deepest moving chain when there is one; else the end of
    the longest chain of moving joints, or, when that chain ends in a gripper (two short
    branches of moving or mimic fingers), the last frame before the gripper's branching.
    Never a frame fixed to the base; the last frame of a model without moving joints."""
    best: str = model.frames[len(model.frames) - 1].name
    best_depth = 0
    named: tuple[int, str] | None = None
    for frame in model.frames:
        if frame.parentJoint == 0:
            continue
        depth = _moving_depth(model, int(frame.parentJoint))
        tool_like = frame.type == pin.BODY and _TOOL_NAME.search(frame.name)
        if depth and tool_like and (named is None or depth >= named[0]):
            named = (depth, frame.name)
        if frame.type == pin.BODY and depth >= best_depth and depth > 0:
            best, best_depth = frame.name, depth
    if named is not None:
        return named[1]
    if best_depth == 0:
        return best
    tip_joint = int(model.frames[model.getFrameId(best)].parentJoint)
    end = _arm_end(model, tip_joint)
    if end == tip_joint:
        return best
    on_end = [f.name for f in model.frames if f.type == pin.BODY and f.parentJoint == end]
    return on_end[-1] if on_end else str(model.names[end])


def srdf_beside(urdf: Path) -> Path | None:
    """example-robot-data's SRDF of a description: ``<description>/srdf/<stem>.srdf`` (or
    the stem without ``_robot``), if there is one."""
    folder = urdf.parent.parent / "srdf"
    for stem in (urdf.stem, urdf.stem.removesuffix("_robot")):
        candidate = folder / f"{stem}.srdf"
        if candidate.is_file():
            return candidate
    return None


def check_physics(model: pin.Model, path: Path) -> None:
    """Refuse what no real robot has: a joint axis of zero length, a negative mass.

    The axis is read from each 1-DoF joint's motion subspace (unit after parsing, or zero),
    whatever Pinocchio's joint type (aligned, unaligned, unbounded)."""
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nv == 1 and joint.shortname() != "JointModelMimic":
            if not np.linalg.norm(np.asarray(data.joints[j].S)) > 0.5:
                raise ModelLoadError(f"{path}: joint {model.names[j]!r} has a zero axis")
    for j, inertia in enumerate(model.inertias):
        if inertia.mass < 0 or not np.isfinite(inertia.mass):
            raise ModelLoadError(
                f"{path}: the body of joint {model.names[j]!r} has mass {inertia.mass} kg"
            )


@dataclass(frozen=True)
class ExampleRobot:
    """A robot shipped by example-robot-data: its URDF (relative to the robots folder) and tip."""

    urdf: str
    tip: str


EXAMPLE_ROBOTS: dict[str, ExampleRobot] = {
    "ur3": ExampleRobot("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur5": ExampleRobot("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": ExampleRobot("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "panda": ExampleRobot("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "so100": ExampleRobot("so_arm_description/urdf/so100.urdf", "gripper"),
    "so101": ExampleRobot("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
    "z1": ExampleRobot("z1_description/urdf/z1.urdf", "gripperStator"),
}


def example_robot_data_dir() -> Path:
    """The ``robots`` folder installed by example-robot-data (searched on disk only).

    ``$EXAMPLE_ROBOT_DATA_DIR`` overrides the search.
    """
    env = os.environ.get("EXAMPLE_ROBOT_DATA_DIR")
    candidates = [Path(env)] if env else []
    for entry in sys.path:
        base = Path(entry or ".")
        candidates.append(base / "cmeel.prefix" / "share" / "example-robot-data" / "robots")
        # sys.path may hold cmeel.prefix/lib/pythonX.Y/site-packages itself
        for parent in base.parents:
            if parent.name == "cmeel.prefix":
                candidates.append(parent / "share" / "example-robot-data" / "robots")
                break
    candidates.append(Path(sys.prefix) / "share" / "example-robot-data" / "robots")
    for folder in candidates:
        if (folder / "ur_description").is_dir():
            return folder
    raise InstallationError(
        "example-robot-data is not installed (no robots folder found on sys.path); "
        "install it with `pip install example-robot-data` or set EXAMPLE_ROBOT_DATA_DIR"
    )


def example_robots() -> dict[str, Path]:
    """Every robot description example-robot-data ships, by name: the curated names of
    :data:`EXAMPLE_ROBOTS`, then each other ``.urdf`` file by its stem (``package-stem``
    where two packages ship the same stem). The installed files are listed once."""
    return dict(_example_robots(example_robot_data_dir()))


@cache
def _example_robots(root: Path) -> tuple[tuple[str, Path], ...]:
    found: dict[str, list[Path]] = {}
    for path in sorted(root.rglob("*.urdf")):
        found.setdefault(path.stem, []).append(path)
    out = {name: root / entry.urdf for name, entry in EXAMPLE_ROBOTS.items()}
    curated = set(out.values())
    for stem, paths in found.items():
        for path in paths:
            if path in curated:
                continue
            name = stem if len(paths) == 1 else f"{path.relative_to(root).parts[0]}-{stem}"
            out.setdefault(name, path)
    return tuple(out.items())
