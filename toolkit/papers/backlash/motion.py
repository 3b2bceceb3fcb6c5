"""[P1]'s backlash along a motion: the joint-output angles of a commanded trajectory with
the torques the motion needs (inverse dynamics, payload included), beside the torques of
gravity alone ([P1]'s static reading), the tool's deviation over time, and the commands
that undo it along the motion.

With the motion's torques ``M(t) = -rnea(theta, qd, qdd)`` (the outputs' velocities and
accelerations taken as the command's: the offsets are small and change slowly, except where
a torque changes sign), eq. 16 holds at every sample: ``theta = q + dtheta(M(theta))``,
solved by iteration from the static answer. A joint whose torque gravity never loads (a
vertical axis: the Katana's joint 1) sits in the middle of its gap at rest and is pushed to
one side by any acceleration: there the two readings part at every speed; elsewhere they
part as the motion's torques grow toward gravity's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ...motion import Trajectory, quintic
from ...robot import Robot, load
from .fixed_point import needs_settling, settle, solve_fixed_point
from .layer import Backlash

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "MotionBacklash",
    "along",
    "compensate_motion",
    "draw_motion_backlash",
    "draw_parting",
    "dynamic_outputs",
    "parting",
    "pick_and_place",
]


@dataclass(frozen=True)
class MotionBacklash:
    """Backlash along a commanded motion, sample by sample: ``t`` (S,) [s]; ``q`` (S, n) the
    commands; ``theta_static`` and ``theta_dynamic`` (S, n) the joint outputs with the
    torques of gravity alone and with the motion's; ``deviation_static`` and
    ``deviation_dynamic`` (S,) [m] the tool's distance from where the command puts it;
    ``residual`` (S,) [rad] of the dynamic fixed point (``converged`` where <= 1e-10)."""

    t: np.ndarray
    q: np.ndarray
    theta_static: np.ndarray
    theta_dynamic: np.ndarray
    deviation_static: np.ndarray
    deviation_dynamic: np.ndarray
    residual: np.ndarray

    @property
    def converged(self) -> np.ndarray:
        return np.asarray(self.residual <= 1e-10)

    @property
    def parting(self) -> float:
        """The largest gap [m] between the two readings' tool deviations."""
        return float(np.abs(self.deviation_dynamic - self.deviation_static).max())


def _layer(layer: object) -> Backlash:
    if not isinstance(layer, Backlash):
        raise InvalidParameterError(f"layer must be a Backlash layer, got {layer!r:.80}")
    return layer


def _check(layer: object, trajectory: object) -> Backlash:
    if not isinstance(trajectory, Trajectory):
        raise InvalidParameterError(f"trajectory must be a toolkit.motion.Trajectory, got "
                                    f"{trajectory!r:.80}")  # fmt: skip
    return _layer(layer)


def dynamic_outputs(
    layer: Backlash, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
    start: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(theta, residual [rad]) (N, n), (N,) of commands q (N, n) moving at qd, qdd (or one
    command (n,): (n,), a number): theta
    = q + dtheta(-rnea(theta, qd, qdd)) from ``start`` (default: the static answer), by
    the bracketing fixed point of the static reading (a joint whose torque changes sign
    inside its gap rests where the torque vanishes)."""
    robot = _layer(layer).robot
    q, qd, qdd = (robot.joints.check(a, batch=True) for a in (q, qd, qdd))
    if qd.shape != q.shape or qdd.shape != q.shape:
        raise InvalidParameterError("q, qd and qdd must have one shape: (n,) or (N, n)")
    one = q.ndim == 1
    q, qd, qdd = np.atleast_2d(q), np.atleast_2d(qd), np.atleast_2d(qdd)
    first = layer.output_angles(q) if start is None else robot.joints.check(start, batch=True)
    first = np.array(np.broadcast_to(first, q.shape), dtype=float)

    def torques(theta: np.ndarray, rows: np.ndarray) -> np.ndarray:
        return layer.torques(theta, qd[rows], qdd[rows])

    def jacobian(theta: np.ndarray, row: int) -> np.ndarray:
        return -np.asarray(
            pin.computeRNEADerivatives(layer.model, layer.data, theta, qd[row], qdd[row])[0]
        )

    out = solve_fixed_point(q, first, layer.delta, torques, layer.offsets, 1e-13, 100)
    rows = needs_settling(out)
    if rows.size:
        out = settle(q, out, layer._law, torques, jacobian, 1e-13, rows)
    residual = np.asarray(out.residual)
    return (out.theta[0], residual[0]) if one else (out.theta, residual)


def along(layer: Backlash, trajectory: Trajectory, rate: float = 200.0) -> MotionBacklash:
    """The backlash of ``layer`` along the commanded ``trajectory`` sampled at ``rate``
    [Hz] (module doc): outputs and tool deviations, static beside dynamic."""
    layer = _check(layer, trajectory)
    robot = layer.robot
    s = trajectory.at_rate(robot, _validate.number(rate, "rate [Hz]", lower=0.0, strict=True,
                                                   upper=100_000.0))  # fmt: skip
    static = layer.output_angles(s.q)
    theta, residual = dynamic_outputs(layer, s.q, s.qd, s.qdd, static)
    apart, apart_dynamic = deviations(robot, s.q, static, theta)
    return MotionBacklash(s.t, s.q, static, theta, apart, apart_dynamic, residual)


def deviations(robot: Robot, q: np.ndarray, *outputs: np.ndarray) -> list[np.ndarray]:
    """Per set of joint outputs (N, nq), the tool's distance [m] (N,) from where the
    commands ``q`` (N, nq) put it."""
    tip = robot.fk(q)[:, :3, 3]
    return [np.linalg.norm(robot.fk(theta)[:, :3, 3] - tip, axis=1) for theta in outputs]


def compensate_motion(
    layer: Backlash, trajectory: Trajectory, rate: float = 200.0
) -> tuple[np.ndarray, np.ndarray]:
    """(t (S,), commands (S, n)) that make the joint outputs follow ``trajectory`` (the
    intended outputs) with the motion's torques: q_cmd = theta - dtheta(M(theta, thetad,
    thetadd)), exact where eq. 16 holds, since the torque depends on the outputs alone."""
    layer = _check(layer, trajectory)
    s = trajectory.at_rate(layer.robot, _validate.number(rate, "rate [Hz]", lower=0.0,
                                                         strict=True, upper=100_000.0))  # fmt: skip
    return s.t, s.q - layer.offsets(layer.torques(s.q, s.qd, s.qdd))


def pick_and_place(duration: float = 5.0) -> Trajectory:
    """A pick-and-place motion of the Katana 6M180 (quintic segments, at rest at each
    waypoint, ``duration`` [s] in all): from above a part, down to it, up, across 90
    degrees of joint 1, down to the place, up. At the default 5 s every joint stays
    within its velocity limit; shorter durations go past them (to show where dynamics
    take over)."""
    duration = _validate.number(duration, "duration [s]", lower=0.0, strict=True)
    robot = load("katana_6m180")
    above = np.array([0.0, 0.6, -1.2, -0.6, 0.0])
    down = np.array([0.0, 0.9, -1.3, -0.9, 0.0])
    turn = np.array([np.pi / 2, 0, 0, 0, 0])
    points = np.array([above, down, above, above + turn, down + turn, above + turn])
    times = np.array([0.0, 0.15, 0.3, 0.7, 0.85, 1.0]) * duration
    return quintic(robot, points, times)


def draw_motion_backlash(data: MotionBacklash, ax: Axes | None = None) -> Axes:
    """The tool's deviation [mm] against time [s], static beside dynamic; returns the axes."""
    import matplotlib.pyplot as plt

    if not isinstance(data, MotionBacklash):
        raise InvalidParameterError(f"data must be what along() returns, got {data!r:.80}")
    _validate.axes(ax)
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    ax.plot(data.t, 1e3 * data.deviation_static, "--", label="gravity and payload only (static)")
    ax.plot(data.t, 1e3 * data.deviation_dynamic, "-", label="with the motion's torques (dynamic)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tool deviation from the command [mm]")
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower center")
    ax.set_title("Katana 6M180, backlash along a pick and place ([P1] eqs. 16-17)")
    return ax


def parting(
    layer: Backlash, durations: ArrayLike = (10.0, 5.0, 3.0, 2.0, 1.0, 0.5),
    rate: float = 200.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """How fast the arm must move before dynamics matter: the pick and place of
    :func:`pick_and_place` at each duration [s] (faster to the right), (durations, the
    largest gap [m] between the dynamic and static tool deviations, the peak joint
    velocity as a fraction of its limit)."""
    layer = _layer(layer)
    d = _validate.real_array(durations, "durations [s]").reshape(-1)
    if not len(d) or not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise InvalidParameterError("durations must be one or more times > 0 [s]")
    limit = layer.robot.model.velocityLimit
    gaps, speed = [], []
    for duration in d.tolist():
        motion = pick_and_place(duration)
        gaps.append(along(layer, motion, rate).parting)
        speed.append(float(np.max(motion.peaks(rate)[0] / limit)))
    return d, np.array(gaps), np.array(speed)


def draw_parting(data: tuple[np.ndarray, np.ndarray, np.ndarray], ax: Axes | None = None) -> Axes:
    """:func:`parting`'s gap [mm] against the peak velocity [fraction of the limit]."""
    import matplotlib.pyplot as plt

    if not (isinstance(data, tuple) and len(data) == 3 and all(
            isinstance(a, np.ndarray) and a.shape == data[0].shape for a in data)):  # fmt: skip
        raise InvalidParameterError(f"data must be what parting() returns, got {data!r:.80}")
    _validate.axes(ax)
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    d, gap, speed = data
    ax.plot(speed, 1e3 * gap, "o-")
    for k, (x, y, t) in enumerate(zip(speed, 1e3 * gap, d, strict=True)):
        below = k % 2 == 1 and k < len(d) - 1  # neighbours alternate: labels apart
        ax.annotate(f"{t:g} s", (x, y), xytext=(-6, -16 if below else 8),
                    textcoords="offset points")  # fmt: skip
    ax.axvline(1.0, color="grey", ls=":", label="the velocity limit")
    ax.set_xlabel("peak joint velocity / its limit")
    ax.set_ylabel("dynamic - static tool deviation [mm]")
    ax.set_xlim(left=0.0)
    ax.set_ylim(-0.08e3 * float(gap.max()), 1.15e3 * float(gap.max()))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left")
    ax.set_title("Where dynamics take over (the same pick and place, faster)")
    return ax
