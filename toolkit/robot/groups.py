"""Planning groups and named states, as an SRDF declares them and MoveIt reads them.

A ``<group>`` lists joints (``<joint>``), links (``<link>``: the joint above the link),
chains (``<chain base_link tip_link>``: the joints from the base link down to the tip
link) and other groups (``<group name>``); its joints that move in the description, in the
model's order, are the group's. A ``<group_state>`` gives values to a group's joints.

:func:`group_robot` makes the robot of a group: the description's other joints locked
(Pinocchio's reduced model) at the values of a given configuration, else at their
neutral values brought into their limits, so that IK, plans, trajectories and maps move
only the group's joints. The group's robot keeps the description's files, frames, shapes
and the SRDF's disabled pairs.
"""

from __future__ import annotations

import difflib
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from ..descriptions import read_srdf
from ..errors import InvalidParameterError, ModelLoadError

__all__ = ["group_joints", "group_robot", "named_states"]


def _body(model: pin.Model, name: str) -> Any:
    """The model's frame of link ``name``."""
    return model.frames[model.getFrameId(name, pin.FrameType.BODY)]


def _chain(model: pin.Model, base: str, tip: str, group: str) -> set[int]:
    """The joints between link ``base`` and link ``tip`` (MoveIt: the parent joints of the
    chain's links below the base)."""
    ids = {}
    for end in (base, tip):
        if not model.existBodyName(end):
            raise InvalidParameterError(f"group {group!r}: chain link {end!r} is not in the model")
        ids[end] = int(_body(model, end).parentJoint)
    above = set(model.supports[ids[tip]])
    return {j for j in above if j > 0 and j not in set(model.supports[ids[base]])}


def _joint_ids(model: pin.Model, groups: Mapping[str, ET.Element], name: str,
               seen: tuple[str, ...] = ()) -> set[int]:  # fmt: skip
    """The model's joints of the SRDF group ``name`` (its subgroups' too)."""
    if name in seen:
        raise InvalidParameterError(f"group {name!r} contains itself ({' > '.join(seen)})")
    found: set[int] = set()
    for item in groups[name]:
        other = str(item.get("name", ""))
        if item.tag == "joint" and model.existJointName(other):
            found.add(int(model.getJointId(other)))  # a fixed joint is not in the model
        elif item.tag == "link" and model.existBodyName(other):
            body = _body(model, other)  # its joint: moving, or fixed (not in the model)
            if model.frames[body.parentFrame].type == pin.FrameType.JOINT:
                found.add(int(body.parentJoint))
        elif item.tag == "chain":
            found |= _chain(model, str(item.get("base_link")), str(item.get("tip_link")), name)
        elif item.tag == "group":
            if other not in groups:
                raise InvalidParameterError(f"group {name!r}: no subgroup {other!r}")
            found |= _joint_ids(model, groups, other, (*seen, name))
    return found - {0}


def group_joints(robot: Any, group: str | Sequence[str]) -> list[str]:
    """The joint names of ``group`` in the model's order: an SRDF group's name, or the
    joint names themselves (a group where there is no SRDF)."""
    model = robot.model
    if isinstance(group, str):
        groups, _ = read_srdf(robot.srdf_path)
        if group not in groups:
            near = difflib.get_close_matches(group, list(groups), n=3)
            hint = f"; did you mean {', '.join(near)}?" if near else ""
            known = ", ".join(groups) or f"none: {robot.name} has no SRDF"
            raise InvalidParameterError(f"no group {group!r} (groups: {known}){hint}")
        ids = _joint_ids(model, groups, group)
    else:
        if not isinstance(group, Sequence) or not all(isinstance(n, str) for n in group):
            raise InvalidParameterError(
                f"group must be an SRDF group's name or a list of joint names, got {group!r:.80}"
            )
        names = list(group)
        unknown = [n for n in names if n not in robot.joints.names]
        if unknown or not names:
            raise InvalidParameterError(
                f"group: unknown joints {unknown} (joints: {', '.join(robot.joints.names)})"
            )
        ids = {int(model.getJointId(n)) for n in names}
    if not ids:
        raise InvalidParameterError(f"group {group!r} moves no joint of {robot.name}")
    return [str(model.names[j]) for j in sorted(ids)]


def _reference(robot: Any, at: object) -> np.ndarray:
    """The configuration the locked joints keep: ``at`` (checked), else the neutral one
    with each 1-value joint brought into its limits."""
    if at is not None:
        q: np.ndarray = robot.joints.check(at)
        return q
    q = np.asarray(robot.joints.neutral(), dtype=float).copy()
    low, high = np.asarray(robot.joints.lower, float), np.asarray(robot.joints.upper, float)
    for joint in list(robot.model.joints)[1:]:
        if joint.nq == 1:
            k = joint.idx_q
            q[k] = min(max(q[k], low[k]), high[k])
    return q


def group_robot(robot: Any, group: str | Sequence[str], at: object = None) -> Any:
    """The robot of ``group`` (module doc): its joints move, the others are locked at
    ``at`` (a configuration of ``robot``) or at their neutral values within the limits."""
    names = group_joints(robot, group)
    q = _reference(robot, at)
    model = robot.model
    locked = [j for j in range(1, model.njoints) if str(model.names[j]) not in set(names)]
    if not locked:
        return robot
    reduced = pin.buildReducedModel(_unclashed(model), locked, q)
    label = group if isinstance(group, str) else "+".join(names)
    return type(robot)(
        reduced, name=f"{robot.name}:{label}", tip=_tip(robot, names), urdf_path=robot.urdf_path,
        params=robot.params, facts=robot.facts, srdf_path=robot.srdf_path,
    )  # fmt: skip


def _tip(robot: Any, names: list[str]) -> str:
    """The group's tool frame: the robot's own where the group moves it, else the last
    link its last joint carries (Baxter's ``left_gripper`` for ``left_arm``)."""
    model = robot.model
    ids = {int(model.getJointId(n)) for n in names}
    tip = model.frames[robot.frames.id(None)]
    if ids & set(model.supports[tip.parentJoint]):
        return str(robot.tip)
    last = max(ids)
    carried = [f.name for f in model.frames
               if f.type == pin.FrameType.BODY and f.parentJoint == last]  # fmt: skip
    return str(carried[-1]) if carried else str(model.names[last])


def _unclashed(model: pin.Model) -> pin.Model:
    """``model``, or a copy whose fixed-joint frames named as a link (Baxter's ``left_hand``
    joint and link) are named ``<name>_joint``: Pinocchio's reduction refuses a name two
    frames share."""
    bodies = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    clash = [i for i, f in enumerate(model.frames)
             if f.type == pin.FrameType.FIXED_JOINT and f.name in bodies]  # fmt: skip
    if not clash:
        return model
    model = model.copy()
    for i in clash:
        frame = model.frames[i]
        frame.name = f"{frame.name}_joint"
        model.frames[i] = frame
    return model


def named_states(robot: Any) -> dict[str, np.ndarray]:
    """The SRDF's ``<group_state>`` configurations of ``robot`` (nq each): the state's
    joints at its values, the others at their neutral values within the limits. Joints
    the description fixes, or this robot locks, are left out."""
    _, states = read_srdf(robot.srdf_path)
    found: dict[str, np.ndarray] = {}
    model = robot.model
    rest = _reference(robot, None)
    for state in states:
        q = rest.copy()
        for item in state.findall("joint"):
            name, value = str(item.get("name", "")), item.get("value")
            if not model.existJointName(name) or value is None:
                continue
            joint = model.joints[model.getJointId(name)]
            try:
                angle = float(value.split()[0])
            except (ValueError, IndexError):
                raise ModelLoadError(f"group_state {state.get('name')!r}: joint {name!r} "
                                     f"value {value!r} is not a number") from None  # fmt: skip
            if joint.nq == 2:  # a continuous joint: (cos, sin)
                q[joint.idx_q : joint.idx_q + 2] = np.cos(angle), np.sin(angle)
            elif joint.nq == 1:
                q[joint.idx_q] = angle
        found[str(state.get("name"))] = q
    return found
