"""Surfaces held by spheres: a shape's surface as triangles (:func:`surface_triangles`) and a
few spheres holding them (:func:`cover`), for :func:`toolkit.collision.sphere_model` and the
checker's pre-filter (:mod:`toolkit.collision.bounds`).

A shape's surface is cut into triangles (a mesh's own; a box's faces; a cylinder, cone or
capsule inside a circumscribed prism), the triangles are grouped by k-means on their
centroids, and each group gets the sphere about its triangles' bounding-box centre that
holds all of their corners. A triangle lies in the convex hull of its corners, so inside
its group's sphere.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import UnsupportedModelError

__all__ = ["SIDES", "cover", "shape_cover", "surface_points", "surface_triangles"]

SIDES = 16
"""Sides of the prism circumscribing a cylinder, cone or capsule."""


def _prism(radius: float, half: float, bottom: float, top: float) -> np.ndarray:
    """Triangles (T, 3, 3) of a closed prism about z circumscribing a circle of ``radius``
    from z = -half to half; ``bottom`` and ``top`` scale the end faces (a cone: 0)."""
    r = radius / math.cos(math.pi / SIDES)
    a = 2 * math.pi * np.arange(SIDES) / SIDES
    ring = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
    lo = np.column_stack([bottom * ring, np.full(SIDES, -half)])
    hi = np.column_stack([top * ring, np.full(SIDES, half)])
    nxt = np.roll(np.arange(SIDES), -1)
    sides = [np.stack([lo, lo[nxt], hi], 1), np.stack([hi, lo[nxt], hi[nxt]], 1)]
    caps = [np.stack([np.broadcast_to([0, 0, z], (SIDES, 3)), e, e[nxt]], 1)
            for z, e in ((-half, lo), (half, hi))]  # fmt: skip
    return np.concatenate(sides + caps)


def _box(half: np.ndarray) -> np.ndarray:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([corners[list(t)] for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


def surface_triangles(shape: Any) -> np.ndarray | None:
    """Triangles (T, 3, 3) [m] in the shape's frame whose union holds its surface (None for
    a sphere, which covers itself; a convex hull's points (K, 1, 3) where its faces are not
    known); an :class:`~toolkit.errors.UnsupportedModelError` for a
    shape without a finite surface (a plane)."""
    import coal

    if isinstance(shape, coal.Sphere):
        return None
    if isinstance(shape, coal.Box):
        return _box(np.asarray(shape.halfSide))
    if isinstance(shape, coal.Capsule):  # the prism reaches past the caps by the radius
        return _prism(shape.radius, shape.halfLength + shape.radius, 1.0, 1.0)
    if isinstance(shape, coal.Cylinder):
        return _prism(shape.radius, shape.halfLength, 1.0, 1.0)
    if isinstance(shape, coal.Cone):
        return _prism(shape.radius, shape.halfLength, 1.0, 0.0)
    if isinstance(shape, coal.ConvexBase):  # its faces where known, else its hull whole
        V = np.array([shape.point(i) for i in range(shape.num_points)], dtype=float)
        faces = getattr(shape, "num_polygons", 0)
        if faces:
            polygons = [[shape.polygons(k)[i] for i in range(3)] for k in range(faces)]
            return V[np.array(polygons, np.int64)]
        return V[:, None, :]  # points (K, 1, 3): one sphere holds them, so their hull
    if isinstance(shape, coal.BVHModelBase):
        V = np.array(shape.vertices(), dtype=float).reshape(-1, 3)  # one call, not one a vertex
        tri = [(t[0], t[1], t[2]) for t in map(shape.tri_indices, range(shape.num_tris))]
        return V[np.array(tri, np.int64)] if tri else np.repeat(V[:, None, :], 3, axis=1)
    raise UnsupportedModelError(f"no sphere cover for a {type(shape).__name__} shape")


def _squared(points_t: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Squared distances (N, k) from points (3, N: by coordinate) to centres ``c`` (k, 3),
    summed x, y, z in that order (as numpy sums the three of a row: the same bits, ~6x
    faster than a reduction over a last axis of three)."""
    d = (points_t[0][:, None] - c[:, 0]) ** 2
    d += (points_t[1][:, None] - c[:, 1]) ** 2
    d += (points_t[2][:, None] - c[:, 2]) ** 2
    return d


def _kmeans(points: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """Labels (N,) of ``points`` (N, 3) in k clusters (k-means++ start, Lloyd steps)."""
    by_axis = np.ascontiguousarray(points.T)
    centers = [points[rng.integers(len(points))]]
    d = _squared(by_axis, centers[0][None])[:, 0]  # to the nearest centre so far
    for _ in range(1, k):
        centers.append(points[rng.choice(len(points), p=d / d.sum())] if d.sum() > 0
                       else points[rng.integers(len(points))])  # fmt: skip
        d = np.minimum(d, _squared(by_axis, centers[-1][None])[:, 0])
    C = np.array(centers)
    labels = np.zeros(len(points), np.int64)
    for _ in range(25):
        labels = np.argmin(_squared(by_axis, C), axis=1)
        count = np.bincount(labels, minlength=k)  # the sums row by row, as a mean's
        sums = np.stack([np.bincount(labels, weights=x, minlength=k) for x in by_axis], axis=1)
        new = np.where(count[:, None] > 0, sums / np.maximum(count, 1)[:, None], C)
        if np.allclose(new, C):
            break
        C = new
    return labels


def _split(triangles: np.ndarray, edge: float) -> np.ndarray:
    """``triangles`` cut in four at their edges' midpoints until no edge is over ``edge``
    (six rounds at most): the same surface in pieces a sphere can hold tightly."""
    for _ in range(6):
        longest = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2).max(axis=1)
        big = longest > edge
        if not big.any():
            break
        a, b, c = (triangles[big, i] for i in range(3))
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        parts = [np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        triangles = np.concatenate([triangles[~big], *parts])
    return triangles


def cover(triangles: np.ndarray, k: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """(centres (m, 3), radii (m,)) of spheres each holding a group of triangles whole (a
    hull's points (K, 1, 3) without its faces: one sphere holding them all)."""
    corners = triangles.reshape(-1, 3)
    if triangles.shape[1] == 1:
        c = (corners.min(axis=0) + corners.max(axis=0)) / 2
        return c[None], np.array([float(np.sqrt(((corners - c) ** 2).sum(axis=1).max()))])
    size = float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))
    triangles = _split(triangles, size / (2.0 * math.sqrt(k)))
    k = min(k, len(triangles))
    labels = _kmeans(triangles.mean(axis=1), k, rng)
    centers, radii = [], []
    for i in np.unique(labels).tolist():
        corners = triangles[labels == i].reshape(-1, 3)
        c = (corners.min(axis=0) + corners.max(axis=0)) / 2
        centers.append(c)
        radii.append(float(np.sqrt(((corners - c) ** 2).sum(axis=1).max())))
    return np.array(centers), np.array(radii)


def surface_points(
    shape: Any, spacing: float, most: int, triangles: np.ndarray | None = None
) -> np.ndarray:
    """Points (K, 3) in the shape's frame that lie on its surface, about ``spacing`` [m]
    apart (its triangles cut until no edge is longer than twice that, their corners, edge
    midpoints and centres, one a cell of a grid of that edge), at most ``most`` (the
    spacing widened to sqrt(area / (4 most)) first, then doubled until they fit), in a
    seeded random order; (0, 3) for a shape whose triangles only circumscribe it (a
    cylinder, cone or capsule: their corners lie outside) or that has none (a sphere, a
    plane). A point of a shape's surface inside a solid proves the two intersect.
    ``triangles``: its :func:`surface_triangles`, where the caller has them."""
    import coal

    if not isinstance(shape, (coal.Box, coal.ConvexBase, coal.BVHModelBase)):
        return np.zeros((0, 3))
    tris = surface_triangles(shape) if triangles is None else triangles
    if tris is None:  # pragma: no cover - the kinds above have triangles
        return np.zeros((0, 3))
    if tris.shape[1] == 3:
        # no finer than ``most`` cells of the surface need: a large shape's cut stays small
        normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        area = 0.5 * float(np.linalg.norm(normals, axis=1).sum())
        spacing = max(spacing, math.sqrt(area / (4 * most)))
        # the corners, edge midpoints and centres of pieces no longer than twice the spacing
        tris = _split(tris, 2.0 * spacing)
        middles = (tris + np.roll(tris, 1, axis=1)) / 2
        tris = np.concatenate([tris, middles, tris.mean(axis=1, keepdims=True)], axis=1)
    points = tris.reshape(-1, 3)
    while True:  # one point per grid cell, the cells widened until at most ``most`` remain
        cells = np.floor(points / spacing).astype(np.int64)
        cells -= cells.min(axis=0)
        span = cells.max(axis=0) + 1  # each cell one integer (unique on rows is 20x slower)
        key = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]
        _, first = np.unique(key, return_index=True)
        if len(first) <= most:
            break
        spacing *= 2.0
    kept = points[np.sort(first)]
    return kept[np.random.default_rng(0).permutation(len(kept))]


def shape_cover(
    shape: Any, k: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(centres (m, 3), radii (m,)) in the shape's frame of at most ``k`` spheres holding
    its surface (:func:`cover`), and its triangles (None for a sphere, which is its own
    cover); an :class:`~toolkit.errors.UnsupportedModelError` for a shape without a finite
    surface (a plane)."""
    tris = surface_triangles(shape)
    if tris is None:
        return np.zeros((1, 3)), np.array([float(shape.radius)]), None
    centers, radii = cover(tris, k, rng)
    return centers, radii, tris
