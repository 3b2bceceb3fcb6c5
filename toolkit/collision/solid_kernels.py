"""Whether a point lies inside a solid shape of the collision pre-filter
(:mod:`toolkit.collision.bound_kernels`), exactly, from the shape's packed box: the test by
which a point of a link's surface inside an obstacle proves a collision."""

from __future__ import annotations

from ..kinematics import inline_kernel

__all__ = ["DEPTH", "SOLIDS", "in_solid"]

DEPTH = 1e-5
"""[m]: how deep inside a solid a surface point must lie to prove a collision (coal's
own answer is left to shallower ones)."""
SOLIDS = ("none", "box", "sphere", "cylinder", "capsule")
"""The kinds of solid in ``radius[:, 2]``: a point inside one is tested exactly (a
cylinder's and capsule's axis is their box's z)."""


@inline_kernel
def in_solid(P, box, radius, b, x, y, z):
    """Whether the point (x, y, z) lies deeper than :data:`DEPTH` inside shape b, a solid
    of kind ``radius[b, 2]`` (:data:`SOLIDS`) centred on its placed box P[b]."""
    kind = radius[b, 2]
    d0 = P[b, 3] * (x - P[b, 0]) + P[b, 6] * (y - P[b, 1]) + P[b, 9] * (z - P[b, 2])
    d1 = P[b, 4] * (x - P[b, 0]) + P[b, 7] * (y - P[b, 1]) + P[b, 10] * (z - P[b, 2])
    d2 = P[b, 5] * (x - P[b, 0]) + P[b, 8] * (y - P[b, 1]) + P[b, 11] * (z - P[b, 2])
    h0, h1, h2 = box[b, 12] - DEPTH, box[b, 13] - DEPTH, box[b, 14] - DEPTH
    if kind == 1.0:  # a box: its own bounding box
        return abs(d0) < h0 and abs(d1) < h1 and abs(d2) < h2
    if kind == 2.0:  # a sphere
        r = radius[b, 1] - DEPTH
        return r > 0.0 and d0 * d0 + d1 * d1 + d2 * d2 < r * r
    if kind == 3.0:  # a cylinder about z: box half extents (r, r, half length)
        return abs(d2) < h2 and h0 > 0.0 and d0 * d0 + d1 * d1 < h0 * h0
    if kind == 4.0:  # a capsule about z: (r, r, half length + r)
        half = box[b, 14] - box[b, 12]
        t = min(max(d2, -half), half)
        return h0 > 0.0 and d0 * d0 + d1 * d1 + (d2 - t) * (d2 - t) < h0 * h0
    return False
