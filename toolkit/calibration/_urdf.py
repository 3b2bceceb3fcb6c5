"""The corrected URDF of a calibrated robot (see :mod:`toolkit.calibration`).

Each moving joint's ``<origin>`` becomes origin E_j X(offset_j) (its placement error,
then its zero offset folded in as a turn about, or a shift along, its axis), the joints
out of the root link take the base error on the left, and the fixed joint of the tool
frame takes the tool error on the right. Joint limits stay in the commanded angles.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from ..descriptions import PackageResolver, read_description
from ..errors import UnsupportedModelError
from ._model import Errors, ParameterSet

__all__ = ["corrected_urdf"]


def _origin(joint: ET.Element) -> pin.SE3:
    node = joint.find("origin")
    xyz = [0.0, 0.0, 0.0] if node is None else [float(v) for v in node.get("xyz", "0 0 0").split()]
    rpy = [0.0, 0.0, 0.0] if node is None else [float(v) for v in node.get("rpy", "0 0 0").split()]
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))


def _set_origin(joint: ET.Element, M: pin.SE3) -> None:
    node = joint.find("origin")
    if node is None:
        node = ET.SubElement(joint, "origin")
    node.set("xyz", " ".join(repr(float(v)) for v in M.translation))
    node.set("rpy", " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)))


def _motion(joint: ET.Element, value: float) -> pin.SE3:
    node = joint.find("axis")
    axis = np.array(
        [1.0, 0.0, 0.0] if node is None else [float(v) for v in node.get("xyz", "1 0 0").split()]
    )
    axis = axis / np.linalg.norm(axis)
    if joint.get("type") == "prismatic":
        return pin.SE3(np.eye(3), axis * value)
    return pin.SE3(pin.exp3(axis * value), np.zeros(3))


def corrected_urdf(pset: ParameterSet, errors: Errors) -> str:
    """The robot's URDF text with ``errors`` folded in (module doc)."""
    robot = pset.robot
    if robot.urdf_path is None:
        raise UnsupportedModelError(f"{robot.name}: no URDF file to correct")
    text = PackageResolver(None, robot.urdf_path).absolute_uris(read_description(robot.urdf_path))
    root = ET.fromstring(text)
    joints = {j.get("name"): j for j in root.findall("joint")}  # not a transmission's
    children: dict[str | None, ET.Element] = {}
    for item in joints.values():
        child = item.find("child")
        if child is not None:
            children[child.get("link")] = item
    model = robot.model
    for j in range(1, model.njoints):
        moving = joints.get(model.names[j])
        if moving is None:
            continue
        M = _origin(moving) * errors.placements.get(j, pin.SE3.Identity())
        M = M * _motion(moving, float(errors.offsets[j]))
        _set_origin(moving, M)
    if not np.allclose(errors.base.homogeneous, np.eye(4)):
        links = {link.get("name") for link in root.findall("link")}
        roots = links - set(children)
        for element in joints.values():
            parent = element.find("parent")
            if parent is not None and parent.get("link") in roots:
                _set_origin(element, errors.base * _origin(element))
    if not np.allclose(errors.tool.homogeneous, np.eye(4)):
        tip = model.frames[pset.tip].name
        tool = children.get(tip)
        if tool is None or tool.get("type") != "fixed":
            raise UnsupportedModelError(
                f"{robot.name}: the tool frame {tip!r} is not a link on a fixed joint, so its "
                "error cannot be written into the URDF (calibrate without 'tool')"
            )
        _set_origin(tool, _origin(tool) * errors.tool)
    return ET.tostring(root, encoding="unicode")
