"""Whole motions certified on the exact shapes (:class:`ExactSweep`): conservative
advancement on coal's distances.

A straight segment a -> b in joint values is free over its whole motion when, at the
configurations checked, every checked pair's distance (coal's, on the exact shapes) exceeds
what the pair can close before the next one: a point turned by dq about an axis moves by at
most |dq| times its distance from the axis, so a pair's distance changes by at most its
``rate`` (the joints that move one shape and not the other, each joint's step times how
far the shape's points can lie from its axis: :func:`toolkit.planning.geometry.reach`) per unit
of the segment. The segment is walked from both ends towards the middle (a grasp a hair
from its object ends a segment: from that end the steps grow as the gap does), and is
refused where a pair that moves comes within :data:`CLOSEST` (a micron), or after
:data:`MOST` configurations.

This is the final check of every segment that the covers' certificate
(:func:`toolkit.planning.kernels.edge_swept`) did not pass: the escapes' short segments and
every path found on the exact checker. It asks only coal and the reach bounds, never the
covers or the configurations sampled by the search."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..collision import convex as sets
from ..collision import convex_kernels, gap_kernels, parts
from ..common import PerThread
from ..errors import InvalidParameterError
from . import kernels
from .certain import READY, CertainTest, kind_of
from .kernels import GROWTH

__all__ = ["CLOSEST", "MOST", "SLACK", "SLACK_SHARE", "ExactSweep"]

CLOSEST = 1e-6
"""[m] The least distance a moving pair may keep along a certified segment."""
SLACK = 2e-6
"""[m] Taken off each of coal's distances before it is used, with :data:`SLACK_SHARE` of
the distance: room for its error. GJK, on convex shapes, answers within its tolerance
(coal's default 1e-6), which is relative to the distance (``gjk_convergence_criterion_type``
Relative): a cylinder against a box read 13.43633 mm or 13.43589 mm by which of the two
coal was handed first (``tests/collision/test_parts.py``), 0.44 um apart, more than the
0.1 um taken off before; two boxes 1.34 m apart read 2.2 um apart by two calls."""
SLACK_SHARE = 2e-6
"""The share of each of coal's distances taken off it beside :data:`SLACK` (twice GJK's
relative tolerance; axis-aligned boxes up to 4 m apart overestimated by at most 6.7e-7 of
their distance against their exact distance, 20,000 pairs, ad hoc)."""
MOST = 20_000
"""Configurations one segment's certificate may check before it refuses the segment."""


class ExactSweep:
    """The whole-motion certificate of straight segments on a checker's exact shapes.

    ``test``: the checker's :class:`~toolkit.planning.certain.CertainTest` with a finite
    ``reach`` (each shape's reach from each joint's axis); ``to_q``: joint values (nv,) ->
    the model's q; ``pairs``: the checker's pairs certified (indices; default every one);
    ``convex``: the robot's shapes as convex sets (:func:`~toolkit.collision.convex.
    convex_sets`; None: made here). Calling it on (a, b) answers whether the whole motion
    is free; :attr:`checks` counts the configurations it checked, :attr:`asked` the pairs
    asked of coal (the cheap bounds of :func:`toolkit.collision.gap_kernels.pair_bounds`
    and the convex sets' of :func:`toolkit.collision.convex_kernels.convex_gaps` carry the
    others)."""

    def __init__(
        self, checker: Any, test: CertainTest, to_q: Callable[[np.ndarray], np.ndarray],
        pairs: np.ndarray | None = None, convex: sets.ConvexSets | None = None,
    ) -> None:  # fmt: skip
        if not test.sweeps or getattr(checker, "bounds", None) is None:
            raise InvalidParameterError(
                "a whole-motion certificate needs the checker's bounds and a finite reach "
                "(a CertainTest that sweeps)"
            )
        self.parts = checker.parts  # coal's distances, part by part
        packed = checker.bounds.packed()  # every checked pair, in the checker's order
        self.index = np.arange(len(packed.first)) if pairs is None else np.asarray(pairs, np.int64)
        packed = packed.with_pairs(packed.first[self.index], packed.second[self.index])
        reach, moves = test.reach, test.moves
        assert reach is not None and moves is not None  # test.sweeps
        self.packed, self.reach, self.moves = packed, reach, moves
        self.first, self.second = packed.first, packed.second
        self.to_q = to_q
        if convex is None:
            convex = sets.convex_sets(checker.parts.shapes, checker.robot_count)
        self.convex = convex
        shapes, pairs_count = len(self.packed.row), len(self.first)
        self._work = PerThread(lambda: (
            np.empty((self.packed.ints.shape[0] + 1, 15)), np.full((shapes, 12), np.nan),
            np.zeros((pairs_count, 1 + convex_kernels.PIECES**2, 3)),
            np.zeros(pairs_count, np.int64)))  # fmt: skip
        self._exact = np.full(pairs_count, np.inf)  # per pair its last distance from coal
        self.checks = self.asked = 0
        self._ready()
        self.checks = self.asked = 0

    def _ready(self) -> None:
        """Its kernels compiled (on a first use after an installation) when it is made,
        before a plan's time budget is read; once per process and kind of arrays."""
        kind = kind_of((self.packed, self.convex, self.reach, self.moves))
        if kind in READY:
            return
        zeros = np.zeros(self.reach.shape[1])
        rate = self.rates(zeros, zeros)
        self.gaps(self.to_q(zeros), rate, 0.0)
        kernels.step_ahead(np.zeros(len(rate)), rate, CLOSEST)
        READY.add(kind)

    def rates(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Per checked pair, the most its distance can change per unit of a -> b [m]."""
        rate = np.empty(len(self.first))
        kernels.pair_rates(np.ascontiguousarray(a, dtype=float),
                           np.ascontiguousarray(b, dtype=float), self.first, self.second,
                           self.reach, self.moves, rate)  # fmt: skip
        return rate

    def gaps(self, q: np.ndarray, rate: np.ndarray, span: float) -> np.ndarray:
        """Per checked pair a lower bound [m] of its distance at q, asked to reach the
        pair's need (``rate`` times ``span``, plus :data:`CLOSEST`): the cheap bounds; else,
        where both shapes are convex sets, the compiled bound of their hulls, then of their
        pieces, taken where it reaches the need or :data:`~toolkit.collision.parts.HULL_FIT`
        of the pair's last distance from coal (:func:`~toolkit.collision.gap_kernels.
        exact_gaps`), else coal's distance; for the other pairs,
        :meth:`~toolkit.collision.parts.Parts.lower_bounds` (the hulls, the pieces, the
        meshes). Coal's answers less :data:`SLACK` and :data:`SLACK_SHARE` of them."""
        W, P, dirs, ask = self._work.get()
        gaps = np.empty(len(rate))
        n = gap_kernels.exact_gaps(q, self.packed, W, P, self.convex, rate, span, CLOSEST,
                                   gaps, dirs, self._exact, parts.HULL_FIT, ask)  # fmt: skip
        self.checks += 1
        if not n:
            return gaps
        short = ask[:n].copy()
        need = np.where(rate[short] > 0.0, rate[short] * span, 0.0) + CLOSEST
        convex = sets.has_set(self.convex, self.first[short]) & sets.has_set(
            self.convex, self.second[short]
        )
        if convex.any():  # coal's distance of the shapes themselves
            exact = short[convex]
            found = self.parts.distances(q, self.index[exact])
            self._exact[exact] = found
            gaps[exact] = np.maximum(gaps[exact], found - SLACK - SLACK_SHARE * np.abs(found))
        if not convex.all():  # the meshes' hulls where they carry what is needed, else coal's
            rest = short[~convex]
            exact = self.parts.lower_bounds(q, self.index[rest], need[~convex] + SLACK)
            gaps[rest] = np.maximum(gaps[rest], exact - SLACK - SLACK_SHARE * np.abs(exact))
        self.asked += n
        return gaps

    def _ahead(self, t: float, a: np.ndarray, b: np.ndarray, rate: np.ndarray,
               aim: float) -> float:  # fmt: skip
        """The stretch of the segment the gaps at ``t`` carry (-1: a pair is too close),
        the bounds asked to carry ``aim``."""
        gaps = self.gaps(self.to_q(a + t * (b - a)), rate, aim)
        return float(kernels.step_ahead(gaps, rate, CLOSEST))

    def __call__(self, a: np.ndarray, b: np.ndarray, deadline: float | None = None) -> bool:
        """Whether the whole straight motion a -> b (joint values) is free."""
        rate = self.rates(a, b)
        lo, hi = 0.0, 1.0  # [0, lo] and [hi, 1] certified so far
        aim_lo = aim_hi = 0.125
        for _ in range(MOST // 2):
            ahead = self._ahead(lo, a, b, rate, min(hi - lo, aim_lo))
            if ahead < 0.0:
                return False
            lo, aim_lo = lo + ahead, GROWTH * ahead
            if lo >= hi:
                return True
            back = self._ahead(hi, a, b, rate, min(hi - lo, aim_hi))
            if back < 0.0:
                return False
            hi, aim_hi = hi - back, GROWTH * back
            if hi <= lo:
                return True
            if deadline is not None and time.perf_counter() > deadline:
                return False
        return False
