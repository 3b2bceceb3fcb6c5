"""The collision checker's compiled pre-filter (see :mod:`toolkit.collision.bound_kernels`): the
bounding boxes and spheres of its shapes and their sphere covers, packed for the kernels."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin

from ..errors import UnsupportedModelError
from ..kinematics import CompiledBackend, parallel
from . import bound_kernels
from .covers import shape_cover, surface_points
from .parts import AllShapes
from .parts import pairs_of as parts_pairs
from .stored import stored_covers

__all__ = [
    "PER_SHAPE",
    "Bounds",
    "Rows",
    "local_box",
    "pair_arrays",
    "placed_boxes",
    "shape_covers",
    "shape_rows",
]


def _solid(shape: Any) -> int:
    """The kind of solid a shape is, for the pre-filter's test of a point inside it
    (:data:`~toolkit.collision.solid_kernels.SOLIDS`; 0: none, a mesh, an octree)."""
    import coal

    kinds = ((coal.Box, 1), (coal.Sphere, 2), (coal.Cylinder, 3), (coal.Capsule, 4))
    return next((kind for cls, kind in kinds if isinstance(shape, cls)), 0)


def _inner(shape: Any) -> float:
    """The radius of the largest sphere about a primitive's centre inside it (0 for
    anything else, meshes included)."""
    import coal

    if isinstance(shape, coal.Sphere):
        return float(shape.radius)
    if isinstance(shape, coal.Box):
        return float(np.min(shape.halfSide))
    if isinstance(shape, coal.Cylinder):
        return float(min(shape.radius, shape.halfLength))
    return 0.0


def local_box(shape: Any) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) corners of a shape's bounding box in its own frame: for an octree, its
    occupied cells' (coal's box of an octree is its points', which the cells pass)."""
    import coal

    if isinstance(shape, coal.OcTree):
        cells = np.asarray(shape.toBoxes(), dtype=float).reshape(-1, 6)
        half = cells[:, 3:4] / 2
        return (cells[:, :3] - half).min(axis=0), (cells[:, :3] + half).max(axis=0)
    shape.computeLocalAABB()
    return np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)


PER_SHAPE = 8
"""Spheres in each shape's cover (the pre-filter's second test)."""
WITNESS_SPACING = 0.015
"""About how far apart [m] the points of a shape's surface that can prove a collision
lie (:func:`~toolkit.collision.covers.surface_points`); at most :data:`WITNESSES` a shape."""
WITNESSES = 512


Cover = tuple[np.ndarray, np.ndarray, np.ndarray]
"""A shape's cover (m, 4), its surface points (K, 3) and the sphere holding each (K,)."""


def shape_covers(geom: pin.GeometryModel, start: int, stop: int) -> list[Cover]:
    """Per shape ``start`` to ``stop`` of ``geom``, in its joint's frame: at most
    :data:`PER_SHAPE` spheres (m, 4) (centre, radius) covering its surface ((0, 4) for a
    shape without a finite surface, a plane), and points of its surface (K, 3), each
    with the sphere of the cover holding it (K,) (-1: none, by rounding; (0, 3) where the
    shape has none, :func:`~toolkit.collision.covers.surface_points`)."""
    rng = np.random.default_rng(0)
    out = []
    for obj in geom.geometryObjects[start:stop]:
        try:
            c, r, tris = shape_cover(obj.geometry, PER_SHAPE, rng)
        except UnsupportedModelError:
            out.append((np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0, np.int64)))
            continue
        w = surface_points(obj.geometry, WITNESS_SPACING, WITNESSES, tris)
        d = np.linalg.norm(w[:, None, :] - c[None], axis=2) - r[None]  # (K, m)
        held = np.where(d.min(axis=1, initial=np.inf) <= 1e-9, d.argmin(axis=1), -1)
        M = obj.placement
        R, t = np.asarray(M.rotation), np.asarray(M.translation)
        out.append((np.column_stack([c @ R.T + t, r]), w @ R.T + t, held.astype(np.int64)))
    return out


PackedCovers = tuple[np.ndarray, ...]
"""A robot's covers packed for the kernels: (cstart, csphere, hold, wstart, wpoint)."""


class Packed(NamedTuple):
    """Everything the bound kernels read of a checker, one argument (``packed``; made by
    :meth:`Bounds.packed`): the kinematics chain, each shape's joint row, box and radii,
    the checked pairs and the covers. A kernel may read it by position, in this order."""

    ints: np.ndarray
    """The chain's integers (:mod:`toolkit.kinematics.kernels`' packed tree)."""
    flts: np.ndarray
    """The chain's placements and axes."""
    row: np.ndarray
    """(S,) each shape's joint row in the kernels' frame table."""
    box: np.ndarray
    """(S, 15) each shape's box in its joint's frame (centre, axes, half extents)."""
    radius: np.ndarray
    """(S, 3) each shape's outer, inner and cover radii."""
    first: np.ndarray
    """(K,) the checked pairs' first shapes."""
    second: np.ndarray
    """(K,) the checked pairs' second shapes."""
    cstart: np.ndarray
    """(S + 1,) each shape's first cover sphere."""
    csphere: np.ndarray
    """(C, 4) the cover spheres (centre in the joint's frame, radius)."""
    hold: np.ndarray
    """(S, 4) the sphere holding each shape's cover."""

    def with_pairs(self, first: np.ndarray, second: np.ndarray) -> Packed:
        """The same with other checked pairs (a subset or an order of them)."""
        return self._replace(first=np.ascontiguousarray(first, np.int64),
                             second=np.ascontiguousarray(second, np.int64))  # fmt: skip


def _witnesses(parts: list[Cover], start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(wstart (S + 1,), wpoint (P, 3)) of :mod:`~toolkit.collision.bound_kernels`: the
    surface points of ``parts`` grouped by the cover sphere holding them (sphere s's from
    wstart[s]; a point no sphere holds is left out: one fewer witness, never a wrong
    answer), ``start``: each shape's first sphere."""
    S = int(start[-1])
    owner = [start[g] + held[held >= 0] for g, (_, _, held) in enumerate(parts)]
    points = [w[held >= 0] for _, w, held in parts]
    if not S or not sum(len(o) for o in owner):
        return np.zeros(S + 1, np.int64), np.zeros((0, 3))
    sphere, P = np.concatenate(owner), np.concatenate(points)
    order = np.argsort(sphere, kind="stable")
    wstart = np.searchsorted(sphere[order], np.arange(S + 1)).astype(np.int64)
    return wstart, np.ascontiguousarray(P[order], dtype=float)


def _packed(covers: list[Cover], box: np.ndarray) -> tuple[np.ndarray, ...]:
    """(cstart, csphere, hold, wstart, wpoint) of ``covers``: the holding sphere about each
    box's centre, the surface points by sphere (:func:`_witnesses`)."""
    parts = [c for c, _, _ in covers]
    counts = np.array([len(c) for c in parts], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    csphere = np.concatenate(parts) if parts else np.zeros((0, 4))
    hold = np.zeros((len(parts), 4))
    if len(csphere):  # each sphere's reach from its shape's box centre, the most per shape
        owner = np.repeat(np.arange(len(parts)), counts)
        far = np.linalg.norm(csphere[:, :3] - box[owner, :3], axis=1) + csphere[:, 3]
        has = counts > 0
        hold[has, :3] = box[has, :3]
        hold[has, 3] = np.maximum.reduceat(far, start[:-1][has])
    return (start, np.ascontiguousarray(csphere, dtype=float), hold,
            *_witnesses(covers, start))  # fmt: skip


def _extended(own: tuple[np.ndarray, ...], more: int) -> tuple[np.ndarray, ...]:
    """The robot's packed covers ``own`` (:func:`_packed`) with ``more`` shapes after its
    own (a scene's) that have none: their first sphere is past the last, their holding
    sphere nothing."""
    cstart, csphere, hold, wstart, wpoint = own
    cstart = np.concatenate([cstart, np.full(more, cstart[-1], np.int64)])
    return cstart, csphere, np.concatenate([hold, np.zeros((more, 4))]), wstart, wpoint


Rows = tuple[np.ndarray, np.ndarray, np.ndarray]
"""Shapes' rows for the kernels: (joint row (n,), box (n, 15), radii (n, 3)), as
:class:`Bounds` holds them (``row``, ``box``, ``radius``)."""


def placed_boxes(objects: Sequence[Any]) -> np.ndarray:
    """(n, 15): each geometry object's bounding box in its joint's frame: centre (3),
    rotation (9, row-major), half extents (3) (:func:`local_box` placed by the object's
    placement)."""
    n = len(objects)
    box = np.empty((n, 15))
    if not n:
        return box
    corners = np.array([local_box(obj.geometry) for obj in objects], dtype=float)  # (n, 2, 3)
    R = np.array([obj.placement.rotation for obj in objects], dtype=float)  # (n, 3, 3)
    t = np.array([obj.placement.translation for obj in objects], dtype=float)
    box[:, :3] = np.einsum("nij,nj->ni", R, (corners[:, 1] + corners[:, 0]) / 2) + t
    box[:, 3:12] = R.reshape(n, 9)
    box[:, 12:] = (corners[:, 1] - corners[:, 0]) / 2
    return box


def shape_rows(objects: Sequence[Any], backend: CompiledBackend) -> Rows:
    """The rows of :class:`Bounds` for each geometry object: its joint's row in the kernels'
    frames, its bounding box in that joint's frame (:func:`placed_boxes`), the radii of the
    spheres about and inside it and its kind of solid."""
    n = len(objects)
    row, box, radius = np.empty(n, np.int64), placed_boxes(objects), np.zeros((n, 3))
    if not n:
        return row, box, radius
    radius[:, 0] = np.linalg.norm(box[:, 12:], axis=1)
    radius[:, 1] = [_inner(obj.geometry) for obj in objects]
    radius[:, 2] = [_solid(obj.geometry) for obj in objects]
    row[:] = [backend.joint_row(int(obj.parentJoint)) for obj in objects]
    return row, box, radius


def pair_arrays(geom: Any) -> tuple[np.ndarray, np.ndarray]:
    """(first, second) (pairs,) int64: each collision pair's two shape indices, the lower
    first, in the pairs' order: a ``GeometryModel``'s read from Pinocchio's pair table (a
    matrix: 1 us; pair by pair from Python cost 0.2 ms among a bookshelf's boards), or
    a checker's parts' (:class:`~toolkit.collision.parts.AllShapes`) as they are. Every
    pair a checker makes holds its shapes so; the kernels treat a pair's two shapes alike
    either way."""
    if isinstance(geom, AllShapes):
        return geom.first.copy(), geom.second.copy()
    return parts_pairs(geom)


class Bounds:
    """Bounding volumes of a GeometryModel's shapes on a robot's compiled kinematics."""

    def __init__(
        self, geom: pin.GeometryModel, backend: CompiledBackend, robot_count: int = 0,
        robot_covers: Callable[[Callable[[], PackedCovers]], PackedCovers] | None = None,
        robot_rows: Rows | None = None,
    ) -> None:  # fmt: skip
        """``robot_rows``: the rows (:func:`shape_rows`) of the robot's own shapes, the
        first ``robot_count``, where the robot keeps them (the same in every scene); None:
        made here with the scene's."""
        ints, flts, _, _ = backend.tree
        self.ints, self.flts = ints, flts
        objects = geom.geometryObjects
        if robot_rows is None or len(robot_rows[0]) != robot_count:
            self.row, self.box, self.radius = shape_rows(objects, backend)
        else:
            rest = shape_rows(objects[robot_count:], backend)
            self.row, self.box, self.radius = (
                np.concatenate([own, more]) for own, more in zip(robot_rows, rest, strict=True)
            )
        self.first, self.second = pair_arrays(geom)
        solid = (self.radius[self.first, 2] != 0) | (self.radius[self.second, 2] != 0)
        self.order = np.argsort(~solid, kind="stable").astype(np.int64)
        """The pairs in the order :meth:`decide_pairs` tries them: those with a solid first
        (most configurations it proves colliding have a link inside an obstacle)."""
        self._geom, self._robot = geom, (robot_count, robot_covers)
        self._covers: tuple[np.ndarray, ...] | None = None

    def witnesses(self) -> tuple[np.ndarray, np.ndarray]:
        """(wstart, wpoint) of :mod:`~toolkit.collision.bound_kernels`: points of the robot's
        shapes' surfaces (meshes, convex shapes, boxes) about
        :data:`WITNESS_SPACING` apart, grouped by the cover sphere holding them, made with
        the covers (:meth:`covers`)."""
        _, _, _, wstart, wpoint = self._packed_covers()
        return wstart, wpoint

    def covers(self) -> tuple[np.ndarray, ...]:
        """(cstart, csphere, hold) of :mod:`~toolkit.collision.bound_kernels`: at most
        :data:`PER_SHAPE` spheres covering each of the robot's own shapes (its first
        ``robot_count``), in its joint's frame, made at the first batch (a few tenths of a
        second for an arm's meshes) through ``robot_covers`` where given, which is handed
        the way to make them (packed) and keeps them per robot (shared by its checkers of
        every scene, which only extend them). A scene's shapes get none: their boxes are
        tested against the robot's covers, and making covers for every object of every
        scene cost more than it saved on MotionBenchMaker's problems, each in its own
        scene."""
        return self._packed_covers()[:3]

    def _packed_covers(self) -> PackedCovers:
        """(cstart, csphere, hold, wstart, wpoint): the robot's packed covers
        (:meth:`covers`, :meth:`witnesses`), extended by the scene's shapes, made once."""
        if self._covers is None:
            count, shared = self._robot
            n = len(self._geom.geometryObjects)
            box = self.box[:count]  # the robot's shapes' boxes: the same in every scene

            def anew() -> PackedCovers:
                return _packed(shape_covers(self._geom, 0, count), box)

            def make() -> PackedCovers:  # kept on disk between processes
                return stored_covers(self._geom, count, anew)

            own = make() if shared is None else shared(make)
            self._covers = _extended(own, n - count)  # a scene's shapes: their boxes suffice
        return self._covers

    def packed(self) -> Packed:
        """Everything the kernels read (:class:`Packed`): the ``packed`` argument of
        :func:`~toolkit.collision.bound_kernels.certainly_free`."""
        return Packed(self.ints, self.flts, self.row, self.box, self.radius, self.first,
                      self.second, *self.covers())  # fmt: skip

    def decide(self, Q: np.ndarray) -> np.ndarray:
        """(N,) states: CLOSE (coal must decide), FREE (every checked pair certainly
        apart) or HIT (the inner spheres of a checked pair overlap, or a point of one
        shape's surface lies inside the other, a solid)."""
        return self.decide_pairs(Q)[0]

    def decide_pairs(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((N,) states as :meth:`decide`'s; (N, 1 + :data:`~toolkit.collision.bound_kernels.NEAR`)
        int32: per configuration how many checked pairs no bound proves apart, then those
        pairs' indices where they are that few): coal need check only the listed pairs of
        a CLOSE configuration; the others are certainly apart."""
        Q = np.ascontiguousarray(Q, dtype=float)
        args: tuple[Any, ...] = (Q, *self.packed(), *self.witnesses(), self.order)
        state, listed = bound_kernels.decide_batch(parallel(len(Q)), *args)
        return np.asarray(state), np.asarray(listed)
