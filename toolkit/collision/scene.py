"""Scenes of obstacles and attached objects, as plain data (see :mod:`toolkit.collision`)."""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import tables as _tables
from ..common import validate as _validate
from ..errors import InvalidParameterError, ModelLoadError, ToolkitError

__all__ = [
    "KINDS",
    "MAX_POINTS",
    "SUPPORT_SLACK",
    "CheckerTimeout",
    "CollisionGeometryWarning",
    "Scene",
    "SceneObject",
]

KINDS = ("box", "sphere", "cylinder", "floor", "mesh", "points")
FIELDS = ("name", "kind", "size", "pose", "path", "link", "support", "points")  # of a file's object

MAX_POINTS = 1_000_000
"""The most points one point cloud takes (a depth camera frame is ~300,000)."""


class CheckerTimeout(ToolkitError, TimeoutError):
    """Building a scene's checker passed the time it was given (:meth:`toolkit.Robot.plan`
    gives its ``time_limit``): the message says how many of the scene's objects it had."""


class CollisionGeometryWarning(UserWarning):
    """A robot's links have no collision geometry: its visual shapes stand in."""


def _pose(value: ArrayLike | None, what: str) -> tuple[float, ...]:
    """A 4x4 pose (or a 3-vector position, or None: identity) as 16 row-major floats."""
    if value is None:
        return tuple(np.eye(4).ravel().tolist())
    arr = _validate.real_array(value, what)
    if arr.shape == (3,):
        T = np.eye(4)
        T[:3, 3] = arr
        arr = T
    arr = _validate.pose(arr, what, "a finite 4x4 pose or a 3-vector position")
    return tuple(float(v) for v in arr.ravel())


MAX_SCENE_BYTES = 128 << 20
"""The largest scene file :meth:`Scene.load` reads [bytes] (a scene of a thousand objects is
a few hundred kB; meshes are files it names, not content; a point cloud's points take ~65
bytes each, so :data:`MAX_POINTS` fit)."""

SUPPORT_SLACK = 0.005
"""[m] How far the shapes fixed to a robot's base may reach into a support (a floor, a box
added with ``support=True``) without colliding: meshes are drawn a few millimetres past
their mounting face (the UR5's base 3 mm)."""

FLOOR = (1000.0, 1000.0, 500.0)
"""A floor's shape [m]: a slab whose top is the floor's plane, 500 m deep and 1 km wide,
the half-space below the plane for any arm that can stand on it."""


@dataclass(frozen=True)
class SceneObject:
    """One object: ``kind`` (box, sphere, cylinder, floor, mesh, points), ``size`` [m] (box:
    x, y, z; sphere: radius; cylinder: radius, length along z; floor: none; mesh: scale x,
    y, z; points: the edge of the octree's cells), ``points`` (a point cloud's (N, 3)
    points [m] in its frame, as float64 bytes),
    ``pose`` (16 row-major floats, in the base frame, or in ``link``'s frame when
    attached), ``path`` (a mesh file), ``link`` (the link it is attached to, or "") and
    ``support``: the robot stands on it (a floor always does), so the shapes fixed to the
    robot's base may touch it and reach :data:`SUPPORT_SLACK` into it; deeper is a
    collision, and the moving links are checked against it like against any object."""

    name: str
    kind: str
    size: tuple[float, ...]
    pose: tuple[float, ...]
    path: str = ""
    link: str = ""
    support: bool = False
    points: bytes = field(default=b"", repr=False)

    @property
    def cloud(self) -> np.ndarray:
        """A point cloud's points (N, 3) [m] in its own frame (a read-only view)."""
        return np.frombuffer(self.points, dtype="<f8").reshape(-1, 3)

    @property
    def placement(self) -> pin.SE3:
        T = np.array(self.pose).reshape(4, 4)
        return pin.SE3(T[:3, :3], T[:3, 3])

    @property
    def shape_placement(self) -> pin.SE3:
        """Where :meth:`shape` sits: the pose, or for a floor the slab under its plane."""
        if self.kind != "floor":
            return self.placement
        return self.placement * pin.SE3(np.eye(3), np.array([0.0, 0.0, -FLOOR[2] / 2]))

    def shape(self) -> Any:
        """The coal collision geometry."""
        import coal

        if self.kind == "box":
            return coal.Box(*self.size)
        if self.kind == "sphere":
            return coal.Sphere(self.size[0])
        if self.kind == "cylinder":
            return coal.Cylinder(self.size[0], self.size[1])
        if self.kind == "floor":  # the half-space below z = 0 of its pose, within any reach
            return coal.Box(*FLOOR)  # (coal's half-space tests against meshes cost 6x more)
        if self.kind == "points":  # every cell of edge size[0] holding a point is occupied
            return coal.makeOctree(np.array(self.cloud), self.size[0])
        kept = self.__dict__.get("_mesh")
        if kept is not None:  # loaded once (a 2-million-triangle file: 7 s), then shared
            return kept
        loader = coal.MeshLoader()
        try:
            mesh = loader.load(self.path, np.array(self.size))
        except Exception as exc:  # assimp's errors come as several kinds
            raise ModelLoadError(
                f"scene object {self.name!r}: cannot load {self.path}: {exc}"
            ) from None
        self.__dict__["_mesh"] = mesh  # the mesh as the scene took it (checkers only read it)
        return mesh

    def __getstate__(self) -> dict[str, Any]:
        """What pickles: the fields, not a loaded mesh (loaded again where unpickled)."""
        return {k: v for k, v in self.__dict__.items() if k != "_mesh"}


@dataclass
class Scene:
    """Obstacles around a robot, and objects attached to its links (plain data)."""

    objects: list[SceneObject] = field(default_factory=list)

    # ------------------------------------------------------------------ building
    def _add(self, obj: SceneObject) -> Scene:
        if not isinstance(obj.name, str) or not obj.name or obj.name.startswith("_"):
            raise InvalidParameterError(f"a scene object needs a name (text), got {obj.name!r}")
        names = self._names()
        if obj.name in names and any(o.name == obj.name for o in self.objects):
            raise InvalidParameterError(f"the scene already has an object named {obj.name!r}")
        obj.shape()  # a mesh that cannot be loaded is refused now, not at the first check
        self.objects.append(obj)
        names.add(obj.name)
        self.__dict__["_kept_names"] = (len(self.objects), names)
        return self

    def _names(self) -> set[str]:
        """The objects' names, kept between adds (made again where the list's length
        changed under it; a name found is checked on the list itself, so an object
        written into the list directly is never refused by a name it no longer has)."""
        kept: tuple[int, set[str]] | None = self.__dict__.get("_kept_names")
        if kept is None or kept[0] != len(self.objects):
            kept = (len(self.objects), {o.name for o in self.objects})
            self.__dict__["_kept_names"] = kept
        return kept[1]

    @staticmethod
    def _sizes(values: ArrayLike, n: int, what: str) -> tuple[float, ...]:
        arr = _validate.real_array(values, what).ravel()
        if arr.shape != (n,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise InvalidParameterError(f"{what} must be {n} finite value(s) > 0 [m]")
        return tuple(float(v) for v in arr)

    def add_box(
        self, name: str, size: ArrayLike, pose: ArrayLike | None = None, *, support: bool = False
    ) -> Scene:
        """A box of edges ``size`` (x, y, z) [m] centred at ``pose``; ``support``: the robot
        stands on it (a table it is mounted on; see :class:`SceneObject`)."""
        sizes = self._sizes(size, 3, "box size")
        support = _validate.flag(support, "support")
        return self._add(SceneObject(name, "box", sizes, _pose(pose, "pose"), support=support))

    def add_sphere(self, name: str, radius: float, pose: ArrayLike | None = None) -> Scene:
        """A sphere of ``radius`` [m] centred at ``pose``."""
        size = self._sizes([radius], 1, "sphere radius")
        return self._add(SceneObject(name, "sphere", size, _pose(pose, "pose")))

    def add_cylinder(
        self, name: str, radius: float, length: float, pose: ArrayLike | None = None
    ) -> Scene:
        """A cylinder of ``radius`` and ``length`` [m] along the z axis of ``pose``."""
        size = self._sizes([radius, length], 2, "cylinder radius and length")
        return self._add(SceneObject(name, "cylinder", size, _pose(pose, "pose")))

    def add_floor(self, z: float = 0.0, name: str = "floor") -> Scene:
        """Everything below the horizontal plane at height ``z`` [m]."""
        height = _validate.number(z, "floor z [m]")
        pose = _pose([0.0, 0.0, height], "pose")
        return self._add(SceneObject(name, "floor", (), pose, support=True))

    def add_mesh(
        self, name: str, path: str | Path, pose: ArrayLike | None = None, scale: ArrayLike = 1.0
    ) -> Scene:
        """A mesh file (STL, DAE, OBJ, ...) placed at ``pose``, scaled by ``scale``."""
        if not isinstance(path, str | Path) or not Path(path).is_file():
            raise InvalidParameterError(f"mesh file not found: {path!r:.200}")
        factors = np.broadcast_to(_validate.real_array(scale, "scale"), (3,))
        size = self._sizes(factors, 3, "mesh scale")
        obj = SceneObject(name, "mesh", size, _pose(pose, "pose"), str(Path(path).resolve()))
        return self._add(obj)

    def add_points(
        self, name: str, points: ArrayLike, resolution: float = 0.01, pose: ArrayLike | None = None
    ) -> Scene:
        """A point cloud (N, 3) [m] (a depth camera's, in the frame of ``pose``) as an
        obstacle: the cells of an octree of edge ``resolution`` [m] that hold a point, each
        cell a solid cube (coal's ``OcTree``). Every point lies inside the obstacle, the
        surface it stands for is widened by up to one cell (sqrt(3) ``resolution`` at a
        corner), and a gap narrower than a cell may close. At most :data:`MAX_POINTS`
        points, each finite."""
        arr = _validate.real_array(points, "points")
        if arr.ndim != 2 or arr.shape[1] != 3 or not 1 <= len(arr) <= MAX_POINTS:
            raise InvalidParameterError(
                f"points must have shape (N, 3) with 1 <= N <= {MAX_POINTS}, got {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            rows = np.flatnonzero(~np.isfinite(arr).all(axis=1))[:5].tolist()
            raise InvalidParameterError(f"points has NaN or infinite entries (rows {rows})")
        size = self._sizes([resolution], 1, "point cloud resolution")
        data = np.ascontiguousarray(arr, dtype="<f8").tobytes()
        return self._add(SceneObject(name, "points", size, _pose(pose, "pose"), points=data))

    def attach(
        self, name: str, link: str, shape: str, size: ArrayLike, pose: ArrayLike | None = None
    ) -> Scene:
        """A tool or a held part fixed to ``link`` (a box, sphere or cylinder, ``size`` as
        for those, ``pose`` in the link's frame): checked against the other links and the
        scene, never against its own link."""
        counts = {"box": 3, "sphere": 1, "cylinder": 2}
        if shape not in counts:
            raise InvalidParameterError(f"attach takes a box, sphere or cylinder, got {shape!r}")
        if not isinstance(link, str) or not link:
            raise InvalidParameterError(f"link must be a link name, got {link!r}")
        sizes = self._sizes(size, counts[shape], f"{shape} size")
        return self._add(SceneObject(name, shape, sizes, _pose(pose, "pose"), link=link))

    # ------------------------------------------------------------------ plain data
    def __iter__(self) -> Iterator[SceneObject]:
        return iter(self.objects)

    def __len__(self) -> int:
        return len(self.objects)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready description (what :meth:`save` writes)."""
        out = []
        for o in self.objects:
            item: dict[str, Any] = {"name": o.name, "kind": o.kind}
            if o.size:
                item["size"] = list(o.size)
            item["pose"] = np.array(o.pose).reshape(4, 4).tolist()
            if o.path:
                item["path"] = o.path
            if o.link:
                item["link"] = o.link
            if o.support and o.kind != "floor":
                item["support"] = True
            if o.kind == "points":
                item["points"] = o.cloud.tolist()
            out.append(item)
        return {"objects": out}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scene:
        """The scene of a :meth:`to_dict` description (checked like the ``add_`` calls)."""
        if not isinstance(data, Mapping) or not isinstance(data.get("objects"), list):
            raise InvalidParameterError("a scene is {'objects': [{name, kind, size, pose}, ...]}")
        unknown = sorted(str(k) for k in data if k != "objects")
        if unknown:
            raise InvalidParameterError(f"a scene has only 'objects'; unknown field(s) {unknown}")
        scene = cls()
        for i, item in enumerate(data["objects"]):
            where = f"scene objects[{i}]"
            if not isinstance(item, Mapping):
                raise InvalidParameterError(f"{where}: an object is a mapping, got {item!r:.80}")
            where += f" ({item.get('name')!r})"
            extra = sorted(str(k) for k in item if k not in FIELDS)
            if extra:
                raise InvalidParameterError(
                    f"{where}: unknown field(s) {', '.join(map(repr, extra))}; an object has "
                    f"{', '.join(FIELDS)} (docs/collision.md, 'Scene files')"
                )
            name, kind, pose = item.get("name"), item.get("kind"), item.get("pose")
            try:
                size = list(np.ravel(item.get("size", ())))
                scene._from_item(name, kind, size, pose, item)
            except InvalidParameterError as exc:
                raise InvalidParameterError(f"{where}: {exc}") from None
        return scene

    def _from_item(
        self, name: Any, kind: Any, size: list[Any], pose: Any, item: Mapping[str, Any]
    ) -> None:
        if item.get("link"):
            self.attach(name, item["link"], kind, size, pose)
        elif kind == "box":
            self.add_box(name, size, pose, support=item.get("support", False))
        elif kind in ("sphere", "cylinder") and len(size) != (1 if kind == "sphere" else 2):
            want = "[radius]" if kind == "sphere" else "[radius, length]"
            raise InvalidParameterError(
                f"size: a {kind} takes {want} [m], got {[float(v) for v in size]}"
            )
        elif kind == "sphere":
            self.add_sphere(name, size[0], pose)
        elif kind == "cylinder":
            self.add_cylinder(name, size[0], size[1], pose)
        elif kind == "floor":
            self.add_floor(_pose(pose, "pose")[11] if pose is not None else 0.0, name)
        elif kind == "mesh":
            self.add_mesh(name, item.get("path", ""), pose, size or 1.0)
        elif kind == "points":
            if len(size) != 1:
                raise InvalidParameterError("size: a point cloud takes [resolution] [m]")
            self.add_points(name, item.get("points", ()), size[0], pose)
        else:
            raise InvalidParameterError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")

    def save(self, path: str | Path) -> None:
        """Write the scene as JSON."""
        Path(path).write_text(json.dumps(self.to_dict(), indent=2), encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path) -> Scene:
        """Read a scene written by :meth:`save` (or by hand): a regular file of at most
        :data:`MAX_SCENE_BYTES`."""
        try:
            raw = _tables.read_regular(path, MAX_SCENE_BYTES, "a scene (JSON)")
            data = json.loads(raw.decode("utf-8-sig"))
        except (OSError, ValueError) as exc:
            raise InvalidParameterError(f"cannot read a scene from {path}: {exc}") from None
        try:
            return cls.from_dict(data)
        except InvalidParameterError as exc:
            raise InvalidParameterError(f"{path}: {exc}") from None

    def digest(self) -> str:
        """A short digest of the scene (part of a map store's identity, and the key of a
        robot's checker for it): kept with the objects it was made of, and made again
        where the list holds other objects (the objects themselves cannot change)."""
        import hashlib

        objects = tuple(self.objects)
        kept = self.__dict__.get("_digest")
        if (
            kept is not None
            and len(kept[0]) == len(objects)
            and all(a is b for a, b in zip(kept[0], objects, strict=True))
        ):  # the very objects (held here, so no other object can take their place)
            return str(kept[1])
        made = hashlib.sha256(json.dumps(self.to_dict(), sort_keys=True).encode()).hexdigest()
        self.__dict__["_digest"] = (objects, made[:16])
        return made[:16]
