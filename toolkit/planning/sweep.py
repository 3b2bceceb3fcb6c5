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

from ..collision import gap_kernels
from ..common import PerThread
from ..errors import InvalidParameterError
from . import kernels
from .certain import CertainTest
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
    the model's q; ``pairs``: the checker's pairs certified (indices; default every one).
    Calling it on (a, b) answers whether the whole motion is free; :attr:`checks` counts
    the configurations it checked, :attr:`asked` the pairs asked of coal (the cheap bounds
    of :func:`toolkit.collision.gap_kernels.pair_bounds` carry the others)."""

    def __init__(
        self, checker: Any, test: CertainTest, to_q: Callable[[np.ndarray], np.ndarray],
        pairs: np.ndarray | None = None,
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
        self.packed, self.reach, self.moves = packed, test.reach, test.moves
        self.first, self.second = packed.first, packed.second
        self.to_q = to_q
        shapes = len(self.packed.row)
        self._work = PerThread(lambda: (np.empty((self.packed.ints.shape[0] + 1, 15)),
                                        np.full((shapes, 12), np.nan)))  # fmt: skip
        self.checks = 0
        self.asked = 0

    def rates(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Per checked pair, the most its distance can change per unit of a -> b [m]."""
        rate = np.empty(len(self.first))
        kernels.pair_rates(np.ascontiguousarray(a, dtype=float),
                           np.ascontiguousarray(b, dtype=float), self.first, self.second,
                           self.reach, self.moves, rate)  # fmt: skip
        return rate

    def gaps(self, q: np.ndarray, need: np.ndarray) -> np.ndarray:
        """Per checked pair a lower bound [m] of its distance at q: the cheap bounds where
        they reach ``need``, else the distance of its meshes' convex hulls or of their
        convex pieces where that does, else coal's distance
        (:meth:`~toolkit.collision.parts.Parts.lower_bounds`; less :data:`SLACK` and
        :data:`SLACK_SHARE` of it)."""
        W, P = self._work.get()
        gaps = np.empty(len(need))
        gap_kernels.pair_bounds(q, self.packed, W, P, gaps, need)
        short = np.flatnonzero(gaps < need)
        self.checks += 1
        if short.size:  # the meshes' hulls where they carry what is needed, else coal's
            exact = self.parts.lower_bounds(q, self.index[short], need[short] + SLACK)
            gaps[short] = np.maximum(gaps[short], exact - SLACK - SLACK_SHARE * np.abs(exact))
            self.asked += int(short.size)
        return gaps

    def _ahead(self, t: float, a: np.ndarray, b: np.ndarray, rate: np.ndarray,
               aim: float) -> float:  # fmt: skip
        """The stretch of the segment the gaps at ``t`` carry (-1: a pair is too close),
        the bounds asked to carry ``aim``."""
        moving = rate > 0.0
        d = self.gaps(self.to_q(a + t * (b - a)), np.where(moving, rate * aim, 0.0) + CLOSEST)
        if np.any(d <= np.where(moving, CLOSEST, 0.0)):
            return -1.0
        if not moving.any():
            return np.inf
        return float(np.min(d[moving] / rate[moving])) * (1.0 - 1e-9)

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
