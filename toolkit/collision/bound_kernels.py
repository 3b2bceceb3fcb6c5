"""Compiled pre-filter of the collision checks (numba): bounding volumes per shape.

Every shape of a checker (a link's, or a scene object's) is bounded by an oriented box
(its local axis-aligned box, from coal) and by the sphere around that box. A pair of
shapes is certainly apart when one shape's sphere does not reach the other's box, or when
an axis separates their boxes (the 15 axes of the separating-axis test). A
configuration whose checked pairs are all certainly apart is free of collision without
asking coal. A box, sphere or cylinder also holds an inner sphere (centred, as large as it
fits); when the inner spheres of a checked pair overlap, the configuration is certainly
in collision. Coal decides the others, on the pairs no bound proves apart, which
:func:`decide_batch` lists (at most :data:`NEAR` a configuration). The answer is never
changed, only skipped (``tests/collision/test_collision.py``,
``tests/collision/test_requests.py``).

Packed arrays, one row per shape: ``row`` the shape's joint row in the kernels' frame
array ``W`` (:mod:`toolkit.kinematics.kernels`, the base is row n); ``box`` (n_shapes, 15):
the box's centre (3) and rotation (9, row-major) in the joint's frame, its half extents (3); and
``radius`` (n_shapes, 3): the outer sphere's radius (centred on the box), the inner
sphere's (0 for a mesh) and the kind of solid the shape is
(:data:`~toolkit.collision.solid_kernels.SOLIDS`). Pairs: ``first``, ``second``.

A pair the boxes leave undecided is tried once more with the shapes' sphere covers
(:mod:`toolkit.collision.covers`: a few spheres holding each shape's surface): when every
sphere of one shape's cover misses the other's box, and that box's centre lies outside the
sphere holding the whole cover, the two are apart. (The surface misses the box, so the box,
being connected, lies wholly inside the shape or wholly outside it; inside, its centre
would lie in the holding sphere.) Covers: ``cstart`` (n_shapes + 1,) each shape's first
sphere (none: no cover, a plane), ``csphere`` (S, 4) their centres in the joint's frame
and radii, ``hold`` (n_shapes, 4) the sphere holding each cover.

A pair still undecided is tried for a certain collision (:func:`decide_batch` only): a
point of one shape's surface (``wpoint`` (P, 3) in its joint's frame, those held by
cover sphere s from ``wstart[s]``) deeper than :data:`DEPTH` inside the other, a solid
(a box, sphere, cylinder or capsule: a scene's obstacle, a floor;
:mod:`toolkit.collision.solid_kernels`) proves they intersect:
the surface's triangle through that point enters the solid. Only the spheres of the
cover that reach into the solid's box have their points tried. A link sunk in a table
is decided so, where coal took 10-20 us a pair.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..kinematics import inline_kernel, kernel, kernels, twin_kernel
from .solid_kernels import DEPTH, in_solid

frames = kernels.frames

CLOSE, FREE, HIT = 0, 1, 2
"""A configuration's answer: undecided (coal decides), certainly free, certainly colliding."""

MARGIN = 1e-9  # [m]: closer than this counts as touching (coal decides)
NEAR = 16
"""The most pairs :func:`decide_batch` lists per undecided configuration (coal checks those
only; a configuration with more has every pair checked)."""
_CHUNK = 256


@inline_kernel
def _place(W, row, box, g, out):
    """World centre (3) and rotation (9) of shape g's box into out (12)."""
    r = row[g]
    for a in range(3):
        s = W[r, 9 + a]
        for b in range(3):
            s += W[r, 3 * a + b] * box[g, b]
        out[a] = s
        for c in range(3):
            t = 0.0
            for b in range(3):
                t += W[r, 3 * a + b] * box[g, 3 + 3 * b + c]
            out[3 + 3 * a + c] = t


@inline_kernel
def _gap2(P, box, b, x, y, z):
    """The squared distance from the point (x, y, z) to shape b's placed box (0 inside)."""
    gap2 = 0.0
    for c in range(3):  # the point in the box's axes, outside the box
        d = (P[b, 3 + c] * (x - P[b, 0]) + P[b, 6 + c] * (y - P[b, 1])
             + P[b, 9 + c] * (z - P[b, 2]))  # fmt: skip
        out = abs(d) - box[b, 12 + c]
        if out > 0.0:
            gap2 += out * out
    return gap2


@inline_kernel
def _apart(P, box, radius, a, b, margin):
    """Whether shape a's sphere misses shape b's box by more than ``margin`` (P: placed
    centres and rotations)."""
    reach = radius[a, 0] + margin
    return _gap2(P, box, b, P[a, 0], P[a, 1], P[a, 2]) > reach * reach


@kernel
def _separated(P, box, a, b, margin):
    """Whether boxes a and b are more than ``margin`` apart along one of the 15 separating
    axes (their 6 face normals and the 9 cross products of their edges)."""
    return _axis_gap(P, box, a, b, margin) > margin


@kernel
def _axis_gap(P, box, a, b, stop):
    """The widest gap [m] between boxes a and b along the 15 separating axes, the first
    one over ``stop`` as soon as it is found (negative where they overlap on every one)."""
    widest = -np.inf
    t0, t1, t2 = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1], P[b, 2] - P[a, 2]
    for kind in range(15):
        if kind < 3:  # a's axis i
            ax, ay, az = P[a, 3 + kind], P[a, 6 + kind], P[a, 9 + kind]
        elif kind < 6:  # b's axis j
            ax, ay, az = P[b, 3 + kind - 3], P[b, 6 + kind - 3], P[b, 9 + kind - 3]
        else:  # a's axis i x b's axis j
            i, j = (kind - 6) // 3, (kind - 6) % 3
            ux, uy, uz = P[a, 3 + i], P[a, 6 + i], P[a, 9 + i]
            vx, vy, vz = P[b, 3 + j], P[b, 6 + j], P[b, 9 + j]
            ax, ay, az = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
            norm = np.sqrt(ax * ax + ay * ay + az * az)
            if norm < 1e-9:  # parallel edges: the face axes decide
                continue
            ax, ay, az = ax / norm, ay / norm, az / norm
        ra = 0.0
        rb = 0.0
        for c in range(3):  # the boxes' half widths along the axis
            ra += box[a, 12 + c] * abs(P[a, 3 + c] * ax + P[a, 6 + c] * ay + P[a, 9 + c] * az)
            rb += box[b, 12 + c] * abs(P[b, 3 + c] * ax + P[b, 6 + c] * ay + P[b, 9 + c] * az)
        widest = max(widest, abs(t0 * ax + t1 * ay + t2 * az) - ra - rb)
        if widest > stop:
            return widest
    return widest


@inline_kernel
def _spheres_apart(P, radius, a, b):
    """Whether the spheres about shapes a's and b's boxes lie more than :data:`MARGIN`
    apart (then so do the shapes, and their inner spheres do not overlap): the cheapest
    bound, which settles most pairs of a configuration."""
    d2 = (P[a, 0] - P[b, 0]) ** 2 + (P[a, 1] - P[b, 1]) ** 2 + (P[a, 2] - P[b, 2]) ** 2
    reach = radius[a, 0] + radius[b, 0] + MARGIN
    return d2 > reach * reach


@inline_kernel
def _inside(P, radius, a, b):
    """Whether the inner spheres of shapes a and b overlap (both primitives)."""
    ra, rb = radius[a, 1], radius[b, 1]
    if ra <= 0.0 or rb <= 0.0:
        return False
    d2 = 0.0
    for c in range(3):
        d2 += (P[a, c] - P[b, c]) ** 2
    reach = ra + rb - MARGIN
    return reach > 0.0 and d2 < reach * reach


@kernel
def _world(W, r, x, y, z):
    """A point of joint row r's frame in the world."""
    return (W[r, 9] + W[r, 0] * x + W[r, 1] * y + W[r, 2] * z,
            W[r, 10] + W[r, 3] * x + W[r, 4] * y + W[r, 5] * z,
            W[r, 11] + W[r, 6] * x + W[r, 7] * y + W[r, 8] * z)  # fmt: skip


@kernel
def _covered_apart(W, row, P, box, covers, a, b, margin):
    """Whether shape a's cover misses shape b's box by more than ``margin`` with b's box
    outside a (module doc)."""
    return _cover_gap(W, row, P, box, covers, a, b, margin) > margin


@kernel
def _cover_gap(W, row, P, box, covers, a, b, stop):
    """The least gap [m] between a sphere of shape a's cover and shape b's box, with b's box
    outside a (module doc); the first one at or below ``stop`` as soon as it is found;
    -inf without a cover or with b's box centre in the sphere holding it."""
    cstart, csphere, hold = covers
    if cstart[a + 1] == cstart[a]:
        return -np.inf
    r = row[a]
    hx, hy, hz = _world(W, r, hold[a, 0], hold[a, 1], hold[a, 2])
    dx, dy, dz = P[b, 0] - hx, P[b, 1] - hy, P[b, 2] - hz
    reach = hold[a, 3] + MARGIN
    if dx * dx + dy * dy + dz * dz <= reach * reach:
        return -np.inf
    least = np.inf
    for s in range(cstart[a], cstart[a + 1]):
        x, y, z = _world(W, r, csphere[s, 0], csphere[s, 1], csphere[s, 2])
        least = min(least, np.sqrt(_gap2(P, box, b, x, y, z)) - csphere[s, 3])
        if least <= stop:
            return least
    return least


@kernel
def _outside_hold(W, covers, ra, rb, a, b):
    """Whether a sphere of shape b's cover lies wholly outside the sphere holding shape
    a's: a corner of b's (circumscribing) surface outside a's, so b not inside a."""
    cstart, csphere, hold = covers
    hx, hy, hz = _world(W, ra, hold[a, 0], hold[a, 1], hold[a, 2])
    for s in range(cstart[b], cstart[b + 1]):
        x, y, z = _world(W, rb, csphere[s, 0], csphere[s, 1], csphere[s, 2])
        reach = hold[a, 3] + csphere[s, 3] + MARGIN
        if (x - hx) ** 2 + (y - hy) ** 2 + (z - hz) ** 2 > reach * reach:
            return True
    return False


@kernel
def _covers_gap(W, row, covers, a, b, stop):
    """The least gap [m] between a sphere of shape a's cover and one of shape b's; the first
    at or below ``stop`` as soon as it is found; -inf without both covers, or where one
    shape could lie inside the other (no sphere of either's cover wholly outside the sphere
    holding the other's). The covers hold the two surfaces (or the prisms circumscribing
    them): surfaces apart, neither inside the other, the shapes are apart by the gap."""
    cstart, csphere, _ = covers
    if cstart[a + 1] == cstart[a] or cstart[b + 1] == cstart[b]:
        return -np.inf
    ra, rb = row[a], row[b]
    if not (_outside_hold(W, covers, ra, rb, a, b) and _outside_hold(W, covers, rb, ra, b, a)):
        return -np.inf
    least = np.inf
    for s in range(cstart[a], cstart[a + 1]):
        x, y, z = _world(W, ra, csphere[s, 0], csphere[s, 1], csphere[s, 2])
        for t in range(cstart[b], cstart[b + 1]):
            u, v, w = _world(W, rb, csphere[t, 0], csphere[t, 1], csphere[t, 2])
            d = np.sqrt((x - u) ** 2 + (y - v) ** 2 + (z - w) ** 2)
            least = min(least, d - csphere[s, 3] - csphere[t, 3])
            if least <= stop:
                return least
    return least


@kernel
def _deep_apart(W, row, P, box, covers, a, b):
    """Whether the boxes' separating axes or either cover (module doc) prove shapes a and b
    more than :data:`MARGIN` apart: what a pair needs where neither :func:`_apart` does.

    Callers write the cheap bounds in their own loop (:func:`_spheres_apart`, then
    :func:`_apart` both ways: most pairs end there) and call this one past them. Not an
    inline helper holding all of them: numba's inlining binds a helper's array arguments
    afresh at each use, and where the helper hands them on to a call, their reference
    counts are kept at every pair (30 ns each, the pre-filter 2.5 times slower among a
    bookshelf's boards)."""
    return (
        _separated(P, box, a, b, MARGIN)
        or _covered_apart(W, row, P, box, covers, a, b, MARGIN)
        or _covered_apart(W, row, P, box, covers, b, a, MARGIN)
        or _covers_gap(W, row, covers, a, b, MARGIN) > MARGIN
    )


@kernel
def _witnessed(W, row, P, box, radius, covers, witness, a, b):
    """Whether a point of shape a's surface lies inside shape b, a solid (``radius[b, 2]``
    not 0: :func:`_pierced` asks only those), deeper than :data:`DEPTH` (module doc): the
    points of the cover spheres that reach into b's box."""
    cstart, csphere = covers[0], covers[1]
    wstart, wpoint = witness
    r = row[a]
    for s in range(cstart[a], cstart[a + 1]):
        if wstart[s + 1] == wstart[s]:
            continue
        x, y, z = _world(W, r, csphere[s, 0], csphere[s, 1], csphere[s, 2])
        reach = csphere[s, 3] - DEPTH
        if reach <= 0.0 or _gap2(P, box, b, x, y, z) >= reach * reach:
            continue  # the sphere holding these points stays out of b's box
        for w in range(wstart[s], wstart[s + 1]):
            x, y, z = _world(W, r, wpoint[w, 0], wpoint[w, 1], wpoint[w, 2])
            if in_solid(P, box, radius, b, x, y, z):
                return True
    return False


@kernel
def _pierced(W, row, P, box, radius, covers, witness, a, b):
    """Whether a point of either shape's surface lies inside the other, a solid
    (:func:`_witnessed`; a pair without a solid costs a comparison)."""
    if radius[b, 2] != 0.0 and _witnessed(W, row, P, box, radius, covers, witness, a, b):
        return True
    return radius[a, 2] != 0.0 and _witnessed(W, row, P, box, radius, covers, witness, b, a)


@kernel
def _decide_rows(Q, ints, flts, row, box, radius, first, second, order, covers, witness, out,
                 listed, start, stop):  # fmt: skip
    W = np.empty((ints.shape[0] + 1, 15))
    P = np.empty((row.shape[0], 12))
    hint = -1  # the pair that proved the last row colliding: tried first (rows come in runs)
    for i in range(start, stop):
        frames(Q[i], ints, flts, W)
        for g in range(row.shape[0]):
            _place(W, row, box, g, P[g])
        state, n = FREE, 0
        if hint >= 0 and _pierced(W, row, P, box, radius, covers, witness, first[hint],
                                  second[hint]):  # fmt: skip
            out[i], listed[i, 0] = HIT, 0
            continue
        for k in order:  # the pairs with a solid first: a link in a table ends the row early
            a, b = first[k], second[k]
            if _spheres_apart(P, radius, a, b):
                continue
            if _inside(P, radius, a, b):
                state = HIT
                break
            if n <= NEAR:  # past NEAR, coal checks every pair: only a HIT matters
                if _apart(P, box, radius, a, b, MARGIN) or _apart(P, box, radius, b, a, MARGIN):
                    continue
                if _deep_apart(W, row, P, box, covers, a, b):
                    continue
            if _pierced(W, row, P, box, radius, covers, witness, a, b):
                state, hint = HIT, k
                break
            state = CLOSE
            n += 1
            if n <= NEAR:
                listed[i, n] = k
        out[i] = state
        listed[i, 0] = n


@inline_kernel
def _placed(q, ints, flts, row, box, W, P):
    """Every joint's frame at q into W and every shape's box into P (a shape fixed to the
    base only where P holds NaN: the first time)."""
    frames(q, ints, flts, W)
    base = ints.shape[0]
    for g in range(row.shape[0]):
        if row[g] != base or np.isnan(P[g, 0]):
            _place(W, row, box, g, P[g])


@kernel
def certainly_free(q, packed, runs, W, P, last, near):
    """Whether configuration q (nq,) is certainly free: every checked pair certainly more
    than :data:`MARGIN` apart (the pre-filter's FREE; False at the first pair that is
    not). ``packed``: the tuple of :meth:`toolkit.collision.Bounds.packed`; ``runs`` (R,
    2): the pairs as runs (first pair, length) of one shape against shapes of consecutive
    indices (:func:`pair_runs`), whose spheres about the boxes are measured together,
    without a branch, before the near ones are looked at; ``W`` (joint rows + 1, 15):
    scratch; ``P`` (shapes, 12): the placed boxes, NaN at first and kept between the calls
    of one ``packed`` (a shape fixed to the base is placed once); ``last`` (1,): the pair
    that refused the last configuration, tried first (a search's next configuration lies
    near its last, and mostly meets the same obstacle), then kept; ``near`` (the longest
    run,): scratch. A conservative test: False may be free on the exact shapes, True never
    collides on them."""
    ints, flts, row, box, radius, first, second, cstart, csphere, hold = packed
    _placed(q, ints, flts, row, box, W, P)
    covers = (cstart, csphere, hold)
    if first.shape[0] == 0:
        return True
    hint = last[0] if 0 <= last[0] < first.shape[0] else 0
    for r in range(-1, runs.shape[0]):  # the hint first (a run of one), then every run
        k0, length = (hint, 1) if r < 0 else (runs[r, 0], runs[r, 1])
        a, b0 = first[k0], second[k0]
        ax, ay, az, reach = P[a, 0], P[a, 1], P[a, 2], radius[a, 0] + MARGIN
        for j in range(length):  # the spheres about both boxes: near, or certainly apart
            b = b0 + j
            d2 = (P[b, 0] - ax) ** 2 + (P[b, 1] - ay) ** 2 + (P[b, 2] - az) ** 2
            near[j] = d2 <= (reach + radius[b, 0]) ** 2
        for j in range(length):
            if not near[j]:
                continue
            b = b0 + j
            if _inside(P, radius, a, b):
                last[0] = k0 + j
                return False
            if _apart(P, box, radius, a, b, MARGIN) or _apart(P, box, radius, b, a, MARGIN):
                continue
            if not _deep_apart(W, row, P, box, covers, a, b):
                last[0] = k0 + j
                return False
    return True


def pair_runs(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """(R, 2) int64: the pairs (first[k], second[k]) in order as runs (first pair, length)
    of one shape against shapes of consecutive indices (a link against a scene's obstacles
    one after another); a pair outside any such run is a run of one."""
    first, second = np.asarray(first, dtype=np.int64), np.asarray(second, dtype=np.int64)
    goes_on = (first[1:] == first[:-1]) & (second[1:] == second[:-1] + 1)
    starts = np.flatnonzero(np.concatenate([[True], ~goes_on]))[: len(first)]
    lengths = np.diff(np.append(starts, len(first)))
    return np.stack([starts, lengths], axis=1).astype(np.int64).reshape(-1, 2)


# the bounds the certificates' gaps read (:mod:`toolkit.collision.gap_kernels`)
placed, gap2, axis_gap, cover_gap, covers_gap = _placed, _gap2, _axis_gap, _cover_gap, _covers_gap
world = _world  # and the convex sets' (:mod:`toolkit.collision.convex_kernels`)


@twin_kernel
def decide_batch(Q, ints, flts, row, box, radius, first, second, cstart, csphere, hold, wstart,
                 wpoint, order):  # fmt: skip
    """((N,) states CLOSE, FREE or HIT; (N, 1 + :data:`NEAR`) int32: per configuration the
    count of its pairs that no bound proves apart, then those pairs (where the count is at
    most NEAR; a CLOSE configuration's others are certainly apart); a twin: over every core,
    or on the calling thread). ``order``: the pairs in the order they are tried."""
    N = Q.shape[0]
    out = np.zeros(N, dtype=np.int8)
    listed = np.zeros((N, NEAR + 1), dtype=np.int32)
    for c in prange((N + _CHUNK - 1) // _CHUNK):
        stop = min(N, (c + 1) * _CHUNK)
        _decide_rows(Q, ints, flts, row, box, radius, first, second, order,
                     (cstart, csphere, hold), (wstart, wpoint), out, listed, c * _CHUNK,
                     stop)  # fmt: skip
    return out, listed
