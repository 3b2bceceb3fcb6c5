"""A robot's shapes as convex point sets for the compiled lower bounds of
:mod:`toolkit.collision.convex_kernels` (:func:`convex_sets`): each mesh's convex hull and
its convex pieces (:func:`~toolkit.collision.pieces.pieces_of`), a box's corners, in the
frame of the joint that carries the shape."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .convex_kernels import PIECES
from .parts import hull_of
from .pieces import kept_for, pieces_of

__all__ = ["ConvexSets", "convex_sets", "has_set"]


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


def _points(shape: Any) -> np.ndarray | None:
    """The points whose hull holds a shape (a mesh's hull's points, a box's corners); None
    for another shape (its surface is curved: coal answers for it)."""
    import coal

    if isinstance(shape, coal.Box):
        half = np.asarray(shape.halfSide, dtype=float)
        signs = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)], dtype=float)
        return (2.0 * signs - 1.0) * half
    if not isinstance(shape, coal.BVHModelBase):
        return None
    hull = kept_for(shape, "hull_of", hull_of)
    return None if hull is None else np.asarray(hull.points(), dtype=float)


def convex_sets(geom: Any, count: int) -> ConvexSets:
    """The first ``count`` shapes of ``geom`` (a ``GeometryModel`` or what a checker's
    bounds read: a robot's own) as convex sets (:class:`ConvexSets`)."""
    sets = np.full((count, 3), -1, np.int64)
    chunks: list[np.ndarray] = []
    for s, obj in enumerate(geom.geometryObjects[:count]):
        points = _points(obj.geometry)
        if points is None:
            continue
        R, t = np.asarray(obj.placement.rotation), np.asarray(obj.placement.translation)
        pieces = kept_for(obj.geometry, "pieces_of", pieces_of) if len(points) > 8 else None
        sets[s] = len(chunks), len(chunks), len(chunks) + 1
        chunks.append(points @ R.T + t)
        if pieces is not None and 1 < len(pieces.hulls) <= PIECES:
            sets[s, 1:] = len(chunks), len(chunks) + len(pieces.hulls)
            chunks += [np.asarray(h.points(), dtype=float) @ R.T + t for h in pieces.hulls]
    sizes = np.array([len(c) for c in chunks], np.int64)
    vstart = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    verts = np.concatenate(chunks) if chunks else np.zeros((0, 3))
    ball = np.zeros((len(chunks), 4))
    for i, c in enumerate(chunks):
        middle = (c.min(axis=0) + c.max(axis=0)) / 2
        ball[i] = *middle, np.linalg.norm(c - middle, axis=1).max() * (1 + 1e-12)
    return ConvexSets(sets, vstart, np.ascontiguousarray(verts), ball)


def has_set(convex: ConvexSets, shapes: np.ndarray) -> np.ndarray:
    """Whether each of ``shapes`` (indices of a checker's shapes) is a convex set."""
    shapes = np.asarray(shapes, dtype=np.int64)
    inside = shapes < len(convex.sets)
    out = np.zeros(len(shapes), dtype=bool)
    out[inside] = convex.sets[shapes[inside], 0] >= 0
    return out
