"""The visual shapes of a robot, for the viewer: meshes where they can be found, primitive
shapes where they cannot.

:func:`visual_model` reads the ``<visual>`` elements of the robot's URDF (already rendered:
``package://`` URIs were resolved by :mod:`toolkit.descriptions` when it was loaded) and
builds Pinocchio's visual ``GeometryModel``. A mesh that is missing, or in a format the
viewer cannot draw (it draws STL, DAE and OBJ), is replaced by a small sphere and named
in a warning; a link-to-link "bone" (a thin cylinder) is then added for every joint
offset, so the robot's shape is still visible. The viewer never fails to show a robot
because of its meshes.
"""

from __future__ import annotations

import hashlib
import os
import re
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import cache, caller_level
from ..common import validate as _validate
from ..descriptions import example_robot_data_dir, read_description
from ..errors import InvalidParameterError, ModelLoadError, ToolkitError
from ..robot import Robot, as_robot

__all__ = [
    "DRAWN_FORMATS",
    "MissingMeshWarning",
    "Visuals",
    "camera_position",
    "frame_box",
    "scene_box",
    "visual_model",
]

DRAWN_FORMATS = (".stl", ".dae", ".obj")


class MissingMeshWarning(UserWarning):
    """A mesh of the robot's description could not be found or drawn."""


@dataclass(frozen=True)
class Visuals:
    """What the viewer draws: the visual geometry, and the meshes left out (with why)."""

    geometry: pin.GeometryModel
    missing: dict[str, str] = field(default_factory=dict)


def _package_dirs(urdf: Path) -> list[Path]:
    dirs = list(urdf.resolve().parents)[:4]
    dirs += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    try:
        dirs.append(example_robot_data_dir().parents[1])  # .../share
    except ToolkitError:
        pass
    return dirs


def _mesh_file(name: str, urdf: Path, dirs: list[Path]) -> Path | None:
    """The file a ``<mesh filename=...>`` names, if it exists."""
    if name.startswith("package://"):
        rest = name[len("package://") :]
        candidates = [d / rest for d in dirs]
    elif name.startswith("file://"):
        candidates = [Path(name[len("file://") :])]
    else:
        candidates = [urdf.parent / name]
    return next((c for c in candidates if c.is_file()), None)


_CAMERA_OR_LIGHT = re.compile(r"<instance_(?:camera|light)\b[^>]*/>")


def _without_cameras(mesh: Path) -> Path:
    """A COLLADA file's copy without its cameras and lights (exported from Blender they
    take over the viewer's camera and lighting); other meshes unchanged."""
    if mesh.suffix.lower() != ".dae":
        return mesh
    text = mesh.read_text(encoding="utf-8", errors="replace")
    cleaned = _CAMERA_OR_LIGHT.sub("", text)
    if cleaned == text:
        return mesh
    digest = hashlib.sha256(cleaned.encode("utf-8")).hexdigest()[:20]
    return cache.store(f"{mesh.stem}-{digest}.dae", lambda: cleaned)


def _bones(root: ET.Element, radius: float) -> None:
    """A thin cylinder along every joint offset, added to the parent link."""
    links = {link.get("name"): link for link in root.iter("link")}
    for joint in root.iter("joint"):
        parent = joint.find("parent")
        origin = joint.find("origin")
        if parent is None or origin is None or parent.get("link") not in links:
            continue
        offset = np.array([float(x) for x in (origin.get("xyz") or "0 0 0").split()])
        length = float(np.linalg.norm(offset))
        if length < 1e-6:
            continue
        rot = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), offset / length)
        rpy = pin.rpy.matrixToRpy(rot.matrix())
        visual = ET.SubElement(links[parent.get("link")], "visual")
        ET.SubElement(
            visual,
            "origin",
            xyz=" ".join(f"{v:.9g}" for v in offset / 2),
            rpy=" ".join(f"{v:.9g}" for v in rpy),
        )
        geometry = ET.SubElement(visual, "geometry")
        ET.SubElement(geometry, "cylinder", radius=f"{radius:.6g}", length=f"{length:.9g}")


def _substituted(urdf: Path, size: float) -> tuple[Path, dict[str, str]]:
    """A copy of the URDF with absolute mesh paths, COLLADA files without cameras, and
    undrawable meshes as spheres (plus bones); and what was replaced."""
    text = read_description(urdf)  # as the kinematic loader reads it
    try:
        root = ET.fromstring(re.sub(r"^<\?xml[^>]*\?>", "", text))
    except ET.ParseError as exc:
        raise ModelLoadError(f"{urdf}: not well-formed XML for the viewer ({exc})") from None
    dirs = _package_dirs(urdf)
    missing: dict[str, str] = {}
    for visual in root.iter("visual"):
        geometry = visual.find("geometry")
        mesh = geometry.find("mesh") if geometry is not None else None
        if geometry is None or mesh is None:
            continue
        name = mesh.get("filename", "")
        found = _mesh_file(name, urdf, dirs)
        if found is None:
            missing[name] = "file not found"
        elif found.suffix.lower() not in DRAWN_FORMATS:
            missing[name] = f"format {found.suffix} is not drawn (STL, DAE, OBJ are)"
        else:
            mesh.set("filename", str(_without_cameras(found)))
            continue
        geometry.remove(mesh)
        ET.SubElement(geometry, "sphere", radius=f"{0.03 * size:.6g}")
    if missing:
        _bones(root, 0.01 * size)
    text = ET.tostring(root, encoding="unicode")
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:20]
    return cache.store(f"{urdf.stem}-visuals-{digest}.urdf", lambda: text), missing


def frame_box(robot: Robot, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) corner of the box holding every frame origin at q (default: the
    neutral configuration) [m, base frame]."""
    robot = as_robot(robot)
    q = robot.joints.neutral() if q is None else robot.joints.check(q)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    points = np.array([placement.translation for placement in data.oMf])
    return points.min(axis=0), points.max(axis=0)


def _corners(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of the box [low, high]."""
    return np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                     for z in (low[2], high[2])])  # fmt: skip


def scene_box(
    robot: Robot, visuals: Visuals, q: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The box holding every frame origin and every visual shape at q [m, base frame]."""
    robot = as_robot(robot)
    if not isinstance(visuals, Visuals):
        raise InvalidParameterError(f"visuals must come from visual_model(), got {visuals!r:.80}")
    q = robot.joints.neutral() if q is None else robot.joints.check(q)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    points = [placement.translation for placement in data.oMf]
    gdata = pin.GeometryData(visuals.geometry)
    pin.updateGeometryPlacements(robot.model, data, visuals.geometry, gdata)  # joints as above
    for obj, placement in zip(visuals.geometry.geometryObjects, gdata.oMg, strict=True):
        try:
            obj.geometry.computeLocalAABB()
            box = obj.geometry.aabb_local
            lo, hi = np.asarray(box.min_), np.asarray(box.max_)
        except (AttributeError, RuntimeError):  # a shape without a box: its origin
            lo = hi = np.zeros(3)
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            continue
        points += list(_corners(lo, hi) @ placement.rotation.T + placement.translation)
    stacked = np.array(points)
    return stacked.min(axis=0), stacked.max(axis=0)


def camera_position(
    low: np.ndarray, high: np.ndarray, half_angle: float = np.radians(32.0)
) -> np.ndarray:
    """A camera position [m, base frame] looking at the base origin from the front right,
    slightly above, far enough that the whole box [low, high] is within ``half_angle`` of
    the line of sight (meshcat's camera orbits the origin; its vertical field is 75 deg)."""
    low = _validate.vector3(low, "low")
    high = _validate.vector3(high, "high")
    half_angle = _validate.number(half_angle, "half_angle [rad]", lower=0.01, upper=1.5)
    corners = _corners(low, high)
    direction = np.array([1.0, -1.0, 0.5]) / 1.5
    distance = max(float(np.abs(corners).max()), 0.05)
    for _ in range(200):
        eye = distance * direction
        rays = corners - eye
        cos = rays @ (-direction) / np.maximum(np.linalg.norm(rays, axis=1), 1e-12)
        if np.all(cos >= np.cos(half_angle)):
            break
        distance *= 1.05
    return distance * direction


def visual_model(robot: Robot) -> Visuals:
    """The visual geometry of ``robot`` (module doc); warns with
    :class:`MissingMeshWarning` naming every mesh it had to leave out."""
    robot = as_robot(robot)
    if robot.urdf_path is None:
        raise ModelLoadError(f"{robot.name}: no URDF file, so no visual shapes")
    low, high = frame_box(robot)
    size = max(float(np.linalg.norm(high - low)), 0.05)
    path, missing = _substituted(robot.urdf_path, size)
    try:  # every mesh of the copy is an absolute path: no package folders needed
        geometry = pin.buildGeomFromUrdf(robot.model, str(path), pin.GeometryType.VISUAL)
    except (ValueError, RuntimeError) as exc:
        raise ModelLoadError(f"{robot.name}: cannot load the visual shapes: {exc}") from exc
    if missing:
        listed = "; ".join(f"{name} ({why})" for name, why in list(missing.items())[:5])
        more = f" and {len(missing) - 5} more" if len(missing) > 5 else ""
        warnings.warn(
            f"{robot.name}: {len(missing)} mesh(es) drawn as primitive shapes: {listed}{more}",
            MissingMeshWarning,
            stacklevel=caller_level(),
        )
    return Visuals(geometry, missing)


def bones_model(robot: Robot, radius: float) -> pin.GeometryModel:
    """A stick figure of ``robot``: a cylinder of ``radius`` [m] along every joint offset and
    on to the tip frame, and a sphere at every joint (primitive shapes, which take any
    colour, where a description's meshes may keep their own)."""
    import coal

    model = robot.model
    shapes = pin.GeometryModel()
    ends = [(j, model.parents[j], model.jointPlacements[j].translation)
            for j in range(1, model.njoints)]  # fmt: skip
    tip = model.frames[robot.frames.id(None)]
    ends.append((-1, tip.parentJoint, tip.placement.translation))
    for j, parent, offset in ends:
        length = float(np.linalg.norm(offset))
        if j > 0:
            ball = pin.GeometryObject(
                f"joint_{j}", j, pin.SE3.Identity(), coal.Sphere(1.6 * radius)
            )
            shapes.addGeometryObject(ball)
        if length < 1e-6:
            continue
        turn = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), offset / length).matrix()
        placement = pin.SE3(turn, np.asarray(offset) / 2)
        bone = coal.Cylinder(radius, length)
        shapes.addGeometryObject(
            pin.GeometryObject(f"bone_{j}_{parent}", int(parent), placement, bone)
        )
    return shapes
