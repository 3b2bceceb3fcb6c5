"""A joint trajectory as piecewise polynomials of time (degree 5 at most, one value per joint),
sampled at any times or at a rate, checked against limits (see :mod:`toolkit.motion`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..dynamics import inverse_dynamics
from ..errors import InvalidParameterError
from ..robot import as_robot

__all__ = ["MAX_SAMPLES", "Samples", "Trajectory"]

MAX_SAMPLES = 10_000_000
"""The most samples :meth:`Trajectory.at_rate` gives (a 1 kHz sampling of 2.8 hours)."""


@dataclass(frozen=True)
class Samples:
    """A trajectory sampled: ``t`` (M,) [s], ``q`` (M, nq) the robot's configurations,
    ``angles``, ``qd`` [rad/s or m/s], ``qdd`` (M, nv) one value per joint."""

    t: np.ndarray
    q: np.ndarray
    angles: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


@dataclass(frozen=True)
class Trajectory:
    """Joint values (one per joint) as polynomials of time on pieces: ``breaks`` (P + 1,) [s]
    from 0, ``coefficients`` (P, n, K) (K = 6, degree 5, but for a time-optimal one, degree
    6): piece p, joint j is sum c_k (t - breaks[p])^k.
    ``waypoints`` (K, n) and ``times`` (K,) are the values and times it passes through;
    ``kind`` says how it was made."""

    breaks: np.ndarray
    coefficients: np.ndarray
    waypoints: np.ndarray
    times: np.ndarray
    kind: str

    @property
    def duration(self) -> float:
        """[s]"""
        return float(self.breaks[-1])

    def evaluate(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(values, first, second derivatives) (M, n) at times ``t`` (M,) [s] within
        [0, duration] (checked)."""
        T = _validate.real_array(t, "t [s]").reshape(-1)
        if (
            not np.all(np.isfinite(T))
            or T.min(initial=0.0) < 0
            or T.max(initial=0.0) > (self.duration * (1 + 1e-12) + 1e-12)
        ):
            raise InvalidParameterError(
                f"t must be finite times within [0, {self.duration:.6g}] s (the trajectory)"
            )
        piece = np.clip(np.searchsorted(self.breaks, T, side="right") - 1, 0, len(self.breaks) - 2)
        s = (T - self.breaks[piece])[:, None]
        c = self.coefficients[piece]  # (M, n, K): degree K - 1
        K = c.shape[2]
        powers = s[..., None] ** np.arange(K)  # (M, 1, K)
        q = (c * powers).sum(axis=2)
        d1 = (c[..., 1:] * np.arange(1, K) * powers[..., : K - 1]).sum(axis=2)
        d2 = (c[..., 2:] * np.arange(2, K) * np.arange(1, K - 1) * powers[..., : K - 2]).sum(axis=2)
        return q, d1, d2

    def sample(self, robot: Any, t: ArrayLike) -> Samples:
        """The trajectory at times ``t`` as ``robot``'s configurations (a continuous joint's
        (cos, sin) from its angle)."""
        robot = as_robot(robot)
        T = _validate.real_array(t, "t [s]").reshape(-1)
        a, d1, d2 = self.evaluate(T)
        return Samples(T, robot.joints.q_from_angles(a), a, d1, d2)

    def at_rate(self, robot: Any, rate: float = 1000.0) -> Samples:
        """:meth:`sample` every 1 / ``rate`` s [Hz] from 0, the end included (the last sample
        moved onto the end when rounding left it within a millionth of a step)."""
        as_robot(robot)
        rate = _validate.number(rate, "rate [Hz]", lower=0.0, strict=True)
        count = int(np.floor(self.duration * rate + 1e-9)) + 1
        if count > MAX_SAMPLES:
            raise InvalidParameterError(
                f"{count:,} samples at {rate:g} Hz over {self.duration:.3g} s: more than "
                f"{MAX_SAMPLES:,}; choose a lower rate"
            )
        t = np.arange(count) / rate
        if t[-1] < self.duration - 1e-6 / rate:  # the end, unless rounding put a sample there
            t = np.append(t, self.duration)
        else:
            t[-1] = self.duration
        return self.sample(robot, t)

    def peaks(self, rate: float = 1000.0) -> tuple[np.ndarray, np.ndarray]:
        """(the largest |velocity|, the largest |acceleration|) (n,) of each joint, sampled
        at ``rate`` [Hz] and at every piece's ends."""
        t = np.unique(np.concatenate([np.arange(0.0, self.duration, 1.0 / rate), self.breaks]))
        _, d1, d2 = self.evaluate(t)
        return np.abs(d1).max(axis=0), np.abs(d2).max(axis=0)

    def torques(self, robot: Any, rate: float = 1000.0, *, payload: object = None) -> tuple[
        Samples, np.ndarray
    ]:  # fmt: skip
        """(the samples at ``rate``, the joint torques (M, nv) [N m or N] along them by
        inverse dynamics, with a ``payload`` as for :func:`toolkit.dynamics.inverse_dynamics`)."""
        s = self.at_rate(robot, rate)
        return s, inverse_dynamics(robot, s.q, s.qd, s.qdd, payload=payload)
