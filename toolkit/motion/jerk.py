"""Jerk-limited motion through waypoints, at rest at each: every segment by Ruckig (Berscheid
and Kroeger, RSS 2021; the ``ruckig`` package, the ``motion`` extra), time-synchronised
over the joints, returned exactly as cubic pieces (Ruckig's profiles are piecewise
constant in jerk)."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidParameterError
from .profiles import extra_module, limit_of, waypoint_values
from .trajectory import Trajectory

__all__ = ["MOST_WAYPOINTS", "jerk_limited"]

MOST_WAYPOINTS = 20_000
"""The most waypoints :func:`jerk_limited` takes: one Ruckig segment each, about 1.1 ms a
waypoint (1,000 in 1.09 s on 2 cores, ad hoc), so 20,000 in about 22 s; more are refused
at once."""


def _segment(ruckig: Any, a: np.ndarray, b: np.ndarray, limits: tuple[np.ndarray, ...]) -> Any:
    """Ruckig's rest-to-rest trajectory from a to b within (velocity, acceleration, jerk)."""
    n = len(a)
    given = ruckig.InputParameter(n)
    given.current_position, given.target_position = a.tolist(), b.tolist()
    given.current_velocity = given.target_velocity = [0.0] * n
    given.current_acceleration = given.target_acceleration = [0.0] * n
    v, acc, jerk = limits
    given.max_velocity, given.max_acceleration, given.max_jerk = (
        v.tolist(),
        acc.tolist(),
        jerk.tolist(),
    )
    out = ruckig.Trajectory(n)
    result = ruckig.Ruckig(n).calculate(given, out)
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise InvalidParameterError(f"Ruckig found no motion between the waypoints: {result}")
    return out


def _pieces(segment: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(breaks from 0, coefficients (P, n, 6)) of one Ruckig trajectory, exactly: each
    joint's seven phases (jerk constant) cut where any joint's phase ends."""
    profiles = segment.profiles[0]
    ends = [np.cumsum(p.t) for p in profiles]
    breaks = np.unique(np.concatenate([[0.0, segment.duration], *ends]))
    breaks = breaks[breaks <= segment.duration]
    c = np.zeros((len(breaks) - 1, n, 6))
    for d, p in enumerate(profiles):
        starts = np.concatenate([[0.0], ends[d][:-1]])
        for k, t0 in enumerate(breaks[:-1].tolist()):
            i = min(int(np.searchsorted(ends[d], t0, side="right")), 6)
            s = t0 - starts[i]  # into phase i
            j, a, v, x = p.j[i], p.a[i], p.v[i], p.p[i]
            c[k, d, :4] = (x + v * s + a * s * s / 2 + j * s**3 / 6, v + a * s + j * s * s / 2,
                           (a + j * s) / 2, j / 6)  # fmt: skip
    return breaks, c


def jerk_limited(
    robot: Any, waypoints: ArrayLike, *, acceleration: ArrayLike, jerk: ArrayLike,
    velocity: ArrayLike | None = None,
) -> Trajectory:  # fmt: skip
    """Through ``waypoints`` (K, nq), at rest at each, every segment as short as the joint
    ``velocity`` (default: the description's), ``acceleration`` and ``jerk`` limits (nv,)
    or one for all [rad/s, rad/s^2, rad/s^3, or m] allow, the joints arriving together
    (Ruckig, the ``motion`` extra); cubic pieces, exactly Ruckig's."""
    ruckig = extra_module("ruckig", "jerk_limited")
    A = waypoint_values(robot, waypoints)
    if len(A) > MOST_WAYPOINTS:
        raise InvalidParameterError(
            f"jerk_limited takes at most {MOST_WAYPOINTS:,} waypoints, got {len(A):,}: thin "
            "the path first (every k-th waypoint) or time it by parts"
        )
    v = limit_of(robot, velocity, "velocity", np.asarray(robot.model.velocityLimit))
    acc = limit_of(robot, acceleration, "acceleration", None)
    j = limit_of(robot, jerk, "jerk", None)
    if v is None or acc is None or j is None:
        raise InvalidParameterError(f"{robot.name}: give velocity= (its description has no "
                                    "finite limits), acceleration= and jerk=")  # fmt: skip
    if np.any(np.all(np.diff(A, axis=0) == 0, axis=1)):
        raise InvalidParameterError("two neighbouring waypoints are the same: no motion")
    breaks, pieces, times = [0.0], [], [0.0]
    for a, b in itertools.pairwise(A):
        local, c = _pieces(_segment(ruckig, a, b, (v, acc, j)), robot.joints.nv)
        breaks += (breaks[-1] + local[1:]).tolist()
        pieces.append(c)
        times.append(breaks[-1])
    return Trajectory(np.array(breaks), np.concatenate(pieces), A, np.array(times),
                      "jerk-limited")  # fmt: skip
