"""Ways to get a :class:`Robot`: the catalogue, any URDF file, or example-robot-data.

Nothing here touches the network: catalogue models are rendered from the
toolkit's own templates and example robots are read from the files the
``example-robot-data`` package installed (:mod:`toolkit.descriptions`).
"""

from __future__ import annotations

import difflib
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import pinocchio as pin

from ..common import validate as _validate
from ..descriptions import (
    EXAMPLE_ROBOTS,
    build_model,
    default_tip,
    example_robot_data_dir,
    example_robots,
    get_spec,
    read_description,
    resolve_arguments,
    srdf_beside,
    tip_candidates,
    urdf_path,
    urdf_source,
    urdf_text,
)
from ..errors import (
    FrameNotFoundError,
    InertiaWarning,
    InstallationError,
    InvalidParameterError,
    UnknownModelError,
)
from .model import Robot

__all__ = ["EXAMPLE_ROBOTS", "load", "load_example", "load_urdf"]


def load(name: str, **params: object) -> Robot:
    """Load a catalogue model by name; keyword arguments override its xacro arguments.

    >>> robot = load("katana_6m180", a2=0.2)
    >>> robot.nq
    5
    """
    try:
        spec = get_spec(name)
    except UnknownModelError as exc:
        near = difflib.get_close_matches(str(name), list(EXAMPLE_ROBOTS), n=1, cutoff=0.6)
        if near:  # the other door, named
            hint = f"toolkit.load_example({near[0]!r})"
            exc.args = (f"{name!r} is not a catalogue model; the example robot {near[0]!r} "
                        f"(example-robot-data) loads with {hint}",)  # fmt: skip
        raise
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
            the folders up from the file (:mod:`toolkit.descriptions.files`).
        args: xacro arguments (``key: value``).
        tip: the tool frame; default: the end of the longest chain of moving joints
            (never a frame fixed to the base). An unknown name lists the candidates.
        mimic: keep ``<mimic>`` joints coupled; default: when the file has any.
        floating: a free-flyer root joint instead of a fixed base.
        srdf: an SRDF file whose ``<disable_collisions>`` pairs the collision checks skip
            (:mod:`toolkit.collision`).

    The model is checked after parsing: a joint with a zero axis or a body with a negative
    mass raises :class:`~toolkit.errors.ModelLoadError`; limits that are not finite or have
    lower > upper make the joint unlimited (see :mod:`toolkit.kinematics.joints`). XML entities are
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
    text = read_description(path) if text is None else text
    model = build_model(path, text, mimic=mimic, floating=floating, source=source)
    missing = _links_without_inertia(text, model)
    if missing:
        warnings.warn(
            f"{name}: the description gives no inertia (an <inertial> with a mass) for "
            f"link{'s' if len(missing) > 1 else ''} {', '.join(missing[:12])}"
            f"{' ...' if len(missing) > 12 else ''} (with shapes, on bodies that then weigh "
            "nothing); kinematics, "
            "collisions and planning work, dynamics (torques, the mass matrix, forward "
            "dynamics, torque-limited timing, backlash) are refused",
            InertiaWarning,
            stacklevel=3,
        )
        facts = {**(facts or {}), "without_inertia": tuple(missing)}
    if tip is None:
        tip = default_tip(model)
    elif isinstance(tip, str) and tip not in {f.name for f in model.frames}:
        raise FrameNotFoundError(tip, tip_candidates(model), robot=name)
    return Robot(
        model, name=name, tip=tip, urdf_path=path, params=params, facts=facts, srdf_path=srdf
    )


def _links_without_inertia(text: str, model: pin.Model) -> list[str]:
    """The links of a URDF that have a visual or collision shape but no inertia (no
    ``<inertial>``, or a mass of 0) on a moving body that weighs nothing in the model:
    a tool link without inertia on a wrist that has its own (UR5's ee_link) is not one,
    and virtual links, frames between joints, carry no shapes and need none."""
    import re
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(re.sub(r"^<\?xml[^>]*\?>", "", text.lstrip()))
    except ET.ParseError:  # pragma: no cover - Pinocchio parsed it already
        return []
    body = {f.name: int(f.parentJoint) for f in model.frames if f.type == pin.FrameType.BODY}
    kept = {name for name, j in body.items() if j > 0 and model.inertias[j].mass <= 0.0}
    out = []
    for link in root.iter("link"):
        shaped = link.find("visual") is not None or link.find("collision") is not None
        inertial = link.find("inertial")
        mass = inertial.find("mass") if inertial is not None else None
        try:
            weight = float(mass.get("value", "0")) if mass is not None else 0.0
        except ValueError:
            weight = 0.0
        if shaped and weight <= 0.0 and link.get("name") in kept:
            out.append(str(link.get("name")))
    return out


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
        srdf = srdf_beside(path)
        return _build(path, name=name, tip=entry.tip, mimic=False, floating=floating, srdf=srdf)
    everything = example_robots()
    if name not in everything:
        raise UnknownModelError(name, everything, what="example robot")
    path = everything[name]
    return _build(path, name=name, tip=None, mimic=False, floating=floating, srdf=srdf_beside(path))
