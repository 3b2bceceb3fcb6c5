"""The planner's tunables, in one record (:class:`PlannerSettings`).

``Robot.plan(..., settings=PlannerSettings(...))`` and :func:`toolkit.planning.plan_values`
take one; the defaults are what every figure in docs/benchmarks.md was measured with. None
of them bears on soundness: a returned path is certified over its whole motion whatever
they are (docs/planning.md); they trade time between the searches.

Not here, because they are compiled into the search's kernels (a change is a new
installation's compile, not a call's argument): the nearest-node block
(:data:`toolkit.planning.kernels.BLOCK`), a shortcut's least worthwhile gain
(:data:`~toolkit.planning.kernels.WORTH`), the covers' tolerances
(:data:`~toolkit.planning.kernels.CLOSEST`, :data:`~toolkit.planning.kernels.GROWTH`) and
the order an edge's configurations are checked in (:data:`toolkit.planning.edges.RAKE`);
nor the exact certificate's margins (:mod:`toolkit.planning.sweep`), which are soundness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from numbers import Integral, Real

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["PlannerSettings"]


@dataclass(frozen=True)
class PlannerSettings:
    """The planner's tunables (module doc); every field checked when made."""

    max_edge: float = 0.5
    """[rad] The longest edge a tree grows by (in the Euclidean norm of the joint values)."""
    covers_coarser: float = 2.0
    """Where the path the search on the covers finds will be certified over its whole
    motion (the start and every goal pass the covers, and their bounds certify motions),
    that search checks its edges at configurations this many times ``resolution`` apart:
    the certification is the final check (a path it refuses is searched again with every
    edge certified, and a path not certified is checked on the exact shapes at
    ``resolution``, or else planned again on them). A path with an escape's segment
    (:func:`~toolkit.planning.certain.escape`, checked on the exact shapes at
    ``resolution`` when it was found) is searched at ``resolution``."""
    search_share: float = 0.8
    """The share of a plan's time limit the searches may take; the rest is kept for the
    last path's shortcuts and its certificate (a plan returns within its time limit)."""
    certain_share: float = 0.5
    """The share of a plan's time limit the compiled search on certainly-free
    configurations may take before the search on the exact checker takes over."""
    chunk: int = 256
    """Rounds of the compiled search between two looks at the clock."""
    restart_nodes: int = 8192
    """The trees' nodes after which the compiled search starts again from the start and
    the goals alone, the random stream going on (the same seed gives the same plan), each
    time with twice the budget: the time RRT-Connect takes through a narrow passage is
    heavy-tailed (one MBM problem under a table took 0.05 to 4.2 s over eight seeds, its
    trees up to 58,000 nodes, before the trees were balanced and given dynamic domains),
    and restarts cut the tail."""
    stalled: int = 4096
    """Calls of the compiled search in a row (``chunk`` rounds each: about a million
    rounds, ~0.1 s here) that grow no node, after which it gives up: an end escaped into a
    pocket of the covers' free space (an MBM bookshelf problem: 3 nodes in 5 s before this
    bound, 0.46 s in all with it, the search on the exact shapes leaving the pocket).
    Others stall for up to ~40 ms and then grow out (a quarter of this gave one of them up:
    2.7 s on the exact shapes)."""
    capacity: int = 1024
    """Nodes each compiled tree has room for at first (twice as many each time one fills)."""
    corners: int = 1
    """How many times the corners of a certified path are cut
    (:meth:`~toolkit.planning.certain.CertainTest.cut_corners`)."""
    tries: int = 30
    """Random cuts the compiled shortcut tries after dropping waypoints."""
    reseeds: int = 2
    """Where the pairs the compiled search leaves out (:attr:`~toolkit.planning.certain.
    CertainTest.deferred`) refuse segments of its path, the search is run again this many
    times, with the seeds after the plan's, each path certified the same way, before the
    stretches refused are searched again on the exact checker: a search on the covers
    takes milliseconds, the exact one between two configurations a few hundred (MBM's UR5,
    6 of 41 plans, its forearm against its wrist)."""
    escapes: tuple[float, ...] = (0.02, 0.05, 0.1, 0.2, 0.4, 0.8)
    """[rad] The lengths (Euclidean, in joint values) of the straight edges tried from an
    end the covers do not pass, shortest first, in rounds of ``directions``; () tries none."""
    directions: tuple[int, ...] = (16, 64, 256)
    """The random directions tried at each of ``escapes``, a round per item: a round tries
    every length before the next, wider round. On the MotionBenchMaker Panda problems
    (2,100 plans) the rounds after the first left 6 plans to the exact search where one
    round of 16 (and lengths to 0.4 rad) left 51, at the same medians (ad hoc)."""
    escape_edges: int = 64
    """Straight edges the exact checker is asked about in one escape at most: a bound on
    the time an end no escape leaves costs (the most MBM's problems asked was 51, 33 ms)."""
    escaped_goals: int = 8
    """Goals the covers do not pass that an escape is tried for (the first ones)."""
    domain: tuple[float, float, float] = (0.75, 0.19, 1e-4)
    """The dynamic domain of the compiled RRT-Connect (:func:`~toolkit.planning.kernels.grow`)
    and the exact one (:mod:`~toolkit.planning.trees`): (the radius a node's domain takes
    after its first blocked extension, the least radius, both as shares of the sampling
    box's spread (:meth:`radii`); the factor by which a blocked extension shrinks the radius
    and a free one grows it). Samples that only a blocked node is nearest to, far from it,
    are not tried. On the Panda's box (spread 5.3 rad) these are the 4.0 and 1.0 rad of
    VAMP's RRT-Connect (its ``RRTCSettings``). With balanced trees, one MBM problem under a
    table went from 11,000-158,000 nodes over eight seeds to 17-88 (ad hoc); the domain
    alone cut its checks a further 5-25x. Radii fixed in radians starve a larger space:
    on MBM's Baxter (14 joints, spread 7.2 rad) a goal in a shelf took 0.5 % of the samples
    within 4 rad and its tree stopped growing; as shares, the plan that failed in 10 s
    took 0.9 s (ad hoc, six seeds: all found by the covers' search)."""

    def radii(self, bounds: tuple[np.ndarray, np.ndarray]) -> tuple[float, float, float]:
        """:attr:`domain` in radians for the sampling box ``bounds`` (lower, upper): its
        radii times the box's spread, the root mean square distance between two uniform
        samples in it (sqrt(sum of its sides squared / 6))."""
        spread = math.sqrt(float(np.sum(np.square(bounds[1] - bounds[0]))) / 6.0)
        return self.domain[0] * spread, self.domain[1] * spread, self.domain[2]

    @classmethod
    def of(cls, settings: object) -> PlannerSettings:
        """``settings`` itself, the defaults for None; anything else refused."""
        if settings is None:
            return cls()
        if not isinstance(settings, PlannerSettings):
            raise InvalidParameterError(
                f"settings must be a PlannerSettings or None, got {settings!r:.80}"
            )
        return settings

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not _fits(f.name, value):
                raise InvalidParameterError(
                    f"PlannerSettings.{f.name} must be {_WHAT[f.name]}, got {value!r:.80}"
                )
            # as plain Python numbers: the kernels compile once for them, not per type given
            plain = int if f.name in _COUNTS or f.name == "directions" else float
            kept = tuple(map(plain, value)) if isinstance(value, tuple) else plain(value)
            object.__setattr__(self, f.name, kept)
        if self.domain[1] > self.domain[0] or self.domain[2] >= 1:
            raise InvalidParameterError(f"PlannerSettings.domain must be {_WHAT['domain']}")


def _number(v: object, whole: bool, least: float) -> bool:
    """Whether ``v`` is a finite number (a whole one where ``whole``) >= ``least`` (> 0
    where ``least`` is 0.0 and not whole)."""
    if isinstance(v, bool | np.bool_) or not isinstance(v, Integral if whole else Real):
        return False
    x = float(v)  # a Real
    return math.isfinite(x) and (x >= least if whole else x > least)


def _fits(name: str, value: object) -> bool:
    """Whether field ``name`` may hold ``value`` (:data:`_WHAT`)."""
    if name in _COUNTS:
        return _number(value, True, 0 if name in ("corners", "tries", "reseeds") else 1)
    if name in ("escapes", "directions", "domain"):
        if not isinstance(value, tuple):
            return False
        whole = name == "directions"
        if not all(_number(v, whole, 1 if whole else 0.0) for v in value):
            return False
        if name == "escapes":
            return list(value) == sorted(value)
        return len(value) == 3 if name == "domain" else len(value) > 0
    if not _number(value, False, 0.0):
        return False
    return name not in ("search_share", "certain_share") or float(value) <= 1  # type: ignore[arg-type]


_COUNTS = ("chunk", "restart_nodes", "stalled", "capacity", "corners", "tries",
           "reseeds", "escape_edges", "escaped_goals")  # fmt: skip
_WHAT = {
    **dict.fromkeys(_COUNTS, "a whole number >= 1"),
    "corners": "a whole number >= 0",
    "tries": "a whole number >= 0",
    "reseeds": "a whole number >= 0",
    "max_edge": "a finite length > 0 [rad]",
    "covers_coarser": "a finite factor > 0",
    "search_share": "a share in (0, 1]",
    "certain_share": "a share in (0, 1]",
    "escapes": "lengths > 0 [rad], shortest first",
    "directions": "whole numbers >= 1, one round at least",
    "domain": "(radius >= least radius > 0, both shares of the box's spread, a factor in (0, 1))",
}
