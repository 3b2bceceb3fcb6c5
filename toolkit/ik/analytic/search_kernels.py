"""The root search of :mod:`toolkit.ik.analytic.search` compiled (numba): every sign change
of the four curves' residual e(q6) over the grid and beside each curve's edges, refined to
round-off, in one call per target (the same brackets, in the same order, by the same
steps as the search's description; the tests compare the two)."""

from __future__ import annotations

import numpy as np

from ...kinematics import inline_kernel, kernel
from .family_kernels import pair_curves

__all__ = ["search_roots"]

BISECTIONS, SECANTS, EDGE_BISECTIONS, EDGE_SAMPLES = 12, 10, 30, 24


@inline_kernel
def _e(h, o, tip_R, tip_p, T, q6, curve, buf):
    """The residual of ``curve`` at one q6 (NaN where the curve does not exist)."""
    q, E, Q, RX = buf
    q[0] = q6
    pair_curves(h, o, tip_R, tip_p, T, q, E, Q, RX)
    return E[0, curve]


@inline_kernel
def _same(x, y):
    """np.sign(x) == np.sign(y), NaN never equal."""
    return np.sign(x) == np.sign(y)


@inline_kernel
def _refine(h, o, tip_R, tip_p, T, a, b, fa, fb, curve, buf):
    """The root in [a, b] (e changes sign across it): halvings, then regula falsi with the
    Illinois rule (the end kept twice in a row has its value halved)."""
    for _ in range(BISECTIONS):
        c = 0.5 * (a + b)
        fc = _e(h, o, tip_R, tip_p, T, c, curve, buf)
        if np.sign(fc) * np.sign(fa) <= 0:  # the root in [a, c]
            b, fb = c, fc
        else:
            a, fa = c, fc
    side = 0.0
    for _ in range(SECANTS):
        c = (fa * b - fb * a) / (fa - fb) if fa != fb else a
        fc = _e(h, o, tip_R, tip_p, T, c, curve, buf)
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
    E, Q, RX = np.empty((N, 4)), np.zeros((N, 4, 3)), np.empty((N, 3, 3))
    pair_curves(h, o, tip_R, tip_p, T, grid, E, Q, RX)
    buf = (np.empty(1), np.empty((1, 4)), np.zeros((1, 4, 3)), np.empty((1, 3, 3)))
    count = 0
    for i in range(N):  # sign changes between neighbouring samples (NaN compares False)
        j = (i + 1) % N
        following = grid[j] if j > 0 else grid[0] + 2.0 * np.pi
        for c in range(4):
            if np.sign(E[i, c]) * np.sign(E[j, c]) <= 0 and count < out.shape[0]:
                out[count, 0] = _refine(h, o, tip_R, tip_p, T, grid[i], following, E[i, c],
                                        E[j, c], c, buf)  # fmt: skip
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
                if np.isnan(_e(h, o, tip_R, tip_p, T, mid, c, buf)):
                    outside = mid
                else:
                    inside = mid
            for k in range(EDGE_SAMPLES):
                step = k / (EDGE_SAMPLES - 1)
                P[k] = inside + (sample - inside) * step * step
                F[k] = _e(h, o, tip_R, tip_p, T, P[k], c, buf)
            for k in range(EDGE_SAMPLES - 1):
                if np.sign(F[k]) * np.sign(F[k + 1]) <= 0 and count < out.shape[0]:
                    out[count, 0] = _refine(h, o, tip_R, tip_p, T, P[k], P[k + 1], F[k],
                                            F[k + 1], c, buf)  # fmt: skip
                    out[count, 1] = c
                    count += 1
    return count
