"""The certificates' per-pair gaps (numba), on :mod:`toolkit.collision.bound_kernels`'
bounds: :func:`pair_gaps`, the step of the covers' whole-motion certificate
(:func:`toolkit.planning.kernels.edge_swept`), and :func:`pair_bounds`, the cheap bounds the
exact shapes' certificate (:class:`toolkit.planning.sweep.ExactSweep`) reads before coal.
Arguments as :mod:`~toolkit.collision.bound_kernels`' (``packed``: the checker's bounds,
``W``, ``P``: its frame and placed-box buffers)."""

from __future__ import annotations

import numpy as np

from ..kinematics import inline_kernel, kernel
from .bound_kernels import MARGIN, axis_gap, cover_gap, covers_gap, gap2, placed
from .convex_kernels import both_sets, convex_gaps

__all__ = ["exact_gaps", "pair_bounds", "pair_gaps"]


@kernel
def pair_gaps(q, packed, W, P, until, rate, t, span, closest):
    """The stretch [in units of the edge] from ``t`` that every checked pair is certainly
    apart over, at configuration q at ``t`` of a straight edge, asked to reach ``span``. A
    pair's distance changes by at most ``rate[k]`` [m] per unit (0: it cannot), so a gap
    g [m] at t keeps it apart until t + g / rate (a hair, 1e-9 of it, short): that is
    ``until[k]`` (per pair; set it below ``t`` before an edge's first call). A pair whose
    ``until`` already reaches t + ``span`` is not measured again; each other one gets a
    lower bound of its shapes' distance from the cheapest of their bounds (the spheres
    about both boxes, the sphere about either box against the other box, the boxes'
    separating axes, the covers) until one proves the need max(``closest``, rate *
    ``span``), and its ``until`` anew. Returns the least ``until`` - t; -1 as soon as no
    bound proves a pair more than :data:`MARGIN` apart, or a pair that moves (``rate`` >
    0, where ``span`` > 0) has a gap under ``closest``; inf where no pair moves. One loop
    over the pairs: the certificate's step (:func:`toolkit.planning.kernels.edge_swept`).
    A pair that does not move keeps its distance along the edge: once apart, it stays.
    Other arguments as :func:`certainly_free`'s."""
    ints, flts, row, box, radius, first, second, cstart, csphere, hold = packed
    placed(q, ints, flts, row, box, W, P)
    covers = (cstart, csphere, hold)
    ahead = np.inf
    for k in range(first.shape[0]):
        if until[k] >= t + span:  # an earlier gap carries it past the stretch asked
            ahead = min(ahead, until[k] - t)
            continue
        a, b, r = first[k], second[k], rate[k]
        need = max(closest, r * span) * (1.0 + 1e-9)
        gap, proved = _pair_gap(W, row, P, box, radius, covers, a, b, need)
        if not proved and (gap <= MARGIN or (r > 0.0 and span > 0.0 and gap < closest)):
            return -1.0
        until[k] = t + (1.0 - 1e-9) * gap / r if r > 0.0 else np.inf
        ahead = min(ahead, until[k] - t)
    return ahead


@inline_kernel
def _pair_gap(W, row, P, box, radius, covers, a, b, need):
    """(a lower bound [m] of the distance between shapes a and b, from the cheapest of their
    bounds until one proves ``need``: the spheres about both boxes, the sphere about either
    box against the other box, the boxes' separating axes, the covers; whether the first
    proved it, its gap then the spheres' own, at least the need and 2 :data:`MARGIN`) on
    placed boxes P."""
    d2 = (P[a, 0] - P[b, 0]) ** 2 + (P[a, 1] - P[b, 1]) ** 2 + (P[a, 2] - P[b, 2]) ** 2
    asked = max(need, 2.0 * MARGIN)
    reach = asked + radius[a, 0] + radius[b, 0]
    if d2 >= reach * reach:
        return max(asked, np.sqrt(d2) - radius[a, 0] - radius[b, 0]), True
    gap = np.sqrt(gap2(P, box, b, P[a, 0], P[a, 1], P[a, 2])) - radius[a, 0]
    if gap < need:
        gap = max(gap, np.sqrt(gap2(P, box, a, P[b, 0], P[b, 1], P[b, 2])) - radius[b, 0])
    if gap < need:
        gap = max(gap, axis_gap(P, box, a, b, need))
    if gap < need:
        gap = max(
            gap,
            cover_gap(W, row, P, box, covers, a, b, -np.inf),
            cover_gap(W, row, P, box, covers, b, a, -np.inf),
        )
    if gap < need:
        gap = max(gap, covers_gap(W, row, covers, a, b, -np.inf))
    return gap, False


@kernel
def pair_bounds(q, packed, W, P, gaps, need):
    """Into ``gaps`` (pairs,): per checked pair at configuration q a lower bound [m] of the
    distance between its two shapes, from the cheapest of their bounds until one proves
    ``need[k]`` (:func:`_pair_gap`; it may be negative: no bound proves them apart). The
    exact shapes' certificate (:class:`toolkit.planning.sweep.ExactSweep`) asks coal only
    about the pairs whose bound falls short. Other arguments as :func:`pair_gaps`'."""
    ints, flts, row, box, radius, first, second, cstart, csphere, hold = packed
    placed(q, ints, flts, row, box, W, P)
    covers = (cstart, csphere, hold)
    for k in range(first.shape[0]):
        gaps[k] = _pair_gap(W, row, P, box, radius, covers, first[k], second[k], need[k])[0]


@kernel
def exact_gaps(q, packed, W, P, convex, rate, span, closest, gaps, dirs, last, fit, ask):
    """The compiled part of a step of the exact shapes' certificate
    (:class:`toolkit.planning.sweep.ExactSweep`) at configuration q: per checked pair its
    need [m] (``rate[k]`` times ``span``, plus ``closest``) and into ``gaps`` a lower bound
    of its distance, from the cheap bounds (:func:`pair_bounds`), then where those fall
    short and both shapes are convex sets, from the sets
    (:func:`~toolkit.collision.convex_kernels.convex_gaps`). Into ``ask``: the pairs coal
    must answer, those still short of their need, except the convex sets' pairs whose
    bound keeps ``fit`` of their last distance from coal (``last``); returns how many.
    ``convex``: :class:`~toolkit.collision.convex.ConvexSets`; ``dirs``: its directions."""
    row, first, second = packed[2], packed[5], packed[6]
    need = np.empty(first.shape[0])
    for k in range(first.shape[0]):
        need[k] = (rate[k] * span if rate[k] > 0.0 else 0.0) + closest
    pair_bounds(q, packed, W, P, gaps, need)
    n = 0
    for k in range(first.shape[0]):
        if gaps[k] < need[k]:
            ask[n] = k
            n += 1
    if n == 0:
        return 0
    convex_gaps(W, row, P, convex, first, second, ask[:n], need, gaps, dirs)
    m = 0
    for i in range(n):
        k = ask[i]
        if gaps[k] >= need[k] or (both_sets(convex[0], first[k], second[k])
                                  and gaps[k] >= fit * last[k]):  # fmt: skip
            continue
        ask[m] = k
        m += 1
    return m
