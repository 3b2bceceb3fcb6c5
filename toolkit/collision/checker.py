"""The collision checker of one robot and one scene (see :mod:`toolkit.collision`): coal's
exact checks behind a compiled pre-filter (:mod:`toolkit.collision.bounds`)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np
import pinocchio as pin

from ..errors import FrameNotFoundError, InvalidParameterError
from ..kinematics import Backend, CompiledBackend, Frames, JointLayout, parallel
from .bound_kernels import CLOSE, HIT, NEAR
from .bounds import Bounds, PackedCovers, Rows, placed_boxes, shape_rows
from .broad import robot_reach, within_reach
from .parts import PART, Parts, exact_requests
from .scene import SUPPORT_SLACK, CheckerTimeout, Scene
from .shapes import robot_geometry

__all__ = ["Checker", "CollisionSubject", "RobotShapes", "exact_requests", "robot_geometry"]


@runtime_checkable
class CollisionSubject(Protocol):
    """What a checker needs of a robot (a :class:`~toolkit.robot.Robot`): its model, the
    description its shapes come from, its frames, its kinematics back end."""

    model: pin.Model
    name: str
    urdf_path: Path | None
    srdf_path: Path | None

    kinematics: Backend
    joints: JointLayout
    frames: Frames

    def random_q(self, n: int | None = None, seed: int | None = None) -> np.ndarray: ...


TOUCH = 1e-6
"""[m] Two fixed shapes (one on the base, one of the scene) collide when one enters the other
deeper than this: resting on each other (a box on a floor slab of the description) is not a
collision; a base 2 mm inside a table is."""


class RobotShapes(NamedTuple):
    """A robot's shapes as every checker of it starts from (:meth:`Checker._robot_shapes`):
    ``geom`` (never changed: a checker adds its scene to a copy), per joint its nearest
    shaped ancestor, each shape's link name."""

    geom: pin.GeometryModel
    shaped_parent: tuple[int, ...]
    names: tuple[str, ...]
    rows: Rows | None = None
    """The shapes' rows of the collision pre-filter (:func:`~toolkit.collision.bounds.shape_rows`,
    on a compiled back end; None: none)."""
    reach: tuple[np.ndarray, float] | None = None
    """The sphere no point of the robot leaves (:func:`~toolkit.collision.broad.robot_reach`;
    None where there is none), made with the shapes, not per checker (0.8 ms a checker on
    MotionBenchMaker's Panda)."""


class Checker:
    """Exact collision queries of one robot among the objects of one scene."""

    def __init__(
        self, robot: CollisionSubject, scene: Scene | None, *, srdf: bool = True,
        robot_covers: Callable[[Callable[[], PackedCovers]], PackedCovers] | None = None,
        robot_shapes: Callable[[bool, Callable[[], RobotShapes]], RobotShapes] | None = None,
        until: Callable[[], bool] | None = None,
    ) -> None:  # fmt: skip
        """``robot_covers`` and ``robot_shapes``: where the robot keeps what its checkers of
        every scene share (its shapes' sphere covers; its shapes and checked pairs, per
        ``srdf``), called with the function that makes it; None: made for this checker.
        ``until``: asked between the scene's objects and before the pre-filter, True stops
        the build (:class:`~toolkit.collision.scene.CheckerTimeout`). More than
        :data:`~toolkit.collision.parts.PART` fixed objects within reach are held in parts
        (:mod:`toolkit.collision.parts`)."""
        model = robot.model
        self.model = model
        shapes = (robot_shapes(srdf, lambda: self._robot_shapes(robot, srdf))
                  if robot_shapes is not None else self._robot_shapes(robot, srdf))  # fmt: skip
        geom = shapes.geom.copy()  # the meshes shared, the pairs and objects this checker's
        self.robot_count = geom.ngeoms
        self.shaped_parent = list(shapes.shaped_parent)
        self.names = list(shapes.names)
        self._static: list[tuple[int, int, bool]] = []
        self._joints = [int(g.parentJoint) for g in geom.geometryObjects]  # each shape's joint
        reach = shapes.reach
        self.out_of_reach: list[str] = []  # fixed objects the robot never nears: unchecked
        objects = list(scene or ())
        if sum(not obj.link for obj in objects) > PART:  # parts: attached ones first, in each
            objects = [obj for obj in objects if obj.link] + [o for o in objects if not o.link]
        shared = sum(bool(obj.link) for obj in objects)
        parts = [geom]
        for n, obj in enumerate(objects):
            if until is not None and until():
                raise CheckerTimeout(
                    f"{robot.name}: the scene's checker was stopped at its "
                    f"time limit, {n} of {len(objects)} objects in"
                )
            shape = obj.shape()
            if not obj.link and not within_reach(reach, shape, obj.shape_placement):
                self.out_of_reach.append(obj.name)
                continue
            if parts[-1].ngeoms - self.robot_count - shared == PART:  # (attached: fewer)
                parts.append(self._part(shapes.geom, geom, shared))
            self._add_object(robot, parts[-1], obj, shape)
        self.geom = geom
        """The first part (module :mod:`~toolkit.collision.parts`): the robot's shapes and
        pairs, and the scene's objects (the first :data:`~toolkit.collision.parts.PART`)."""
        self.parts = Parts(model, parts, self.robot_count, shared if len(parts) > 1 else 0)
        self._static_gap = self._static_gaps()
        self.base_hits = self._static_pairs()
        if until is not None and until():  # the pre-filter's rows are the build's too
            raise CheckerTimeout(f"{robot.name}: the scene's checker was stopped at its time "
                                 f"limit, its {len(self.names) - self.robot_count} objects in "
                                 "but not its pre-filter")  # fmt: skip
        backend = robot.kinematics
        self.bounds = (Bounds(self.parts.shapes, backend, self.robot_count, robot_covers,
                              shapes.rows)
                       if isinstance(backend, CompiledBackend) else None)  # fmt: skip

    def _part(self, robot: pin.GeometryModel, first: pin.GeometryModel, shared: int) -> Any:
        """A new part: the robot's shapes without their pairs (the first part has them) and
        copies of the first part's ``shared`` attached objects (paired with the part's
        fixed objects as those are added)."""
        part = robot.copy()
        part.removeAllCollisionPairs()
        count = self.robot_count
        for obj in list(first.geometryObjects)[count : count + shared]:
            part.addGeometryObject(obj.copy())
        return part

    def _robot_shapes(self, robot: CollisionSubject, srdf: bool) -> RobotShapes:
        """The robot's shapes with the pairs checked among them (adjacent links dropped,
        visual stand-ins touching at rest dropped, the SRDF's disabled pairs dropped)."""
        geom, visual = robot_geometry(robot)
        geom.addAllCollisionPairs()
        self.shaped_parent = self._shaped_parents(geom)
        self._drop_adjacent(geom)
        if visual:  # visual shapes overlap at the joints: what touches at rest is design
            self._drop_touching(geom, robot.joints.neutral())
        if srdf and robot.srdf_path is not None:
            pin.removeCollisionPairs(self.model, geom, str(robot.srdf_path))
        names = tuple(self._link_name(g) for g in geom.geometryObjects)
        backend = robot.kinematics
        rows = (shape_rows(geom.geometryObjects, backend)
                if isinstance(backend, CompiledBackend) else None)  # fmt: skip
        return RobotShapes(geom, tuple(self.shaped_parent), names, rows,
                           robot_reach(self.model, geom))  # fmt: skip

    def _link_name(self, g: Any) -> str:
        frame = int(g.parentFrame)
        if 0 <= frame < len(self.model.frames):
            return str(self.model.frames[frame].name)
        return str(self.model.names[int(g.parentJoint)])

    def _drop_adjacent(self, geom: pin.GeometryModel) -> None:
        """Links joined by a joint touch by design: their pairs are never checked. Links
        without shapes do not count, so two shaped links joined through shapeless ones
        (a universal joint built of two joints) are adjacent too."""
        keep = [
            pair
            for pair in geom.collisionPairs
            if not self.adjacent(
                int(geom.geometryObjects[pair.first].parentJoint),
                int(geom.geometryObjects[pair.second].parentJoint),
            )
        ]
        geom.removeAllCollisionPairs()
        for pair in keep:
            geom.addCollisionPair(pair)

    def _shaped_parents(self, geom: pin.GeometryModel) -> list[int]:
        """Per joint, its nearest ancestor joint that carries a shape (0: the base)."""
        shaped = {int(g.parentJoint) for g in geom.geometryObjects}
        parents = self.model.parents
        found = [0] * self.model.njoints
        for j in range(1, self.model.njoints):
            p = int(parents[j])
            while p != 0 and p not in shaped:
                p = int(parents[p])
            found[j] = p
        return found

    def adjacent(self, a: int, b: int) -> bool:
        """Whether the bodies of joints a and b are the same or joined (see above)."""
        up = self.shaped_parent
        return a == b or up[a] == b or up[b] == a

    def _drop_touching(self, geom: pin.GeometryModel, q: np.ndarray) -> None:
        data, gdata = self.model.createData(), geom.createData()
        pin.computeCollisions(self.model, data, geom, gdata, q, False)
        keep = [
            pair
            for pair, result in zip(geom.collisionPairs, gdata.collisionResults, strict=True)
            if not result.isCollision()
        ]
        geom.removeAllCollisionPairs()
        for pair in keep:
            geom.addCollisionPair(pair)

    def _add_object(
        self, robot: CollisionSubject, geom: pin.GeometryModel, obj: Any, shape: Any
    ) -> None:
        placement = obj.shape_placement
        joint = 0
        if obj.link:
            try:
                frame = robot.model.frames[robot.frames.id(obj.link)]
            except FrameNotFoundError as exc:
                raise InvalidParameterError(f"attached object {obj.name!r}: {exc}") from None
            joint = int(frame.parentJoint)
            placement = frame.placement * placement
        index = geom.addGeometryObject(pin.GeometryObject(obj.name, joint, placement, shape))
        self.names.append(obj.name)  # global numbering: names and joints of every part
        self._joints.append(joint)
        for i in range(self.robot_count):
            other = self._joints[i]
            if obj.link:  # not its own link, nor the links joined to it
                if self.adjacent(other, joint):
                    continue
            elif other == 0:  # both fixed: the same answer at every q, found once (base_hits)
                self._static.append((i, len(self.names) - 1, obj.support))
                continue
            geom.addCollisionPair(pin.CollisionPair(i, index))
        for k in range(self.robot_count, index):  # attached objects against the scene (one
            if bool(obj.link) != bool(self._joints[k]):  # part: local numbering is global)
                geom.addCollisionPair(pin.CollisionPair(k, index))

    def _static_pairs(self) -> list[tuple[str, str]]:
        """The pairs of a shape fixed to the base and a fixed scene object that collide:
        the same at every q, so checked once here by coal's signed distance. A support
        (:class:`SceneObject`) may be touched and entered by
        :data:`~toolkit.collision.scene.SUPPORT_SLACK`; any other object touched only
        (:data:`TOUCH`: a block standing on a floor the description carries), never
        entered (a base inside a table collides wherever the arm is). Coal is asked only
        where the spheres about the two shapes' boxes overlap (a pair or two among MBM's
        objects; about 30 us each saved for the others)."""
        gaps = self._static_gap
        hits = [(self.names[i], self.names[k]) for n, (i, k, support) in enumerate(self._static)
                if not gaps[n] >= (-SUPPORT_SLACK if support else 0.0)  # NaN: coal says
                and self._static_distance(n) < (-SUPPORT_SLACK if support else -TOUCH)]  # fmt: skip
        return list(dict.fromkeys(hits))

    @functools.cached_property
    def base_distance(self) -> tuple[float, tuple[str, str]]:
        """(the smallest distance [m] between a shape fixed to the base and a fixed scene
        object, their names) (inf where there is none; a support counts only where entered
        deeper than :data:`~toolkit.collision.scene.SUPPORT_SLACK`): found at the first
        :meth:`min_distance`, coal asked nearest pair first, and not for a pair whose
        spheres lie farther apart than a distance found."""
        nearest: tuple[float, tuple[str, str]] = (float("inf"), ("", ""))
        for lower, n in sorted((gap, n) for n, gap in enumerate(self._static_gap)):
            i, k, support = self._static[n]
            if lower >= (-SUPPORT_SLACK if support else 0.0) and (support or lower > nearest[0]):
                continue  # cannot be entered, nor nearer than the nearest found
            d = self._static_distance(n)
            if not support or d < -SUPPORT_SLACK:  # a support's touch is no distance
                nearest = min(nearest, (d, (self.names[i], self.names[k])))
        return nearest

    def _static_gaps(self) -> np.ndarray:
        """Per fixed pair (``_static``), the gap [m] between the spheres about the two
        shapes' boxes (as they stand: :func:`~toolkit.collision.bounds.placed_boxes` in the
        base's frame), a lower bound of their distance."""
        shapes = sorted({g for pair in self._static for g in pair[:2]})
        at = {g: n for n, g in enumerate(shapes)}
        boxes = placed_boxes([self.parts.objects[g] for g in shapes])
        radii = np.linalg.norm(boxes[:, 12:], axis=1)
        first = np.array([at[i] for i, _, _ in self._static], np.int64)
        second = np.array([at[k] for _, k, _ in self._static], np.int64)
        apart = np.linalg.norm(boxes[first, :3] - boxes[second, :3], axis=1)
        gaps: np.ndarray = apart - radii[first] - radii[second] - 1e-9
        return gaps

    def _static_distance(self, n: int) -> float:
        """Coal's signed distance [m] of fixed pair n (``_static``)."""
        import coal

        i, k, _ = self._static[n]
        a, b = self.parts.objects[i], self.parts.objects[k]
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        where = [coal.Transform3s(o.placement.rotation, o.placement.translation)
                 for o in (a, b)]  # fmt: skip
        coal.distance(a.geometry, where[0], b.geometry, where[1], request, result)
        return float(result.min_distance)

    # ------------------------------------------------------------------ queries
    def pair_flags(self, q: np.ndarray) -> np.ndarray:
        """Per checked pair, 1 where it collides at q (0 otherwise)."""
        return self.parts.flags(q)

    def pair_names(self, k: int) -> tuple[str, str]:
        """The link or object names of checked pair k."""
        return self.names[int(self.parts.first[k])], self.names[int(self.parts.second[k])]

    def in_collision(self, q: np.ndarray) -> bool:
        return bool(self.base_hits) or self.parts.any(q)

    def in_collision_many(self, Q: np.ndarray) -> np.ndarray:
        """Flags (N,) for configurations Q (N, nq). The compiled pre-filter
        (:mod:`toolkit.collision.bounds`) decides the configurations whose pairs are certainly
        apart, or certainly overlap; coal checks the others, on the pairs the pre-filter
        left undecided only (:meth:`_listed_collide`; every pair where more than
        :data:`~toolkit.collision.bound_kernels.NEAR` are: over every core by Pinocchio's
        ``computeCollisionsInParallel`` from :data:`~toolkit.kinematics.PARALLEL_MIN` rows on
        (one batch at a time), one by one below that or inside ``toolkit.kinematics.serial()``)."""
        if self.base_hits:
            return np.ones(len(Q), dtype=bool)
        if self.bounds is None or not len(Q):
            return self._exact_many(Q)
        Q = np.ascontiguousarray(Q, dtype=float)
        state, listed = self.bounds.decide_pairs(Q)
        flags: np.ndarray = np.asarray(state == HIT)
        close = np.flatnonzero(state == CLOSE)
        few = listed[close, 0] <= NEAR
        if not few.all():  # too many near pairs to list: coal on every pair
            flags[close[~few]] = self._exact_many(Q[close[~few]])
        if few.any():
            flags[close[few]] = self._listed_collide(Q, close[few], listed)
        return flags

    def _listed_collide(self, Q: np.ndarray, rows: np.ndarray, listed: np.ndarray) -> np.ndarray:
        """Per row i of Q in ``rows``: whether coal finds a collision in one of the pairs
        ``listed[i]`` names (the pre-filter's undecided pairs: every other pair of the row
        is certainly apart), to the first that collides (each check on its own:
        :func:`exact_requests`). A configuration costs its placements and a few pairs, where
        coal on every pair cost 20x that in MotionBenchMaker's table scene (ad hoc)."""
        return self.parts.listed_collide(Q, rows, listed)

    def _exact_many(self, Q: np.ndarray) -> np.ndarray:
        """Flags (N,) by coal on every pair, over every core from
        :data:`~toolkit.kinematics.PARALLEL_MIN` rows on."""
        if not parallel(len(Q)):
            return np.array([self.in_collision(q) for q in Q], dtype=bool)
        return self.parts.many(Q)

    def collisions(self, q: np.ndarray) -> list[tuple[str, str]]:
        """Every colliding pair, by link or object name."""
        found = [self.pair_names(k) for k in np.flatnonzero(self.pair_flags(q)).tolist()]
        return list(dict.fromkeys([*self.base_hits, *found]))

    def first_collision(self, q: np.ndarray) -> tuple[str, str] | None:
        if self.base_hits:
            return self.base_hits[0]
        k = self.parts.first_hit(q)
        return None if k is None else self.pair_names(k)

    def min_distance(self, q: np.ndarray) -> tuple[float, tuple[str, str]]:
        """The smallest distance [m] over the checked pairs (negative: penetration; the
        base's shapes against a support count only where they enter it too deep)."""
        d, k = self.parts.nearest(q)
        if k < 0:
            return self.base_distance
        return min((d, self.pair_names(k)), self.base_distance)
