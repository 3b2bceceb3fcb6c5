"""A mesh as a few convex pieces (:func:`pieces_of`), and a lower bound of two shapes'
distance from their pieces (:func:`pieces_distance`).

The exact certificate of a plan (:class:`~toolkit.planning.sweep.ExactSweep`) asks for a
lower bound of the distance of two links' meshes at each configuration it checks. Two
links a joint or two apart are often 1-2 cm apart and the convex hulls of their whole
meshes overlap; coal's distance of the meshes themselves then took 0.3-0.4 ms a pair
(the UR10's base against its upper arm, 366 and 1,224 triangles). Split into
:data:`PIECES` pieces (the triangles grouped by their centres, each group's convex hull),
the least distance between the pieces of one and of the other is a lower bound of the
meshes' distance (each triangle lies in its group's hull), the pieces far apart skipped by
a ball about each: 0.07-0.11 ms, at the meshes' distance at the median of 200 random
configurations of those two pairs (a tenth percentile of 0.97 of it; ad hoc).
"""

from __future__ import annotations

import hashlib
import threading
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin

__all__ = ["FLAT", "MOST", "PIECES", "Pieces", "address", "convex_hull", "kept_for",
           "pieces_distance", "pieces_of"]  # fmt: skip

PIECES = 4
"""How many pieces a mesh is split into (more pieces: a closer bound, more GJK calls;
8 took 20 calls a pair where 4 took 6, at the same bound)."""
FLAT = 1e-5
"""Points that spread less than this share of their widest spread in some direction are
flat: they have no hull (qhull, as the ``pin`` wheel's coal calls it, crashed the process
on points spread 1e-8 as much one way as another); :func:`pieces_of` then makes no pieces
for the mesh."""
MOST = 100_000
"""A mesh of more triangles has no pieces (reading its triangles alone takes about a
microsecond each: 60 ms for one of MotionBenchMaker's UR5 gripper meshes of 56,000, made
once a process since a robot's meshes are kept per coal object (:func:`kept_for`); coal's
distance of those meshes took 1 ms a pair each time the certificate asked it)."""
ROUNDS = 20
"""Rounds of grouping the triangles' centres (Lloyd's, from seeded centres)."""
KEPT = 512
"""The most meshes whose pieces this process keeps by their vertices' and triangles'
digest (the same mesh in another coal object, a robot loaded again, is split once: 10-20
ms each for the UR10's), and the most shapes :func:`kept_for` keeps by object."""
_KEPT: dict[bytes, Pieces | None] = {}
_LOCK = threading.Lock()
_BY_SHAPE: dict[tuple[int, str], tuple[Any, Any]] = {}
"""(a shape's address, what was made) -> (the shape, what was made of it): a shape met
again (a robot's links are one set of coal objects in every scene's checker, each read
through a new Python wrapper) answered without reading its triangles again (that took
1.5 ms a plan on MotionBenchMaker's Panda). The address is coal's own (``id()``: the C++
object's); the shape is kept beside its answer, so the address is not reused while the
entry lives."""


class Pieces(NamedTuple):
    """A shape's convex pieces in its own frame: coal's hulls, and a ball about each."""

    hulls: list[Any]
    """Each piece's convex hull (coal ``ConvexBase``), or the shape itself where it is not
    a mesh (one piece)."""
    centres: np.ndarray
    """(K, 3) each piece's ball's centre [m]."""
    radii: np.ndarray
    """(K,) each piece's ball's radius [m] (inf: no ball, the piece is always asked)."""


def convex_hull(points: np.ndarray) -> Any:
    """coal's convex hull of ``points`` (N, 3), a ``ConvexBase`` (None: fewer than 4
    points, or flat: :data:`FLAT`)."""
    import coal

    if len(points) < 4:
        return None
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if not np.all(np.isfinite(spread)) or spread[-1] < FLAT * spread[0]:
        return None
    vertices = coal.StdVec_Vec3s()
    vertices.extend(list(points))
    return coal.ConvexBase.convexHull(vertices, False, "Qt")


def address(shape: Any) -> int | None:
    """Where coal holds a shape (its ``id()``: the C++ object's address, the same through
    every Python wrapper of it); None for an object that is not coal's."""
    return int(shape.id()) if callable(getattr(shape, "id", None)) else None


def kept_for(shape: Any, what: str, make: Any) -> Any:
    """``make(shape)``, kept per shape object (:data:`_BY_SHAPE`; at most :data:`KEPT`)."""
    found_at = address(shape)
    key = (id(shape) if found_at is None else found_at, what)
    with _LOCK:
        found = _BY_SHAPE.get(key)
    if found is not None:
        return found[1]
    made = make(shape)
    with _LOCK:
        if len(_BY_SHAPE) >= KEPT:
            _BY_SHAPE.clear()
        _BY_SHAPE[key] = (shape, made)
    return made


def pieces_of(shape: Any, count: int = PIECES) -> Pieces | None:
    """A coal mesh split into ``count`` convex pieces (module doc): its triangles grouped
    by their centres (Lloyd's rounds from centres picked with a fixed seed), each group's
    hull holding every vertex of the group's triangles, so the pieces hold the mesh.
    Another shape is one piece, itself, with no ball. None for a mesh of fewer triangles
    than ``count`` or more than :data:`MOST`, or where a group's hull cannot be made (a
    group flat or of one triangle): every triangle must lie in a piece."""
    import coal

    if not isinstance(shape, coal.BVHModelBase):
        return Pieces([shape], np.zeros((1, 3)), np.full(1, np.inf))
    if not count <= shape.num_tris <= MOST:
        return None
    vertices = np.asarray(shape.vertices(), dtype=float)
    corners = [shape.tri_indices(i) for i in range(shape.num_tris)]
    triangles = np.array([[t[0], t[1], t[2]] for t in corners], dtype=np.int64)
    key = hashlib.sha256(vertices.tobytes() + triangles.tobytes() + bytes([count])).digest()
    with _LOCK:
        if key in _KEPT:
            return _KEPT[key]
    made = _split(vertices, triangles, count)
    with _LOCK:
        if len(_KEPT) >= KEPT:
            _KEPT.clear()
        return _KEPT.setdefault(key, made)


def _split(vertices: np.ndarray, triangles: np.ndarray, count: int) -> Pieces | None:
    """:func:`pieces_of` a mesh's vertices (V, 3) and triangles (T, 3)."""
    mids = vertices[triangles].mean(axis=1)
    rng = np.random.default_rng(0)
    centres = mids[rng.choice(len(mids), count, replace=False)]
    for _ in range(ROUNDS):
        group = np.argmin(((mids[:, None] - centres[None]) ** 2).sum(axis=2), axis=1)
        centres = np.array([mids[group == k].mean(axis=0) if (group == k).any() else c
                            for k, c in enumerate(centres)])  # fmt: skip
    hulls, balls = [], []
    for k in np.unique(group):
        points = vertices[np.unique(triangles[group == k])]
        hull = convex_hull(points)
        if hull is None:
            return None
        middle = points.mean(axis=0)
        hulls.append(hull)
        balls.append((middle, float(np.linalg.norm(points - middle, axis=1).max())))
    return Pieces(hulls, np.array([c for c, _ in balls]), np.array([r for _, r in balls]))


def pieces_distance(a: Pieces, Ma: pin.SE3, b: Pieces, Mb: pin.SE3) -> float:
    """A lower bound [m] of the distance of two shapes placed at ``Ma`` and ``Mb``, from
    their pieces: the least of the pieces' distances (coal's GJK), pairs taken nearest
    balls first, and a pair skipped where the balls' distance alone reaches the least
    found; from the first pair of pieces that meet, coal's answer for them (0 or below)."""
    import coal

    ca = a.centres @ Ma.rotation.T + Ma.translation
    cb = b.centres @ Mb.rotation.T + Mb.translation
    apart = np.linalg.norm(ca[:, None] - cb[None], axis=2) - a.radii[:, None] - b.radii[None]
    order = np.argsort(apart, axis=None)
    Ta = coal.Transform3s(Ma.rotation, Ma.translation)
    Tb = coal.Transform3s(Mb.rotation, Mb.translation)
    request, best = coal.DistanceRequest(), np.inf
    for flat in order.tolist():
        i, j = divmod(flat, len(b.hulls))
        if apart[i, j] >= best:
            break
        result = coal.DistanceResult()
        coal.distance(a.hulls[i], Ta, b.hulls[j], Tb, request, result)
        best = min(best, result.min_distance)  # below 0: two pieces overlap
        if best <= 0.0:
            break
    return float(best)
