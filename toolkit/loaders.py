"""Ways to get a :class:`Robot`: the catalogue, any URDF file, or example-robot-data.

Nothing here touches the network: catalogue models are rendered from the
toolkit's own templates and example robots are read from the files the
``example-robot-data`` package installed.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .catalogue import get_spec
from .errors import InstallationError, InvalidParameterError, ModelLoadError, UnknownModelError
from .render import resolve_arguments, urdf_path
from .robot import Robot

__all__ = [
    "EXAMPLE_ROBOTS",
    "ExampleRobot",
    "example_robot_data_dir",
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
    return _build(path, name=name, tip=spec.tip, mimic=spec.mimic, params=values, facts=spec.facts)


def load_urdf(
    path: str | Path, *, tip: str | None = None, mimic: bool = False, name: str | None = None
) -> Robot:
    """Build a :class:`Robot` from any URDF file (fixed base).

    ``tip`` defaults to the last frame of the model. ``mimic=True`` keeps
    ``<mimic>`` joints as coupled joints (Pinocchio >= 3.8). The model is checked after
    parsing: a joint with a zero axis or a body with a negative mass raises
    :class:`~toolkit.errors.ModelLoadError`; limits that are not finite or have
    lower > upper make the joint unlimited (see :mod:`toolkit.joints`). XML entities
    are not expanded by the URDF parser (no external file is read through them).
    """
    if not isinstance(path, str | Path):
        raise InvalidParameterError(f"path must be a file path (str or Path), got {path!r}")
    if not isinstance(mimic, bool):
        raise InvalidParameterError(f"mimic must be True or False, got {mimic!r}")
    path = Path(path)
    if not path.is_file():
        raise ModelLoadError(f"URDF file not found: {path}")
    return _build(path, name=name or path.stem, tip=tip, mimic=mimic)


def _build(
    path: Path,
    *,
    name: str,
    tip: str | None,
    mimic: bool,
    params: Mapping[str, float | int | str] | None = None,
    facts: Mapping[str, object] | None = None,
) -> Robot:
    try:
        if mimic:
            model = pin.buildModelFromUrdf(str(path), mimic=True)
        else:
            model = pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError) as exc:
        raise ModelLoadError(f"Pinocchio could not parse {path}: {exc}") from exc
    _check_physics(model, path)
    return Robot(model, name=name, tip=tip, urdf_path=path, params=params, facts=facts)


def _check_physics(model: pin.Model, path: Path) -> None:
    """Refuse what no real robot has: a joint axis of zero length, a negative mass."""
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if "Unaligned" in joint.shortname():
            axis = np.asarray(joint.extract().axis, dtype=float)
            if not np.linalg.norm(axis) > 0.5:  # unit after parsing, or zero
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


def load_example(name: str) -> Robot:
    """Load a robot shipped by example-robot-data from disk (never downloaded).

    Known names: see :data:`EXAMPLE_ROBOTS` (``ur5``, ``panda``, ``so101``, ``z1``, ...).
    """
    entry = EXAMPLE_ROBOTS.get(name) if isinstance(name, str) else None
    if entry is None:
        raise UnknownModelError(str(name), EXAMPLE_ROBOTS, what="example robot")
    path = example_robot_data_dir() / entry.urdf
    if not path.is_file():
        raise InstallationError(f"example-robot-data has no file {path}")
    return _build(path, name=name, tip=entry.tip, mimic=False)
