"""[P1]'s backlash simulated: the arm's links driven through their gaps by forward dynamics,
a check of the quasi-static reading (:func:`~toolkit.backlash.along`) by another route.

Each joint's drive holds its link through a gap of width delta and a spring: with
e = theta - q (output minus command), the drive's torque on the link is 0 inside the gap
(|e| <= delta / 2) and -K (e - sign(e) delta / 2) outside it, K = M_H / (delta k_H) the
stiffness eq. 17 implies (at rest theta = q + delta (sign(M) / 2 + k_H M / M_H) exactly), and
a damper -D (theta' - q') with D = 2 zeta sqrt(K I) (I the joint's inertia at the start,
zeta the damping ratio). The links move by Pinocchio's ABA with the payload, integrated by
fourth-order Runge-Kutta; nothing of eq. 16's fixed point is used.

What it shows (``benchmarks/backlash_simulation.py``, docs/backlash.md): the joints gravity
loads, always in contact, follow the quasi-static dynamic reading closely; a joint gravity
leaves unloaded floats inside its gap, where the reading's instant jumps across the gap
become motions that take time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ...motion import Trajectory
from .layer import Backlash
from .motion import deviations

__all__ = ["SimulatedBacklash", "simulate"]


@dataclass(frozen=True)
class SimulatedBacklash:
    """A simulated motion, sampled: ``t`` (S,) [s]; ``q`` (S, n) the commands; ``theta`` and
    ``theta_dot`` (S, n) the links' angles and velocities; ``deviation`` (S,) [m] the tool's
    distance from where the command puts it."""

    t: np.ndarray
    q: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    deviation: np.ndarray


def simulate(
    layer: Backlash, trajectory: Trajectory, *, rate: float = 200.0, step: float = 2e-4,
    damping: float = 0.7, start: np.ndarray | None = None,
) -> SimulatedBacklash:  # fmt: skip
    """The links of ``layer``'s arm driven through their gaps along a commanded
    ``trajectory`` (module doc), sampled at ``rate`` [Hz], integrated with time ``step``
    [s] (at most 1/20 of the fastest joint's period is advised) and damping ratio
    ``damping``, from the links at ``start`` (default: the static reading of the first
    command) at rest."""
    if not isinstance(layer, Backlash):
        raise InvalidParameterError(f"layer must be a Backlash layer, got {layer!r:.80}")
    if not isinstance(trajectory, Trajectory):
        raise InvalidParameterError(f"trajectory must be a toolkit.motion.Trajectory, got "
                                    f"{trajectory!r:.80}")  # fmt: skip
    rate = _validate.number(rate, "rate [Hz]", lower=0.0, strict=True)
    step = _validate.number(step, "step [s]", lower=0.0, strict=True, upper=0.01)
    damping = _validate.number(damping, "damping", lower=0.0)
    robot, model = layer.robot, layer.model
    data = model.createData()
    steps = max(1, int(np.ceil(trajectory.duration / step)))
    dt = trajectory.duration / steps
    q, qd, _ = trajectory.evaluate(np.arange(2 * steps + 1) * dt / 2)  # every half step
    theta = layer.output_angles(q[0]) if start is None else robot.joints.check(start)
    theta = np.array(theta, dtype=float)
    K = layer.nominal_torque / (layer.delta * layer.k_h)
    D = 2.0 * damping * np.sqrt(K * np.diag(pin.crba(model, data, theta)))
    half = layer.delta / 2.0

    def accel(i: int, th: np.ndarray, w: np.ndarray) -> np.ndarray:
        e = th - q[i]
        tau = np.where(np.abs(e) > half, -K * (e - np.sign(e) * half), 0.0) - D * (w - qd[i])
        return np.asarray(pin.aba(model, data, th, w, tau))

    every = max(1, round(1.0 / (rate * dt)))  # steps between samples
    out, dots, w = [theta.copy()], [np.zeros(robot.joints.nv)], np.zeros(robot.joints.nv)
    for k in range(steps):  # fourth-order Runge-Kutta on (theta, w)
        i = 2 * k
        a1 = accel(i, theta, w)
        w2 = w + dt / 2 * a1
        a2 = accel(i + 1, theta + dt / 2 * w, w2)
        w3 = w + dt / 2 * a2
        a3 = accel(i + 1, theta + dt / 2 * w2, w3)
        w4 = w + dt * a3
        a4 = accel(i + 2, theta + dt * w3, w4)
        theta = theta + dt / 6 * (w + 2 * w2 + 2 * w3 + w4)
        w = w + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        if (k + 1) % every == 0:
            out.append(theta.copy())
            dots.append(w.copy())
    kept = np.arange(len(out)) * every
    links = np.array(out)
    (deviation,) = deviations(robot, q[2 * kept], links)
    return SimulatedBacklash(kept * dt, q[2 * kept], links, np.array(dots), deviation)
