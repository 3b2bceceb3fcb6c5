"""Lower bounds of the distance of two convex point sets (numba): the compiled step of the
exact shapes' certificate (:class:`toolkit.planning.sweep.ExactSweep`) on a robot's meshes
held by their convex hulls and convex pieces (:mod:`toolkit.collision.convex`).

Why every answer is a lower bound, whatever the iteration did: for two point sets A and B
and any unit direction d, every a of A and b of B have |a - b| >= d.(a - b) >= min over A
of d.a - max over B of d.b; the convex hulls of A and B are no nearer (a linear function
takes its least on a hull at one of its points). The search for a good d is Gilbert,
Johnson and Keerthi's (GJK: IEEE J. Robotics and Automation 4(2), 1988) on the Minkowski
difference A - B, its simplex's nearest point found over all its faces; it only picks the
direction, so a slow or stopped search gives a smaller bound, never a wrong one. Each
set's least point along a direction is found over its points in its joint's frame
(``W`` rows, as :mod:`~toolkit.collision.bound_kernels`' frames).

Arrays (:class:`~toolkit.collision.convex.ConvexSets`): ``sets`` (S, 3) per shape its hull
(a piece index, -1: no convex set) and the range of its pieces; ``vstart`` (sets + 1,)
each piece's first point in ``verts`` (V, 3), in the joint's frame; ``ball`` (pieces, 4) a
ball holding each piece (centre in the joint's frame, radius)."""

from __future__ import annotations

import math

import numpy as np

from ..kinematics import inline_kernel, kernel
from .bound_kernels import world

__all__ = ["PIECES", "ROUND", "STEPS", "both_sets", "convex_gaps", "scratch", "set_lower"]

ROUND = 1e-9
"""[m] Taken off every bound: room for rounding in the frames and in the hulls' points (a
point of a mesh that the hull's computation judged on a face may lie outside it by the
order of 1e-15 m)."""
STEPS = 24
"""The most GJK steps one pair of sets takes."""
PIECES = 4
"""The most pieces a shape's set may have (one direction kept per pair of pieces)."""


@inline_kernel
def _least(W, r, verts, v0, v1, dx, dy, dz):
    """(the point of set v0:v1 (joint row r's frame) least along d, in the world; d.it)."""
    lx = W[r, 0] * dx + W[r, 3] * dy + W[r, 6] * dz
    ly = W[r, 1] * dx + W[r, 4] * dy + W[r, 7] * dz
    lz = W[r, 2] * dx + W[r, 5] * dy + W[r, 8] * dz
    best, bi = np.inf, v0
    for i in range(v0, v1):
        s = lx * verts[i, 0] + ly * verts[i, 1] + lz * verts[i, 2]
        if s < best:
            best, bi = s, i
    return world(W, r, verts[bi, 0], verts[bi, 1], verts[bi, 2])


@inline_kernel
def _difference(W, ra, rb, verts, a0, a1, b0, b1, dx, dy, dz, out, m):
    """The point of A - B least along d into out[m]; the lower bound d gives [m] (d unit)."""
    ax, ay, az = _least(W, ra, verts, a0, a1, dx, dy, dz)
    bx, by, bz = _least(W, rb, verts, b0, b1, -dx, -dy, -dz)
    out[m, 0], out[m, 1], out[m, 2] = ax - bx, ay - by, az - bz
    return dx * (ax - bx) + dy * (ay - by) + dz * (az - bz)


@kernel
def _nearest(S, m, G, mu, keep):
    """The point of the hull of S[:m] (m <= 4) nearest the origin: over every subset of the
    points, the nearest point of its affine hull where its weights are all >= 0, the least
    of those (each lies in the hull, and the hull's nearest point is one of them). S is
    cut to that subset's points; returns (x, y, z, how many). ``G`` (3, 4), ``mu`` (3,),
    ``keep`` (4, 3): scratch."""
    best, chosen = np.inf, 1
    bx, by, bz = S[0, 0], S[0, 1], S[0, 2]
    for mask in range(1, 1 << m):
        p0, k = -1, 0
        for i in range(m):
            if mask >> i & 1:
                if p0 < 0:
                    p0 = i
                else:
                    keep[k, 0] = S[i, 0] - S[p0, 0]  # the edges p_i - p_0
                    keep[k, 1] = S[i, 1] - S[p0, 1]
                    keep[k, 2] = S[i, 2] - S[p0, 2]
                    k += 1
        for i in range(k):  # the normal equations of the edges' weights
            for j in range(k):
                G[i, j] = (keep[i, 0] * keep[j, 0] + keep[i, 1] * keep[j, 1]
                           + keep[i, 2] * keep[j, 2])  # fmt: skip
            G[i, 3] = -(keep[i, 0] * S[p0, 0] + keep[i, 1] * S[p0, 1] + keep[i, 2] * S[p0, 2])
        if not _solve(G, k, mu):
            continue
        w0, x, y, z = 1.0, S[p0, 0], S[p0, 1], S[p0, 2]
        ok = True
        for i in range(k):
            w0 -= mu[i]
            ok = ok and mu[i] >= 0.0
            x += mu[i] * keep[i, 0]
            y += mu[i] * keep[i, 1]
            z += mu[i] * keep[i, 2]
        if not ok or w0 < 0.0:
            continue
        d = x * x + y * y + z * z
        if d < best:
            best, chosen, bx, by, bz = d, mask, x, y, z
    n = 0
    for i in range(m):
        if chosen >> i & 1:
            keep[n, 0], keep[n, 1], keep[n, 2] = S[i, 0], S[i, 1], S[i, 2]
            n += 1
    for i in range(n):
        S[i, 0], S[i, 1], S[i, 2] = keep[i, 0], keep[i, 1], keep[i, 2]
    return bx, by, bz, n


@inline_kernel
def _solve(G, k, x):
    """Whether the k x k system G[:k, :k] x = G[:k, 3] (k <= 3) has a solution, solved into
    x by Gaussian elimination with partial pivoting (G overwritten); False where it is
    singular."""
    for c in range(k):
        p = c
        for i in range(c + 1, k):
            if abs(G[i, c]) > abs(G[p, c]):
                p = i
        if abs(G[p, c]) < 1e-30:
            return False
        for j in range(4):
            G[c, j], G[p, j] = G[p, j], G[c, j]
        for i in range(c + 1, k):
            f = G[i, c] / G[c, c]
            for j in range(c, 4):
                G[i, j] -= f * G[c, j]
    for c in range(k - 1, -1, -1):
        s = G[c, 3]
        for j in range(c + 1, k):
            s -= G[c, j] * x[j]
        x[c] = s / G[c, c]
    return True


@kernel
def set_lower(W, ra, rb, verts, a0, a1, b0, b1, d, target, scratch):
    """A lower bound [m] of the distance of sets a0:a1 (joint row ra) and b0:b1 (row rb):
    the best of the directions GJK tries (module doc), starting from ``d`` (3,) (pointing
    from the second set to the first: the best direction of the pair's last call; zero:
    none), which it leaves holding the best one; it stops at ``target``, when the bound
    meets the distance found, or after :data:`STEPS` steps. ``scratch``: :func:`scratch`."""
    S, G, mu, keep = scratch
    n = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
    if n == 0.0:
        d[0], n = 1.0, 1.0
    dx, dy, dz = d[0] / n, d[1] / n, d[2] / n
    lower = _difference(W, ra, rb, verts, a0, a1, b0, b1, dx, dy, dz, S, 0)
    d[0], d[1], d[2] = dx, dy, dz
    m, vx, vy, vz = 1, S[0, 0], S[0, 1], S[0, 2]
    for _ in range(STEPS):
        vv = vx * vx + vy * vy + vz * vz
        if lower >= target or vv <= 1e-24 or m == 4:
            break
        nv = math.sqrt(vv)
        dx, dy, dz = vx / nv, vy / nv, vz / nv
        got = _difference(W, ra, rb, verts, a0, a1, b0, b1, dx, dy, dz, S, m)
        if got > lower:
            lower, d[0], d[1], d[2] = got, dx, dy, dz
        if nv - got <= 1e-9 * nv:
            break
        vx, vy, vz, m = _nearest(S, m + 1, G, mu, keep)
        if vx * vx + vy * vy + vz * vz >= vv * (1.0 - 1e-12):
            break
    return lower


def scratch() -> tuple[np.ndarray, ...]:
    """The scratch arrays of :func:`set_lower` (a simplex and its solver's)."""
    return np.empty((4, 3)), np.empty((3, 4)), np.empty(3), np.empty((4, 3))


@inline_kernel
def both_sets(sets, a, b):
    """Whether shapes a and b are both convex sets (``sets``: :class:`~toolkit.collision.
    convex.ConvexSets`' first array; a shape past its rows has none)."""
    n = sets.shape[0]
    return a < n and b < n and sets[a, 0] >= 0 and sets[b, 0] >= 0


@kernel
def convex_gaps(W, row, P, convex, first, second, ks, need, gaps, dirs):
    """For each pair k of ``ks``: ``gaps[k]`` raised to a lower bound [m] of the distance
    of its two shapes' convex sets where both have one: their hulls' (:func:`set_lower`),
    then where that falls short of ``need[k]``, the least over their pieces' pairs (a
    pair's balls' distance, or its sets' bound where the balls come nearer than the least
    found and the need), less :data:`ROUND`. ``dirs`` (pairs, 1 + PIECES**2, 3): each
    pair's directions (hulls first, then per pair of pieces), kept between calls. ``P``:
    the placed boxes (their centres start a first direction)."""
    sets, vstart, verts = convex[0], convex[1], convex[2]
    work = (np.empty((4, 3)), np.empty((3, 4)), np.empty(3), np.empty((4, 3)))
    order = np.empty(PIECES * PIECES, np.int64)
    apart = np.empty(PIECES * PIECES)
    for n in range(ks.shape[0]):
        k = ks[n]
        a, b = first[k], second[k]
        if not both_sets(sets, a, b):
            continue  # a shape without a set (a sphere, a capsule): coal answers
        ha, hb = sets[a, 0], sets[b, 0]
        ra, rb = row[a], row[b]
        d = dirs[k, 0]
        if d[0] == 0.0 and d[1] == 0.0 and d[2] == 0.0:
            d[0], d[1], d[2] = P[a, 0] - P[b, 0], P[a, 1] - P[b, 1], P[a, 2] - P[b, 2]
        g = set_lower(W, ra, rb, verts, vstart[ha], vstart[ha + 1], vstart[hb], vstart[hb + 1],
                      d, need[k] + ROUND, work)  # fmt: skip
        split = sets[a, 2] - sets[a, 1] > 1 or sets[b, 2] - sets[b, 1] > 1
        if g < need[k] + ROUND and split:
            g = max(g, _pieces_lower(W, ra, rb, convex, sets[a], sets[b], need[k] + ROUND,
                                     dirs[k], work, order, apart))  # fmt: skip
        gaps[k] = max(gaps[k], g - ROUND)


@kernel
def _pieces_lower(W, ra, rb, convex, sa, sb, target, dirs, work, order, apart):
    """The least over the pieces' pairs of shapes with sets ``sa`` and ``sb`` of a lower
    bound of their distance, nearest balls first, each pair's sets asked only where its
    balls come nearer than both the least found and ``target``."""
    _, vstart, verts, ball = convex
    na, nb = sa[2] - sa[1], sb[2] - sb[1]
    for i in range(na):
        ci = world(W, ra, ball[sa[1] + i, 0], ball[sa[1] + i, 1], ball[sa[1] + i, 2])
        for j in range(nb):
            cj = world(W, rb, ball[sb[1] + j, 0], ball[sb[1] + j, 1], ball[sb[1] + j, 2])
            c = math.sqrt((ci[0] - cj[0]) ** 2 + (ci[1] - cj[1]) ** 2 + (ci[2] - cj[2]) ** 2)
            apart[i * nb + j] = c - ball[sa[1] + i, 3] - ball[sb[1] + j, 3]
    m = na * nb
    for t in range(m):  # nearest balls first (insertion sort: at most PIECES**2 pairs)
        order[t] = t
        u = t
        while u > 0 and apart[order[u - 1]] > apart[order[u]]:
            order[u - 1], order[u] = order[u], order[u - 1]
            u -= 1
    best = np.inf
    for t in range(m):
        p = order[t]
        if apart[p] >= best or apart[p] >= target:
            best = min(best, apart[p])
            break
        i, j = p // nb, p % nb
        pa, pb = sa[1] + i, sb[1] + j
        d = dirs[1 + i * PIECES + j]
        if d[0] == 0.0 and d[1] == 0.0 and d[2] == 0.0:
            ca = world(W, ra, ball[pa, 0], ball[pa, 1], ball[pa, 2])
            cb = world(W, rb, ball[pb, 0], ball[pb, 1], ball[pb, 2])
            d[0], d[1], d[2] = ca[0] - cb[0], ca[1] - cb[1], ca[2] - cb[2]
        g = set_lower(W, ra, rb, verts, vstart[pa], vstart[pa + 1], vstart[pb], vstart[pb + 1],
                      d, min(best, target), work)  # fmt: skip
        best = min(best, max(g, apart[p]))
    return best
