"""The root search of :mod:`toolkit.ik.analytic.search` compiled (numba): every sign change
of the four curves' residual e(q6) over the grid and beside each curve's edges, refined to
round-off, in one call per target (the same brackets, in the same order, by the same
steps as the search's description; the tests compare the two)."""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import inline_kernel, kernel
from .family_kernels import curve_constants, curve_elbow, curve_ratio, curve_residual, pair_curves
from .subproblem_kernels import dot, mm, mtm, mv, rotation, sp1, usable

__all__ = ["meeting_pairs", "search_roots", "search_rows"]

BISECTIONS, SECANTS, EDGE_BISECTIONS, EDGE_SAMPLES = 12, 10, 30, 24
SAMPLES = 512
"""How many angles of q6 each curve is sampled at (:data:`toolkit.ik.analytic.search.SAMPLES`)."""
PER_CURVE = 19
"""The most roots of one curve a branch's roots can name (its label's "root 1" to "root 19",
in :func:`toolkit.ik.analytic.door_kernels.label_code`); a target with more, or with more
branches than ``out`` has rows, is left to the Python form."""


@inline_kernel
def _e(h, o, tip_p, T, q6, curve, shared, work):
    """The residual of ``curve`` at one q6 (NaN where the curve does not exist): the steps
    of :func:`pair_curves` for that curve alone (the same helpers, so the same bits)."""
    V, M = work
    ratio = curve_ratio(h, o, tip_p, T, shared, q6, V, M[4], M[6])
    if abs(ratio) > 1.0 + 1e-12:
        return np.nan
    delta = math.acos(max(-1.0, min(1.0, ratio)))
    phi, s2 = shared[2][5], shared[2][3]
    q3 = phi + delta if curve // 2 == 0 else phi - delta
    rest = curve_elbow(h, o, shared, q3, V, M[5])
    if rest < -1e-12:
        return np.nan
    z = math.sqrt(max(rest, 0.0) / s2)
    return curve_residual(h, shared, z if curve % 2 == 0 else -z, V, M[5], M[6], M)[0]


@inline_kernel
def _same(x, y):
    """np.sign(x) == np.sign(y), NaN never equal."""
    return np.sign(x) == np.sign(y)


@inline_kernel
def _refine(h, o, tip_p, T, a, b, fa, fb, curve, shared, work):
    """The root in [a, b] (e changes sign across it): halvings, then regula falsi with the
    Illinois rule (the end kept twice in a row has its value halved)."""
    for _ in range(BISECTIONS):
        c = 0.5 * (a + b)
        fc = _e(h, o, tip_p, T, c, curve, shared, work)
        if np.sign(fc) * np.sign(fa) <= 0:  # the root in [a, c]
            b, fb = c, fc
        else:
            a, fa = c, fc
    side = 0.0
    for _ in range(SECANTS):
        c = (fa * b - fb * a) / (fa - fb) if fa != fb else a
        fc = _e(h, o, tip_p, T, c, curve, shared, work)
        with_b = _same(fc, fb)
        with_a = (not with_b) and _same(fc, fa)
        if with_b and side == -1.0:
            fa = 0.5 * fa
        if with_a and side == 1.0:
            fb = 0.5 * fb
        if with_b:
            b, fb = c, fc
            side = -1.0
        elif with_a:
            a, fa = c, fc
            side = 1.0
        else:  # fc == 0 (or NaN): stop there
            a, b, fa, fb = c, c, 0.0, 0.0
    return a if abs(fa) <= abs(fb) else b


@kernel
def search_roots(h, o, tip_R, tip_p, T, grid, out):  # long: the grid's brackets, then edges'
    """The roots q6 of the four curves (module doc) into ``out`` (K, 2): q6 and the curve;
    returns how many (at most K). ``grid`` the trial angles, increasing, within one turn."""
    N = grid.shape[0]
    E, RX = np.empty((N, 4)), np.empty((N, 3, 3))
    pair_curves(h, o, tip_R, tip_p, T, grid, E, np.empty((0, 4, 3)), RX)  # no angles
    shared = curve_constants(h, o, tip_R, T)
    work = (np.empty((5, 3)), np.empty((7, 3, 3)))
    count = 0
    for i in range(N):  # sign changes between neighbouring samples (NaN compares False)
        j = (i + 1) % N
        following = grid[j] if j > 0 else grid[0] + 2.0 * np.pi
        for c in range(4):
            if np.sign(E[i, c]) * np.sign(E[j, c]) <= 0 and count < out.shape[0]:
                out[count, 0] = _refine(h, o, tip_p, T, grid[i], following, E[i, c],
                                        E[j, c], c, shared, work)  # fmt: skip
                out[count, 1] = c
                count += 1
    F = np.empty(EDGE_SAMPLES)
    P = np.empty(EDGE_SAMPLES)
    for i in range(N):  # a curve's edge between two samples, and the stretch beside it
        j = (i + 1) % N
        following = grid[j] if j > 0 else grid[0] + 2.0 * np.pi
        for c in range(4):
            if np.isnan(E[i, c]) == np.isnan(E[j, c]):
                continue
            if np.isnan(E[i, c]):
                inside, outside = following, grid[i]
            else:
                inside, outside = grid[i], following
            sample = inside
            for _ in range(EDGE_BISECTIONS):
                mid = 0.5 * (inside + outside)
                if np.isnan(_e(h, o, tip_p, T, mid, c, shared, work)):
                    outside = mid
                else:
                    inside = mid
            for k in range(EDGE_SAMPLES):
                step = k / (EDGE_SAMPLES - 1)
                P[k] = inside + (sample - inside) * step * step
                F[k] = _e(h, o, tip_p, T, P[k], c, shared, work)
            for k in range(EDGE_SAMPLES - 1):
                if np.sign(F[k]) * np.sign(F[k + 1]) <= 0 and count < out.shape[0]:
                    out[count, 0] = _refine(h, o, tip_p, T, P[k], P[k + 1], F[k],
                                            F[k + 1], c, shared, work)  # fmt: skip
                    out[count, 1] = c
                    count += 1
    return count


@kernel
def search_rows(h, o, tip_R, tip_p, T, q6s, curves, out):
    """Each root's joint angles into ``out`` (K, 8): q1 .. q5, SP1's flags of q4 and q5,
    and 1.0 where the root is one (its residual within 1e-9; a bracket across a gap is
    not): joints 4 and 5 make ``R_r = (R1 R2 R3)^T R_X`` by SP1 on h5, then on the unit
    h5 x h4 (as :func:`toolkit.ik.analytic.search.meeting_pairs` does)."""
    K = q6s.shape[0]
    E, Q, RX = np.empty((K, 4)), np.zeros((K, 4, 3)), np.empty((K, 3, 3))
    pair_curves(h, o, tip_R, tip_p, T, q6s, E, Q, RX)
    M = np.empty((5, 3, 3))
    R1, R2, R3, R12, Rr = M[0], M[1], M[2], M[3], M[4]
    v, w, x = np.empty(3), np.empty(3), np.empty(3)
    x[0] = h[4, 1] * h[3, 2] - h[4, 2] * h[3, 1]
    x[1] = h[4, 2] * h[3, 0] - h[4, 0] * h[3, 2]
    x[2] = h[4, 0] * h[3, 1] - h[4, 1] * h[3, 0]
    norm = np.sqrt(dot(x, x))
    for i in range(3):
        x[i] /= norm
    for j in range(K):
        c = curves[j]
        e = E[j, c]
        out[j, :] = 0.0
        if not np.isfinite(e) or abs(e) > 1e-9:  # a bracket across a gap, not a root
            continue
        q1, q2, q3 = Q[j, c, 0], Q[j, c, 1], Q[j, c, 2]
        rotation(h[0], q1, R1)
        rotation(h[1], q2, R2)
        rotation(h[2], q3, R3)
        mm(R1, R2, R12)
        mm(R12, R3, R1)
        mtm(R1, RX[j], Rr)
        mv(Rr, h[4], v)
        q4, f4 = sp1(h[4], v, h[3])
        mv(Rr, x, v)
        rotation(h[3], -q4, R2)
        mv(R2, v, w)
        q5, f5 = sp1(x, w, h[4])
        out[j, 0], out[j, 1], out[j, 2], out[j, 3], out[j, 4] = q1, q2, q3, q4, q5
        out[j, 5], out[j, 6], out[j, 7] = f4, f5, 1.0


@kernel
def _elbow_middles(h, o, tip_R, tip_p, T, out):
    """The middle of each stretch of q6 between the elbow's tangents into ``out`` (4,):
    how many (:func:`toolkit.ik.analytic.search._elbow_edges`, the same steps)."""
    shared = curve_constants(h, o, tip_R, T)  # a = o4 - o3, b = o1 - o3 and SP3's scalars
    a, b = shared[1][0], shared[1][1]
    hb, ha, r = shared[2][0], shared[2][1], shared[2][4]
    V, R6, RX = np.empty((5, 3)), np.empty((3, 3)), np.empty((3, 3))
    d2 = np.empty(3)
    for k in range(3):  # ||y||^2 at q6 = 0, pi / 2, pi: y = X(W) - S, left in V[0]
        curve_ratio(h, o, tip_p, T, shared, 0.5 * np.pi * k, V, R6, RX)
        d2[k] = dot(V[0], V[0])
    c0, c1 = 0.5 * (d2[0] + d2[2]), 0.5 * (d2[0] - d2[2])
    c2 = d2[1] - c0
    amp, psi = np.hypot(c1, c2), np.arctan2(c2, c1)
    ends = np.empty(4)
    n = 0
    for sign in (1.0, -1.0):  # ||y||^2 at the elbow's two tangents
        level = dot(a, a) + dot(b, b) - 2 * hb * ha - 2 * sign * r
        if amp > 1e-15 and abs(level - c0) <= amp:
            half = np.arccos((level - c0) / amp)
            ends[n], ends[n + 1] = psi + half, psi - half
            n += 2
    two = 2.0 * np.pi
    ends = np.sort(np.remainder(ends[:n] + np.pi, two) - np.pi)
    for k in range(n):
        nxt = ends[k + 1] if k + 1 < n else ends[0] + two
        out[k] = np.remainder(0.5 * (ends[k] + nxt) + np.pi, two) - np.pi
    return n


@kernel
def meeting_pairs(h, o, tip_R, tip_p, T, near, pref, out, roots, free):
    """The branches of :func:`toolkit.ik.analytic.search.meeting_pairs` (the same grid, roots
    and joints) into ``out`` (16, 6): the roots a branch names are its elbow and shoulder
    (0 or 1: the curve) and its index among its curve's roots; -1 where there are more
    branches than ``out``'s rows or :data:`PER_CURVE` on a curve (the Python form answers)."""
    grid = np.empty(SAMPLES + 4)
    for k in range(SAMPLES):
        grid[k] = -np.pi + k * (2.0 * np.pi / SAMPLES)
    m = _elbow_middles(h, o, tip_R, tip_p, T, grid[SAMPLES:])
    trial = np.unique(grid[: SAMPLES + m])
    found = np.empty((8 * trial.shape[0], 2))
    K = search_roots(h, o, tip_R, tip_p, T, trial, found)
    q6s = found[:K, 0].copy()
    curves = np.empty(K, np.int64)
    for j in range(K):
        curves[j] = int(found[j, 1])
    rows = np.empty((K, 8))
    search_rows(h, o, tip_R, tip_p, T, q6s, curves, rows)
    seen = np.zeros(4, np.int64)
    count = 0
    for j in range(K):
        if rows[j, 7] == 0.0 or not (usable(int(rows[j, 5]), near)
                                     and usable(int(rows[j, 6]), near)):  # fmt: skip
            continue
        c = curves[j]
        if count == out.shape[0] or seen[c] == PER_CURVE:
            return -1
        for i in range(5):
            out[count, i] = rows[j, i]
        out[count, 5] = q6s[j]
        roots[count, 0], roots[count, 1], roots[count, 2] = c // 2, c % 2, seen[c]
        free[count] = 0
        seen[c] += 1
        count += 1
    return count
