"""Shapes as convex point sets for the compiled lower bounds of
:mod:`toolkit.collision.convex_kernels` (:func:`convex_sets`): a robot mesh's convex hull
and its convex pieces (:func:`~toolkit.collision.pieces.pieces_of`), a scene mesh's hull, a
box's corners, a cylinder's circumscribed prism (it holds the cylinder, so it is no
farther from anything), in the frame of the joint that carries the shape."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .convex_kernels import PIECES
from .covers import SIDES
from .parts import hull_of
from .pieces import kept_for, pieces_of

__all__ = ["SCENE_MOST", "ConvexSets", "convex_sets", "has_set"]

SCENE_MOST = 5_000
"""A scene's mesh of more vertices is no convex set (its hull is made anew in every scene's
checker; coal answers for it)."""


class ConvexSets(NamedTuple):
    """Shapes as convex point sets, one argument of
    :func:`~toolkit.collision.convex_kernels.convex_gaps` (read by position there)."""

    sets: np.ndarray
    """(S, 3) per shape of the robot (the first S of a checker's): its hull (a set's index;
    -1: the shape has none, a sphere, a cylinder) and the range of its pieces' sets (the
    hull alone where the mesh has no pieces). A scene's shapes have none."""
    vstart: np.ndarray
    """(sets + 1,) each set's first point in ``verts``."""
    verts: np.ndarray
    """(V, 3) the sets' points, each in its shape's joint's frame."""
    ball: np.ndarray
    """(sets, 4) a ball holding each set (centre in the joint's frame, radius)."""


def _points(shape: Any, most: int | None = None) -> np.ndarray | None:
    """The points whose hull holds a shape (a mesh's hull's points, a box's corners, the
    corners of a prism about a cylinder); None for another shape (a sphere, a capsule:
    coal answers for it), and for a mesh of more than ``most`` vertices."""
    import coal

    if isinstance(shape, coal.Box):
        half = np.asarray(shape.halfSide, dtype=float)
        signs = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)], dtype=float)
        return (2.0 * signs - 1.0) * half
    if isinstance(shape, coal.Cylinder):  # the prism about it: its sides touch the circle
        out = float(shape.radius) / np.cos(np.pi / SIDES) * (1.0 + 1e-12)
        angle = 2.0 * np.pi * np.arange(SIDES) / SIDES
        ring = np.column_stack([out * np.cos(angle), out * np.sin(angle)])
        h = float(shape.halfLength)
        return np.concatenate([np.column_stack([ring, np.full(SIDES, z)]) for z in (-h, h)])
    if not isinstance(shape, coal.BVHModelBase) or (most is not None and shape.num_vertices > most):
        return None
    hull = kept_for(shape, "hull_of", hull_of)
    return None if hull is None else np.asarray(hull.points(), dtype=float)


def convex_sets(geom: Any, count: int, robot: ConvexSets | None = None) -> ConvexSets:
    """The first ``count`` shapes of ``geom`` (a ``GeometryModel`` or what a checker's
    bounds read) as convex sets (:class:`ConvexSets`); ``robot``: those of its first shapes
    (the robot's, kept per robot), to which the rest are added, hulls without pieces."""
    start = 0 if robot is None else len(robot.sets)
    sets = np.full((count, 3), -1, np.int64)
    chunks: list[np.ndarray] = []
    first = 0 if robot is None else len(robot.ball)  # the sets' numbers go on from there
    for s in range(start, count):
        obj = geom.geometryObjects[s]
        points = _points(obj.geometry, None if robot is None else SCENE_MOST)
        if points is None:
            continue
        R, t = np.asarray(obj.placement.rotation), np.asarray(obj.placement.translation)
        split = robot is None and len(points) > 8
        pieces = kept_for(obj.geometry, "pieces_of", pieces_of) if split else None
        n = first + len(chunks)
        sets[s] = n, n, n + 1
        chunks.append(points @ R.T + t)
        if pieces is not None and 1 < len(pieces.hulls) <= PIECES:
            sets[s, 1:] = n + 1, n + 1 + len(pieces.hulls)
            chunks += [np.asarray(h.points(), dtype=float) @ R.T + t for h in pieces.hulls]
    ball = np.zeros((len(chunks), 4))
    for i, c in enumerate(chunks):
        middle = (c.min(axis=0) + c.max(axis=0)) / 2
        ball[i] = *middle, np.linalg.norm(c - middle, axis=1).max() * (1 + 1e-12)
    sizes = np.array([len(c) for c in chunks], np.int64)
    verts = np.concatenate(chunks) if chunks else np.zeros((0, 3))
    if robot is None:
        vstart = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        return ConvexSets(sets, vstart, np.ascontiguousarray(verts), ball)
    sets[:start] = robot.sets
    vstart = np.concatenate([robot.vstart, robot.vstart[-1] + np.cumsum(sizes)]).astype(np.int64)
    return ConvexSets(sets, vstart, np.ascontiguousarray(np.concatenate([robot.verts, verts])),
                      np.concatenate([robot.ball, ball]))  # fmt: skip


def has_set(convex: ConvexSets, shapes: np.ndarray) -> np.ndarray:
    """Whether each of ``shapes`` (indices of a checker's shapes) is a convex set."""
    shapes = np.asarray(shapes, dtype=np.int64)
    inside = shapes < len(convex.sets)
    out = np.zeros(len(shapes), dtype=bool)
    out[inside] = convex.sets[shapes[inside], 0] >= 0
    return out
