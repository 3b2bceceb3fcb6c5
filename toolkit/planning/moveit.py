"""MoveIt's formats, read and written as YAML: a planning scene (``moveit_msgs/PlanningScene``)
into a :class:`~toolkit.collision.Scene`, a motion plan request
(``moveit_msgs/MotionPlanRequest``) into a :class:`~toolkit.planning.MotionRequest`, and a
plan out as a joint trajectory (``moveit_msgs/RobotTrajectory``), as MotionBenchMaker ships
its problems and ``ros2 topic echo`` prints the messages.

* **Scenes**: ``world.collision_objects`` (or ``planning_scene_world.collision_objects``,
  or a bare ``collision_objects`` list; a file with none of these is refused), each
  with its ``primitives`` and ``primitive_poses`` (box, sphere, cylinder; a cone is
  checked as the cylinder around it, which is conservative), ``meshes`` and ``mesh_poses``
  (triangles kept in the verified cache as STL) and ``planes`` (a horizontal plane with its
  normal up is a floor), placed by the object's ``pose`` where given; and
  ``robot_state.attached_collision_objects`` (primitives in their link's frame) attached
  to their link. A pose is ``{position: {x, y, z}, orientation: {x, y, z, w}}`` or lists
  ``[x, y, z]`` and ``[x, y, z, w]``; a primitive's type is a name or MoveIt's number
  (1 box, 2 sphere, 3 cylinder, 4 cone). An object's ``header.frame_id`` places it: a
  frame fixed to the robot's base (:func:`fixed_frames`: the world, the base link) by that
  frame's pose; any other frame is refused rather than misplaced. The allowed-collision
  matrix is not read (the description's SRDF decides which links are never checked).
* **Requests** (:mod:`toolkit.planning.requests`): ``start_state.joint_state``,
  ``goal_constraints`` (each a set of joint constraints, or one position and one
  orientation constraint on a link: a tool pose; several constraint sets are several
  goals, any of which ends the plan), ``allowed_planning_time`` and ``group_name``.
* **Trajectories** (the same module): ``joint_trajectory`` with ``joint_names`` and
  ``points`` (positions, velocities, accelerations, ``time_from_start`` as
  ``{sec, nanosec}``).

Every reader refuses what it cannot represent with an
:class:`~toolkit.errors.InvalidParameterError` naming the file and the field (a file of at
most :data:`MAX_YAML_BYTES`, read as YAML's safe subset: no object is built from the
file's tags).
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..collision import Scene
from ..common import cache
from ..common import tables as _tables
from ..common import validate as _validate
from ..errors import InvalidParameterError

__all__ = [
    "MAX_YAML_BYTES",
    "fixed_frames",
    "listed",
    "load_yaml",
    "numbers",
    "pose_of",
    "read_scene",
]

MAX_YAML_BYTES = 64 * 1024 * 1024
_TYPES = {1: "box", 2: "sphere", 3: "cylinder", 4: "cone"}
_DIMENSIONS = {"box": 3, "sphere": 1, "cylinder": 2, "cone": 2}
_ADD = (None, 0, "0", "ADD", "add", b"\x00", "\x00")


def load_yaml(source: object, what: str) -> tuple[Mapping[str, Any], str]:
    """(the YAML document, how to name it in messages) of a file path or a mapping."""
    if isinstance(source, Mapping):
        return source, what
    if not isinstance(source, str | os.PathLike):
        raise InvalidParameterError(f"{what}: a YAML file or a mapping, got {source!r:.80}")
    import yaml

    try:
        raw = _tables.read_regular(os.fspath(source), MAX_YAML_BYTES, what)
        data = yaml.safe_load(raw.decode("utf-8-sig"))
    except FileNotFoundError:
        raise InvalidParameterError(f"no such file: {source}") from None
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise InvalidParameterError(f"cannot read {what} from {source}: {exc}") from None
    if not isinstance(data, Mapping):
        raise InvalidParameterError(
            f"{source}: {what} is a YAML mapping, got {type(data).__name__}"
        )
    return data, str(source)


def numbers(value: object, count: int | None, where: str) -> np.ndarray:
    """A finite float vector (of ``count`` values) from a list or an {x, y, z[, w]} map."""
    if isinstance(value, Mapping):
        keys = "xyzw"[: count or 3]
        value = [value.get(k, 0.0 if k != "w" else 1.0) for k in keys]
    try:
        arr = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{where}: numbers expected, got {value!r:.80}") from None
    if (count is not None and arr.shape != (count,)) or not np.isfinite(arr).all():
        raise InvalidParameterError(f"{where}: {count} finite numbers expected, got {value!r:.80}")
    return arr


def pose_of(value: object, where: str) -> np.ndarray:
    """A 4x4 pose of a ``geometry_msgs/Pose`` (maps or lists; None: identity)."""
    T = np.eye(4)
    if value is None:
        return T
    if not isinstance(value, Mapping):
        raise InvalidParameterError(
            f"{where}: a pose is {{position, orientation}}, got {value!r:.80}"
        )
    T[:3, 3] = numbers(value.get("position", [0, 0, 0]), 3, f"{where}.position")
    x, y, z, w = numbers(value.get("orientation", [0, 0, 0, 1]), 4, f"{where}.orientation")
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if norm < 1e-9:
        raise InvalidParameterError(f"{where}.orientation: a zero quaternion is no rotation")
    T[:3, :3] = pin.Quaternion(w / norm, x / norm, y / norm, z / norm).toRotationMatrix()
    return T


Frames = Mapping[str, np.ndarray] | None


def _frame(item: Mapping[str, Any], frames: Frames, where: str) -> tuple[str, np.ndarray]:
    """(the frame id of ``item``'s header, that frame's pose in the base frame)."""
    header = item.get("header") or {}
    frame = str(header.get("frame_id", "") if isinstance(header, Mapping) else "").lstrip("/")
    if frames is None:
        return frame, np.eye(4)
    if frame not in frames:
        raise InvalidParameterError(
            f"{where}: given in frame {frame!r}, not one fixed to the base "
            f"({', '.join(repr(f) for f in sorted(frames))})"
        )
    return frame, frames[frame]


def fixed_frames(robot: Any) -> dict[str, np.ndarray]:
    """The frames of ``robot`` fixed to its base (the world, the base link, ...) with their
    poses in the base frame, and "" for the base frame itself: the ``frames`` that
    :func:`read_scene` places objects by."""
    out = {"": np.eye(4)}
    for frame in robot.model.frames:
        if frame.parentJoint == 0:
            out.setdefault(frame.name, np.asarray(frame.placement.homogeneous, dtype=float))
    return out


def _frames(frames: object) -> Frames:
    """``read_scene``'s ``frames`` as {name: pose}: None, names (each the base frame) or a
    mapping of names to 4x4 poses."""
    if frames is None:
        return None
    if isinstance(frames, Mapping):
        return {str(name): _validate.pose(T, f"frames[{name!r}]") for name, T in frames.items()}
    if isinstance(frames, str) or not isinstance(frames, Collection):
        raise InvalidParameterError(f"frames: names or {{name: 4x4 pose}}, got {frames!r:.80}")
    return {str(name): np.eye(4) for name in frames}


def listed(item: Mapping[str, Any], key: str, where: str) -> list[Any]:
    value = item.get(key) or []
    if not isinstance(value, list):
        raise InvalidParameterError(f"{where}.{key}: a list, got {value!r:.80}")
    return value


def _primitive(prim: object, where: str) -> tuple[str, list[float]]:
    """(kind, toolkit size) of a ``shape_msgs/SolidPrimitive``."""
    if not isinstance(prim, Mapping):
        raise InvalidParameterError(f"{where}: a primitive is {{type, dimensions}}")
    kind = prim.get("type")
    kind = _TYPES.get(kind, kind) if isinstance(kind, int) else str(kind).lower()
    if kind not in _DIMENSIONS:
        raise InvalidParameterError(f"{where}.type: box, sphere, cylinder or cone, got {kind!r}")
    d = numbers(prim.get("dimensions"), _DIMENSIONS[kind], f"{where}.dimensions ({kind})")
    if kind == "box" or kind == "sphere":
        return kind, d.tolist()
    return "cylinder", [float(d[1]), float(d[0])]  # MoveIt: (height, radius); a cone inside


def _mesh_file(mesh: object, where: str) -> Path:
    """A ``shape_msgs/Mesh`` as an ASCII STL in the verified cache (named by its content)."""
    if not isinstance(mesh, Mapping):
        raise InvalidParameterError(f"{where}: a mesh is {{triangles, vertices}}")
    vertices = listed(mesh, "vertices", where)
    V = np.array([numbers(v, 3, f"{where}.vertices[{i}]") for i, v in enumerate(vertices)])
    V = V.reshape(-1, 3)
    tris = []
    for i, t in enumerate(listed(mesh, "triangles", where)):
        idx = t.get("vertex_indices") if isinstance(t, Mapping) else t
        ijk = numbers(idx, 3, f"{where}.triangles[{i}]")
        if (ijk != np.round(ijk)).any() or ijk.min() < 0 or ijk.max() >= len(V):
            raise InvalidParameterError(f"{where}.triangles[{i}]: indices into {len(V)} vertices")
        tris.append(ijk.astype(int))
    if not tris:
        raise InvalidParameterError(f"{where}: a mesh without triangles")
    lines = ["solid moveit"]
    for a, b, c in tris:
        lines += ["facet normal 0 0 0", " outer loop"]
        lines += [
            f"  vertex {float(V[k, 0])!r} {float(V[k, 1])!r} {float(V[k, 2])!r}" for k in (a, b, c)
        ]
        lines += [" endloop", "endfacet"]
    text = "\n".join([*lines, "endsolid moveit", ""])
    digest = hashlib.sha256(text.encode()).hexdigest()[:24]
    return cache.store(f"moveit-mesh-{digest}.stl", lambda: text)


def _add_object(
    scene: Scene, obj: Mapping[str, Any], where: str, frames: Frames, link: str = ""
) -> None:
    if obj.get("operation") not in _ADD:
        raise InvalidParameterError(
            f"{where}.operation: only ADD is read, got {obj['operation']!r}"
        )
    frame, placed = _frame(obj, None if link else frames, where)
    if link and frame not in ("", link):
        raise InvalidParameterError(f"{where}: attached to {link!r} but given in frame {frame!r}")
    name = str(obj.get("id") or f"object{len(scene)}")
    base = placed @ pose_of(obj.get("pose"), f"{where}.pose")
    prims, poses = listed(obj, "primitives", where), listed(obj, "primitive_poses", where)
    meshes, mesh_poses = listed(obj, "meshes", where), listed(obj, "mesh_poses", where)
    if len(prims) != len(poses) or len(meshes) != len(mesh_poses):
        raise InvalidParameterError(f"{where}: one pose per primitive and per mesh")
    single = len(prims) + len(meshes) + len(listed(obj, "planes", where)) == 1
    for k, (prim, p) in enumerate(zip(prims, poses, strict=True)):
        kind, size = _primitive(prim, f"{where}.primitives[{k}]")
        T = base @ pose_of(p, f"{where}.primitive_poses[{k}]")
        label = name if single else f"{name}_{k}"
        if link:
            scene.attach(label, link, kind, size, T)
        elif kind == "box":
            scene.add_box(label, size, T)
        elif kind == "sphere":
            scene.add_sphere(label, size[0], T)
        else:
            scene.add_cylinder(label, size[0], size[1], T)
    for k, (mesh, p) in enumerate(zip(meshes, mesh_poses, strict=True)):
        if link:
            raise InvalidParameterError(f"{where}.meshes: an attached mesh is not read")
        T = base @ pose_of(p, f"{where}.mesh_poses[{k}]")
        scene.add_mesh(
            name if single else f"{name}_mesh{k}", _mesh_file(mesh, f"{where}.meshes[{k}]"), T
        )
    for k, plane in enumerate(listed(obj, "planes", where)):
        coef = plane.get("coef") if isinstance(plane, Mapping) else plane
        a, b, c, d = numbers(coef, 4, f"{where}.planes[{k}]")
        n = (base[:3, :3] @ [a, b, c]) / max(math.sqrt(a * a + b * b + c * c), 1e-300)
        if link or abs(n[0]) > 1e-9 or abs(n[1]) > 1e-9 or n[2] <= 0:
            raise InvalidParameterError(
                f"{where}.planes[{k}]: only a horizontal plane with its normal up (a floor) is read"
            )
        height = -d / math.sqrt(a * a + b * b + c * c) + base[2, 3]
        scene.add_floor(height, name if single else f"{name}_plane{k}")


def read_scene(source: object, *, frames: object = None) -> Scene:
    """The obstacles of a MoveIt planning scene (module doc): a YAML file, or its mapping.
    ``frames``: the frame ids an object's ``header.frame_id`` may name, as names (each the
    base frame) or {name: 4x4 pose in the base frame} (:func:`fixed_frames` of a robot);
    an object in any other frame is refused. None: every object is taken in the base
    frame, whatever its frame id."""
    placed = _frames(frames)
    data, label = load_yaml(source, "a MoveIt planning scene")
    keys = ("world", "planning_scene_world", "collision_objects", "robot_state")
    if not any(key in data for key in keys):
        raise InvalidParameterError(
            f"{label}: no MoveIt planning scene: none of {', '.join(keys)} is in it "
            f"(its keys: {', '.join(map(str, list(data)[:8])) or 'none'})"
        )
    world = data.get("world", data.get("planning_scene_world", data))
    if not isinstance(world, Mapping):
        raise InvalidParameterError(f"{label}: world is a mapping")
    scene = Scene()
    try:
        for i, obj in enumerate(listed(world, "collision_objects", "world")):
            if not isinstance(obj, Mapping):
                raise InvalidParameterError(f"world.collision_objects[{i}]: a mapping")
            _add_object(scene, obj, f"world.collision_objects[{i}] ({obj.get('id')!r})", placed)
        state = data.get("robot_state") or {}
        attached = state.get("attached_collision_objects") if isinstance(state, Mapping) else None
        for i, item in enumerate(attached or []):
            where = f"robot_state.attached_collision_objects[{i}]"
            if not isinstance(item, Mapping) or not isinstance(item.get("object"), Mapping):
                raise InvalidParameterError(f"{where}: {{link_name, object}}")
            link = str(item.get("link_name") or "")
            if not link:
                raise InvalidParameterError(f"{where}.link_name: the link it is attached to")
            _add_object(scene, item["object"], f"{where}.object", placed, link=link)
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"{label}: {exc}") from None
    return scene
