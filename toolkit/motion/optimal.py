"""The fastest timing of a path within joint velocity, acceleration and (optionally) torque
limits: TOPP-RA (Pham and Pham, IEEE T-RO 34(3), 2018) through the maintained ``toppra``
package (the ``motion`` extra), its answer sampled into a :class:`Trajectory`."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..dynamics import inverse_dynamics, require_inertia
from ..errors import InvalidParameterError
from .profiles import extra_module, limit_of, waypoint_values
from .trajectory import Trajectory

__all__ = ["MOST_WAYPOINTS", "exact_pieces", "time_optimal"]

MOST_WAYPOINTS = 1_000
"""The most waypoints :func:`time_optimal` takes: TOPP-RA's grid and the checks between its
points cost about 20 ms a waypoint (1,000 in 20.6 s, 200 in 4.1 s on 2 cores, ad hoc), so
more are refused at once; thin a dense path first (every k-th waypoint), or time it by parts."""

_ROUNDS = 8
_SLACK = 2e-3  # how far below a limit the answer's peak may stay once it has been scaled
_GRID = 4000  # the fewest points of a refined grid on a path through _MANY waypoints or more
_MANY = 50  # (fewer: 4 times the pieces; the finer grid cost 3.5 times the time on 4
# waypoints for 0.5 % of the duration)
_AIM = 1.0 - 1e-4  # the peak aimed at: the samples between checks passed it by 3e-5


def _toppra() -> Any:
    toppra = extra_module("toppra", "time_optimal")
    for part in ("algorithm", "constraint"):
        extra_module(f"toppra.{part}", "time_optimal")
    toppra.setup_logging("WARNING")
    return toppra


def _path(toppra: Any, A: np.ndarray) -> Any:
    """The cubic spline through waypoints (K, n) against their chord length, clamped (at
    rest along the path at both ends)."""
    chord = np.linalg.norm(np.diff(A, axis=0), axis=1)
    if np.any(chord <= 0):
        raise InvalidParameterError(
            f"waypoints {int(np.flatnonzero(chord <= 0)[0])} and the next are the same"
        )
    s = np.concatenate([[0.0], np.cumsum(chord)]) / chord.sum()
    s[-1] = 1.0  # exactly: a grid must end where the path does (the sum may round below)
    return toppra.SplineInterpolator(s, A, bc_type="clamped")


def _finer(path: Any, count: int) -> np.ndarray:
    """A grid of ``count`` even points on [0, 1] and every knot of the path, without the even
    points within 1e-9 of a knot (a sliver of an interval, where the solver's rounding
    shows)."""
    knots = np.asarray(path.cspl.x, dtype=float)
    even = np.linspace(0.0, 1.0, count)
    at = np.searchsorted(knots, even)
    left, right = knots[np.maximum(at - 1, 0)], knots[np.minimum(at, len(knots) - 1)]
    near = np.minimum(np.abs(even - left), np.abs(even - right)) < 1e-9
    return np.union1d(even[~near], knots)


def time_optimal(
    robot: Any, waypoints: ArrayLike, *, acceleration: ArrayLike,
    velocity: ArrayLike | None = None, torque: ArrayLike | bool | None = None,
    payload: object = None,
) -> Trajectory:  # fmt: skip
    """The fastest motion along the cubic spline through ``waypoints`` (K, nq) (clamped: at
    rest at both ends) within joint ``velocity`` (default: the description's) and
    ``acceleration`` limits (nv,) or one for all [rad/s, rad/s^2 or m/s, m/s^2], and with
    ``torque`` limits [N m or N] (True: the description's effort limits; None: none)
    through :func:`toolkit.dynamics.inverse_dynamics` with ``payload``. Solved by TOPP-RA
    (``toppra``, the ``motion`` extra) on its grid, returned as the piecewise polynomial
    of degree 6 that is its answer exactly (:func:`exact_pieces`)."""
    A = waypoint_values(robot, waypoints)
    if len(A) > MOST_WAYPOINTS:
        raise InvalidParameterError(
            f"time_optimal takes at most {MOST_WAYPOINTS:,} waypoints, got {len(A):,}: thin "
            "the path first (every k-th waypoint) or time it by parts"
        )
    toppra = _toppra()
    v = limit_of(robot, velocity, "velocity", np.asarray(robot.model.velocityLimit))
    a = limit_of(robot, acceleration, "acceleration", None)
    if v is None or a is None:
        raise InvalidParameterError(f"{robot.name}: give velocity= (its description has no "
                                    "finite limits) and acceleration=")  # fmt: skip
    tau = None
    if payload is not None and (torque is None or torque is False):
        raise InvalidParameterError("payload= matters with torque limits only: give torque=")
    if torque is not None and torque is not False:
        effort = np.asarray(robot.model.effortLimit) if torque is True else torque
        tau = limit_of(robot, effort, "torque", None)
        if tau is None:
            raise InvalidParameterError(f"{robot.name}'s description has no effort limits")
        require_inertia(robot, "torque-limited timing")
    path = _path(toppra, A)
    motion = _within(toppra, robot, path, (v, a, tau), payload)
    return Trajectory(motion.breaks, motion.coefficients, A, np.array([0.0, motion.duration]),
                      "time-optimal")  # fmt: skip


def _within(
    toppra: Any, robot: Any, path: Any, limits: tuple[np.ndarray, np.ndarray, Any],
    payload: object,
) -> Trajectory:  # fmt: skip
    """TOPP-RA's answer within the limits between its grid points too: the velocity and
    acceleration limits it is given scaled until the answer's largest ratio to a limit is
    within 0.2 % below 0.9999, the grid refined the first time a limit is passed (4 times
    the pieces, at least 4,000 points on a path through 50 waypoints or more, every
    waypoint's knot); with torque limits, which holding the arm may pin and scaling cannot
    ease, up to 1, the grid refined (4 times the pieces) each time one is passed. (Scaling
    by the first overshoot alone, which on a coarse grid can be 2.6, as on a UR5 path
    through 1,000 waypoints, gave a motion 1.6 times slower than the optimum.)"""
    v, a, tau = limits
    scale, grid, best = 1.0, None, None
    aim = 1.0 if tau is not None else _AIM  # torque is checked at the grid's samples only
    for _ in range(_ROUNDS):
        motion = _solve(toppra, robot, path, (v * scale, a * scale, tau), payload, grid)
        over = _overshoot(robot, motion, limits, payload) / aim  # 1: at the aim
        if over <= 1.0 and (best is None or motion.duration < best.duration):
            best = motion
        if over <= 1.0 and (scale == 1.0 or over >= 1.0 - _SLACK):
            break
        if over > 1.0 and (grid is None or tau is not None):  # finer where one was passed
            many = tau is None and len(path.cspl.x) >= _MANY
            grid = _finer(path, max(len(motion.breaks) * 4, _GRID if many else 0))
        scale = min(1.0, scale / (over * (1.0 + 1e-6)))
    if best is None:  # pragma: no cover - the rounds have always sufficed
        raise InvalidParameterError(f"the timing exceeds a limit between grid points by "
                                    f"{100 * (over - 1):.2g} % after {_ROUNDS} rounds")  # fmt: skip
    return best


def _solve(
    toppra: Any, robot: Any, path: Any, limits: tuple[np.ndarray, np.ndarray, Any],
    payload: object, grid: np.ndarray | None,
) -> Trajectory:  # fmt: skip
    """TOPP-RA within (velocity, acceleration, torque or None) limits, exactly as pieces."""
    v, a, tau = limits
    constraint = toppra.constraint
    given = [constraint.JointVelocityConstraint(np.stack([-v, v], axis=1)),
             constraint.JointAccelerationConstraint(np.stack([-a, a], axis=1))]  # fmt: skip
    if tau is not None:

        def needs(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
            return np.asarray(inverse_dynamics(robot, robot.joints.q_from_angles(q), qd, qdd,
                                               payload=payload))  # fmt: skip

        given.append(constraint.JointTorqueConstraint(
            needs, np.stack([-tau, tau], axis=1), np.zeros(robot.joints.nv)))  # fmt: skip
    for c in given:  # each limit held at both ends of every grid interval
        c.set_discretization_type(constraint.DiscretizationType.Interpolation)
    solver = toppra.algorithm.TOPPRA(given, path, gridpoints=grid,
                                     parametrizer="ParametrizeConstAccel")  # fmt: skip
    if solver.compute_trajectory(0.0, 0.0) is None:
        raise InvalidParameterError(
            "no timing within these limits: the path cannot be followed (a torque limit "
            "below what holding the arm on the path needs?)"
        )
    data = solver.problem_data
    breaks, c = exact_pieces(path.cspl, np.asarray(data.gridpoints), np.asarray(data.sd_vec))
    return Trajectory(breaks, c, c[:0, :, 0], breaks[:0], "time-optimal")


def _overshoot(
    robot: Any, motion: Trajectory, limits: tuple[np.ndarray, np.ndarray, Any], payload: object
) -> float:
    """The largest ratio of |velocity|, |acceleration| (and |torque|) to its limit, at 8
    points of every piece and its ends and every 0.25 ms."""
    v, a, tau = limits
    b = motion.breaks
    t = np.unique(np.concatenate([b, (b[:-1, None] + np.diff(b)[:, None]
                                      * np.linspace(0, 1, 9)[1:-1]).ravel(),
                                  np.linspace(0.0, motion.duration,
                                              int(motion.duration * 4000) + 2)]))  # fmt: skip
    q, qd, qdd = motion.evaluate(np.clip(t, 0.0, motion.duration))
    ratio = max(float((np.abs(qd) / v).max()), float((np.abs(qdd) / a).max()))
    if tau is not None:
        need = inverse_dynamics(robot, robot.joints.q_from_angles(q), qd, qdd, payload=payload)
        ratio = max(ratio, float((np.abs(need) / tau).max()))
    return ratio


def _times_at(s_b: np.ndarray, s0: float, sd0: float, u: float) -> np.ndarray:
    """The times after the start of an interval at which s(t) = s0 + sd0 t + u t^2 / 2
    reaches ``s_b`` (without the cancellation of the textbook root)."""
    d = s_b - s0
    root = sd0 + np.sqrt(np.maximum(sd0 * sd0 + 2.0 * u * d, 0.0))
    return np.where(d > 0, 2.0 * d / np.where(d > 0, root, 1.0), 0.0)


def exact_pieces(
    spline: Any, ss: np.ndarray, sd: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(breaks (P + 1,), coefficients (P, n, 7)) of q(t) = path(s(t)) exactly: the path a
    cubic spline in s (``spline``, SciPy's), s(t) quadratic between the grid points ``ss``
    with speeds ``sd`` (TOPP-RA's constant path acceleration), so each piece, cut where the
    grid or the spline's knots fall, is one polynomial of degree 6 in time."""
    knots, c = spline.x, spline.c  # c (4, m, n): highest power first
    starts, polys = [0.0], []
    for i in range(len(ss) - 1):
        ds = ss[i + 1] - ss[i]
        u = (sd[i + 1] ** 2 - sd[i] ** 2) / (2.0 * ds)
        inner = knots[(knots > ss[i]) & (knots < ss[i + 1])]
        cuts = np.concatenate([[ss[i]], inner, [ss[i + 1]]])
        tau = _times_at(cuts, ss[i], sd[i], u)
        for a, b, s_a in zip(tau[:-1], tau[1:], cuts[:-1], strict=True):
            k = min(int(np.searchsorted(knots, s_a, side="right")) - 1, len(knots) - 2)
            y = np.array([s_a - knots[k], sd[i] + u * a, u / 2.0])  # s - knot, in sigma
            power, out = np.array([1.0]), np.zeros((c.shape[2], 7))
            for m in range(4):  # sum c_m y^m, y a quadratic in sigma
                out[:, : len(power)] += np.outer(c[3 - m, k], power)
                power = np.convolve(power, y)
            polys.append(out)
            starts.append(starts[-1] + (b - a))
    return np.array(starts), np.array(polys)
