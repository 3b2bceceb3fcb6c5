"""The search's root finding written with numpy, as it was before it was compiled: the
oracle :func:`toolkit.ik.analytic.search.roots` is compared with (the same brackets, in
the same order, refined by the same steps)."""

from __future__ import annotations

import numpy as np

from toolkit.ik.analytic.search import (
    BISECTIONS,
    EDGE_BISECTIONS,
    EDGE_SAMPLES,
    SECANTS,
    _curves,
)
from toolkit.ik.analytic.structure import Chain


def _edges(
    chain: Chain, o: np.ndarray, T: np.ndarray, grid: tuple[np.ndarray, np.ndarray],
    E: np.ndarray, nxt: np.ndarray,
) -> tuple[np.ndarray, ...]:  # fmt: skip
    """Brackets (a, b, e(a), e(b), curve) between a curve's edge (where it begins or ends
    between two samples: a tangent of SP3 or SP2) and the sample beside it, where e changes
    sign: the edge is found by EDGE_BISECTIONS halvings of the step, and the stretch from it
    to the sample is sub-sampled at EDGE_SAMPLES points."""
    i, curve = np.nonzero(np.isnan(E) != np.isnan(nxt))
    rows = np.arange(len(i))
    here, then = grid[0][i], grid[1][i]
    inside = np.where(np.isnan(E[i, curve]), then, here)
    outside = np.where(np.isnan(E[i, curve]), here, then)
    f_in = np.where(np.isnan(E[i, curve]), nxt[i, curve], E[i, curve])
    sample = inside.copy()
    for _ in range(EDGE_BISECTIONS):
        mid = 0.5 * (inside + outside)
        f_mid = _curves(chain, o, T, mid)[0][rows, curve]
        live = ~np.isnan(f_mid)
        inside, f_in = np.where(live, mid, inside), np.where(live, f_mid, f_in)
        outside = np.where(live, outside, mid)
    # near an edge e goes as the square root of the distance to it: sub-samples at squares
    # of even steps, where e is close to linear, find roots that cluster there
    steps = np.linspace(0.0, 1.0, EDGE_SAMPLES) ** 2
    P = inside[:, None] + (sample - inside)[:, None] * steps[None]
    F = _curves(chain, o, T, P.ravel())[0].reshape(len(i), EDGE_SAMPLES, 4)
    F = F[rows, :, curve]
    m, k = np.nonzero(np.sign(F[:, :-1]) * np.sign(F[:, 1:]) <= 0)
    return (P[m, k], P[m, k + 1], F[m, k], F[m, k + 1], curve[m])


def _refine(
    chain: Chain, o: np.ndarray, T: np.ndarray, a: np.ndarray, b: np.ndarray,
    fa: np.ndarray, fb: np.ndarray, curve: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The root in each bracket [a, b] of its curve (e changes sign across it), all at once:
    BISECTIONS halvings, then regula falsi with the Illinois rule (the end kept twice in a
    row has its value halved), superlinear to round-off."""
    rows = np.arange(len(a))
    for _ in range(BISECTIONS):
        c = 0.5 * (a + b)
        fc = _curves(chain, o, T, c)[0][rows, curve]
        left = np.sign(fc) * np.sign(fa) <= 0  # the root in [a, c]
        b, fb = np.where(left, c, b), np.where(left, fc, fb)
        a, fa = np.where(left, a, c), np.where(left, fa, fc)
    side = np.zeros(len(a))
    for _ in range(SECANTS):
        c = np.where(fa != fb, (fa * b - fb * a) / np.where(fa != fb, fa - fb, 1.0), a)
        fc = _curves(chain, o, T, c)[0][rows, curve]
        with_b = np.sign(fc) == np.sign(fb)
        with_a = ~with_b & (np.sign(fc) == np.sign(fa))
        fa = np.where(with_b & (side == -1), 0.5 * fa, fa)
        fb = np.where(with_a & (side == 1), 0.5 * fb, fb)
        b, fb = np.where(with_b, c, b), np.where(with_b, fc, fb)
        a, fa = np.where(with_a, c, a), np.where(with_a, fc, fa)
        side = np.where(with_b, -1.0, np.where(with_a, 1.0, side))
        hit = ~(with_a | with_b)  # fc == 0 (or NaN): stop there
        a, b = np.where(hit, c, a), np.where(hit, c, b)
        fa, fb = np.where(hit, 0.0, fa), np.where(hit, 0.0, fb)
    return np.where(np.abs(fa) <= np.abs(fb), a, b)


def roots(chain: Chain, o: np.ndarray, T: np.ndarray, grid: np.ndarray):
    """(q6, curve) of every root: the grid's sign changes, then the edges' brackets."""
    following = np.append(grid[1:], grid[0] + 2 * np.pi)
    E, _, _ = _curves(chain, o, T, grid)
    nxt = np.roll(E, -1, axis=0)
    lo_i, curve = np.nonzero(np.sign(E) * np.sign(nxt) <= 0)  # NaN compares False
    a, b, fa, fb = grid[lo_i], following[lo_i], E[lo_i, curve], nxt[lo_i, curve]
    edges = _edges(chain, o, T, (grid, following), E, nxt)
    a, b, fa, fb, curve = (np.concatenate(pair) for pair in zip((a, b, fa, fb, curve), edges,
                                                                strict=True))  # fmt: skip
    if not len(a):
        return np.zeros(0), np.zeros(0, np.int64)
    return _refine(chain, o, T, a, b, fa, fb, curve), curve
