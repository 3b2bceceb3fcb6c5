"""Ways to get a :class:`Robot`: the catalogue, any URDF file, or example-robot-data.

Nothing here touches the network: catalogue models are rendered from the
toolkit's own templates and example robots are read from the files the
``example-robot-data`` package installed.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import IO

import numpy as np
import pinocchio as pin

from . import _validate
from .catalogue import get_spec
from .descriptions import check_size, read_description, urdf_source
from .errors import (
    FrameNotFoundError,
    InstallationError,
    InvalidParameterError,
    ModelLoadError,
    UnknownModelError,
)
from .render import resolve_arguments, urdf_path, urdf_text
from .robot import Robot

__all__ = [
    "EXAMPLE_ROBOTS",
    "ExampleRobot",
    "example_robot_data_dir",
    "example_robots",
    "load",
    "load_example",
    "load_urdf",
]


def load(name: str, **params: object) -> Robot:
    """Load a catalogue model by name; keyword arguments override its xacro arguments.

    >>> robot = load("katana_6m180", a2=0.2)
    >>> robot.nq
    5
    """
    spec = get_spec(name)
    path = urdf_path(name, **params)
    values = resolve_arguments(name, **params)
    text = urdf_text(name, **params)  # rendered by this process: never read back from disk
    return _build(
        path, name=name, tip=spec.tip, mimic=spec.mimic, params=values, facts=spec.facts, text=text
    )


def load_urdf(
    source: str | Path,
    *,
    package_dirs: Sequence[str | Path] | Mapping[str, str | Path] | None = None,
    args: Mapping[str, object] | None = None,
    tip: str | None = None,
    mimic: bool | None = None,
    floating: bool = False,
    name: str | None = None,
    srdf: str | Path | None = None,
) -> Robot:
    """Build a :class:`Robot` from a ``.urdf`` or ``.xacro`` file, or from URDF text.

    Args:
        source: a file path, or URDF text (anything containing ``<robot``).
        package_dirs: where ``$(find pkg)`` and ``package://pkg/`` look first: folders
            holding packages, or a {name: folder} map; then ``$ROS_PACKAGE_PATH``, then
            the folders up from the file (:mod:`toolkit.descriptions`).
        args: xacro arguments (``key: value``).
        tip: the tool frame; default: the end of the longest chain of moving joints
            (never a frame fixed to the base). An unknown name lists the candidates.
        mimic: keep ``<mimic>`` joints coupled; default: when the file has any.
        floating: a free-flyer root joint instead of a fixed base.
        srdf: an SRDF file whose ``<disable_collisions>`` pairs the collision checks skip
            (:mod:`toolkit.collision`).

    The model is checked after parsing: a joint with a zero axis or a body with a negative
    mass raises :class:`~toolkit.errors.ModelLoadError`; limits that are not finite or have
    lower > upper make the joint unlimited (see :mod:`toolkit.joints`). XML entities are
    not expanded by the URDF parser. Xacro runs ``${...}`` as Python: load trusted files.
    """
    if mimic is not None and not isinstance(mimic, bool):
        raise InvalidParameterError(f"mimic must be True, False or None, got {mimic!r}")
    floating = _validate.flag(floating, "floating")
    path, text, default_name = urdf_source(source, package_dirs, args)
    if mimic is None:
        mimic = "<mimic" in text
    if name is not None and not isinstance(name, str):
        raise InvalidParameterError(f"name must be a string or None, got {name!r:.80}")
    if srdf is not None and (not isinstance(srdf, str | Path) or not Path(srdf).is_file()):
        raise InvalidParameterError(f"srdf must be an SRDF file, got {srdf!r:.200}")
    return _build(
        path,
        name=name or default_name,
        tip=tip,
        mimic=mimic,
        floating=floating,
        source=source,
        text=text,
        srdf=Path(srdf) if srdf is not None else None,
    )


def _build(
    path: Path,
    *,
    name: str,
    tip: str | None,
    mimic: bool,
    params: Mapping[str, float | int | str] | None = None,
    facts: Mapping[str, object] | None = None,
    floating: bool = False,
    source: str | Path | None = None,
    text: str | None = None,
    srdf: Path | None = None,
) -> Robot:
    """The robot of ``text`` (the URDF this process rendered or read once; Pinocchio never
    opens a cache path that could change between check and use), else of the file."""
    root = [pin.JointModelFreeFlyer()] if floating else []
    text = read_description(path) if text is None else text
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
    _check_physics(model, path)
    if tip is None:
        tip = default_tip(model)
    elif isinstance(tip, str) and tip not in {f.name for f in model.frames}:
        raise FrameNotFoundError(tip, _tip_candidates(model), robot=name)
    return Robot(
        model, name=name, tip=tip, urdf_path=path, params=params, facts=facts, srdf_path=srdf
    )


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


def _tip_candidates(model: pin.Model) -> list[str]:
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


def _srdf_beside(urdf: Path) -> Path | None:
    """example-robot-data's SRDF of a description: ``<description>/srdf/<stem>.srdf`` (or
    the stem without ``_robot``), if there is one."""
    folder = urdf.parent.parent / "srdf"
    for stem in (urdf.stem, urdf.stem.removesuffix("_robot")):
        candidate = folder / f"{stem}.srdf"
        if candidate.is_file():
            return candidate
    return None


def _check_physics(model: pin.Model, path: Path) -> None:
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


def load_example(name: str, *, floating: bool = False) -> Robot:
    """Load a robot shipped by example-robot-data from disk (never downloaded).

    Every description it ships has a name (:func:`example_robots`; ``toolkit list``):
    ``ur5``, ``panda``, ``so101``, ``z1`` ... with a chosen tool frame, and every other
    ``.urdf`` by its file name (``talos_full_v2``, ``solo12``, ``go2``, ...) with the tip
    :func:`default_tip` picks. Fixed base by default; ``floating=True`` adds a free-flyer
    root (legged and humanoid robots). ``<mimic>`` joints are kept independent.
    """
    floating = _validate.flag(floating, "floating")
    if not isinstance(name, str):
        raise UnknownModelError(repr(name)[:60], EXAMPLE_ROBOTS, what="example robot")
    entry = EXAMPLE_ROBOTS.get(name)
    if entry is not None:
        path = example_robot_data_dir() / entry.urdf
        if not path.is_file():
            raise InstallationError(f"example-robot-data has no file {path}")
        srdf = _srdf_beside(path)
        return _build(path, name=name, tip=entry.tip, mimic=False, floating=floating, srdf=srdf)
    everything = example_robots()
    if name not in everything:
        raise UnknownModelError(name, everything, what="example robot")
    path = everything[name]
    return _build(
        path, name=name, tip=None, mimic=False, floating=floating, srdf=_srdf_beside(path)
    )
