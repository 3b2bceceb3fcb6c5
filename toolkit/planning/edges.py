"""Straight joint-space segments checked at configurations at most ``resolution`` apart
(:class:`EdgeChecker`), and a path shortened by straight cuts between its waypoints that
pass the same check (:func:`shortcut`)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

__all__ = ["RAKE", "RESOLUTION", "EdgeChecker", "shortcut"]

RESOLUTION = math.radians(1.0)
"""[rad or m] The largest step of any joint between two checked configurations of an edge."""

RAKE = 8
"""An edge's configurations checked first after its end: every RAKE-th."""

Collides = Callable[[np.ndarray], np.ndarray]
"""(N, n) joint values -> (N,) True where the robot collides."""
Sweep = Callable[[np.ndarray, np.ndarray, float | None], bool]
"""A whole-motion certificate of a straight segment (a, b, deadline) -> free."""


class EdgeChecker:
    """Checks segments a -> b in joint values by ``collides``, counting the configurations
    checked (``checks``); ``a`` is known free (a tree's node), ``b`` and every
    configuration between are checked (:meth:`free`)."""

    def __init__(self, collides: Collides, resolution: float = RESOLUTION) -> None:
        self.collides, self.resolution, self.checks = collides, resolution, 0

    def points(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The configurations of a -> b checked, b last ((k, n), a excluded): every joint
        moves at most ``resolution`` between neighbours."""
        k = max(1, math.ceil(float(np.abs(b - a).max()) / self.resolution))
        t = np.arange(1, k + 1) / k
        P: np.ndarray = a + t[:, None] * (b - a)
        P[-1] = b  # the end itself, not a rounding of it
        return P

    def free(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether every checked configuration of a -> b is free: the end, then a coarse
        rake (every ``RAKE``-th configuration), then the rest, each in one batch (a
        blocked edge most often fails at the first or second)."""
        P = self.points(a, b)
        rake = np.zeros(len(P), dtype=bool)
        rake[RAKE - 1 :: RAKE] = True
        rake[-1] = False
        for part in (P[-1:], P[rake], P[:-1][~rake[:-1]]):
            if len(part):
                self.checks += len(part)
                if bool(np.any(self.collides(part))):
                    return False
        return True


class SweptEdges(EdgeChecker):
    """An :class:`EdgeChecker` whose segments pass only where ``sweep`` (a whole-motion
    certificate, :class:`~toolkit.planning.sweep.ExactSweep`) passes them after the
    configurations checked: the exact search's edges once a path it found was refused."""

    def __init__(
        self, collides: Collides, resolution: float, sweep: Sweep, deadline: float
    ) -> None:
        super().__init__(collides, resolution)
        self.sweep, self.deadline = sweep, deadline

    def free(self, a: np.ndarray, b: np.ndarray) -> bool:
        return super().free(a, b) and self.sweep(a, b, self.deadline)


def shortcut(
    path: np.ndarray, edges: EdgeChecker, rng: np.random.Generator, deadline: float,
    tries: int = 30,
) -> np.ndarray:  # fmt: skip
    """``path`` (K, n) shortened by straight cuts that pass ``edges``: first, from each
    waypoint kept (from the start on), a cut to the farthest waypoint it sees (the farthest
    tried first: a blocked cut mostly fails at its first checks, and each waypoint's
    stretch is checked once where it passes); then cuts between random waypoints two or
    more apart, each pair tried once, at most ``tries`` of them or until ``deadline``."""
    P = list(path)
    i = 0
    while i < len(P) - 2 and time.perf_counter() < deadline:
        for j in range(len(P) - 1, i + 1, -1):
            if edges.free(P[i], P[j]):
                del P[i + 1 : j]
                break
        i += 1
    tried: set[tuple[int, int]] = set()
    for _ in range(tries):
        pairs = [(a, b) for a in range(len(P)) for b in range(a + 2, len(P)) if (a, b) not in tried]
        if not pairs or time.perf_counter() > deadline:
            break
        i, j = pairs[int(rng.integers(len(pairs)))]
        tried.add((i, j))
        if edges.free(P[i], P[j]):
            P = P[: i + 1] + P[j:]
            tried = set()  # the indices name other waypoints now
    return np.array(P)
