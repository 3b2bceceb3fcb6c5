"""Vectorised kinematics and gravity of a serial chain, over many configurations at once.

Pinocchio evaluates one configuration per call (about 2 us from Python for FK plus
gravity). Error maps and the backlash benchmark need hundreds of thousands, so
:class:`SerialChain` copies the joint placements, axes and inertias out of a
Pinocchio model once and evaluates FK and the generalized gravity with NumPy over
a batch dimension. It is a second, independent route: the tests compare it with
Pinocchio at random configurations.

Scope: a chain whose joint ``j`` has joint ``j - 1`` as parent, every joint a
1-DoF revolute or prismatic joint (aligned or unaligned axis), no mimic joints.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from . import _validate
from .errors import ConfigurationError, InvalidParameterError, UnsupportedModelError

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["SerialChain"]

Walked = tuple[int, list[np.ndarray], np.ndarray, np.ndarray, np.ndarray]

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _joint_axis(joint: pin.JointModel) -> tuple[bool, np.ndarray]:
    """(revolute?, unit axis in the joint frame) of a 1-DoF joint model."""
    short = joint.shortname()
    for prefix, revolute in (("JointModelR", True), ("JointModelP", False)):
        if short.startswith(prefix):
            tail = short[len(prefix) :]
            if tail in _AXES:
                return revolute, np.array(_AXES[tail])
            if tail in ("evoluteUnaligned", "rismaticUnaligned", "evoluteUnboundedUnaligned"):
                axis = np.asarray(joint.extract().axis, dtype=float)
                return revolute, axis / np.linalg.norm(axis)
            if tail.startswith("evoluteUnbounded"):
                raise UnsupportedModelError(
                    "continuous (unbounded) joints are not supported by SerialChain"
                )
    raise UnsupportedModelError(
        f"SerialChain supports 1-DoF revolute/prismatic joints, not {short}"
    )


def _times_constant(cols: list[np.ndarray], C: np.ndarray) -> list[np.ndarray]:
    """Columns of R @ C, for R given by its columns (each (3, N)) and a constant 3x3 C."""
    out = []
    for k in range(3):
        acc = None
        for j in range(3):
            if C[j, k] != 0.0:
                term = cols[j] if C[j, k] == 1.0 else cols[j] * C[j, k]
                acc = term if acc is None else acc + term
        out.append(acc if acc is not None else np.zeros_like(cols[0]))
    return out


def _times_rotation(
    cols: list[np.ndarray], axis: np.ndarray, angles: np.ndarray
) -> list[np.ndarray]:
    """Columns of R @ Rot(axis, angle) for N angles (Rodrigues' formula, entry by entry)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    K2 = K @ K
    s, one_minus_c = np.sin(angles), 1.0 - np.cos(angles)
    out = []
    for k in range(3):
        acc = None
        for j in range(3):
            eye = 1.0 if j == k else 0.0
            if eye == 0.0 and K[j, k] == 0.0 and K2[j, k] == 0.0:
                continue
            coeff = eye + s * K[j, k] + one_minus_c * K2[j, k]
            term = cols[j] * coeff
            acc = term if acc is None else acc + term
        out.append(acc if acc is not None else np.zeros_like(cols[0]))
    return out


class SerialChain:
    """Joint placements, axes and inertias of a serial Pinocchio model, evaluated in batches.

    Attributes:
        n: number of joints (= nq).
        revolute: per joint, True for revolute and False for prismatic.
        masses: mass of the bodies carried by each joint [kg].
        gravity: gravity vector in the base frame [m/s^2] (Pinocchio's ``model.gravity``).
    """

    def __init__(self, model: pin.Model, tip_frame: int) -> None:
        if not isinstance(model, pin.Model):
            raise InvalidParameterError(f"model must be a pinocchio.Model, got {model!r:.100}")
        tip_frame = _validate.count(
            tip_frame, "tip_frame", minimum=0, maximum=len(model.frames) - 1
        )
        n = model.njoints - 1
        if n < 1 or model.nq != n or model.nv != n:
            raise UnsupportedModelError(
                "SerialChain needs one coordinate per joint (no mimic joints)"
            )
        if hasattr(model, "mimicking_joints") and len(model.mimicking_joints) > 0:
            raise UnsupportedModelError("SerialChain does not support mimic joints")
        self.n = n
        self.revolute = np.zeros(n, dtype=bool)
        self._axes = np.zeros((n, 3))
        self._rot = np.zeros((n, 3, 3))
        self._trans = np.zeros((n, 3))
        self.masses = np.zeros(n)
        self._levers = np.zeros((n, 3))
        for j in range(1, n + 1):
            if model.parents[j] != j - 1:
                raise UnsupportedModelError(
                    "SerialChain needs a chain: joint j must have parent j - 1"
                )
            self.revolute[j - 1], self._axes[j - 1] = _joint_axis(model.joints[j])
            placement = model.jointPlacements[j]
            self._rot[j - 1] = placement.rotation
            self._trans[j - 1] = placement.translation
            self.masses[j - 1] = model.inertias[j].mass
            self._levers[j - 1] = model.inertias[j].lever
        frame = model.frames[tip_frame]
        self._tip_joint = int(frame.parentJoint)
        self._tip_rot = np.array(frame.placement.rotation)
        self._tip_trans = np.array(frame.placement.translation)
        self.gravity = np.array(model.gravity.linear)

    @classmethod
    def from_robot(cls, robot: Robot, frame: str | None = None) -> SerialChain:
        """The chain of a :class:`~toolkit.robot.Robot` up to ``frame`` (default: its tip)."""
        return cls(robot.model, robot.frame_id(frame))

    def _check(self, q: np.ndarray) -> np.ndarray:
        arr = _validate.array(q, "q", error=ConfigurationError)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.n:
            raise ConfigurationError(f"q must have shape (N, {self.n}), got {np.shape(q)}")
        return arr

    def _walk(self, q: np.ndarray) -> Iterator[Walked]:
        """Yield, per joint j: (j, R columns, p, axis, origin), each vector of shape (3, N).

        R and p are the joint frame's pose after its motion; axis and origin locate the
        joint axis in the base frame.
        """
        N = len(q)
        cols = [np.repeat(np.eye(3)[:, k : k + 1], N, axis=1) for k in range(3)]
        p = np.zeros((3, N))
        for j in range(self.n):
            t = self._trans[j]
            p = p + sum(cols[i] * t[i] for i in range(3) if t[i] != 0.0)
            cols = _times_constant(cols, self._rot[j])
            a = self._axes[j]
            axis_world = sum(cols[i] * a[i] for i in range(3) if a[i] != 0.0)
            origin = p
            if self.revolute[j]:
                cols = _times_rotation(cols, a, q[:, j])
            else:
                p = p + axis_world * q[:, j]
            yield j, cols, p, axis_world, origin

    def tip_poses(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rotations (N, 3, 3), positions (N, 3)) of the tip frame for q of shape (N, n)."""
        q = self._check(q)
        cols, p = self._tip(q)
        return np.stack(cols, axis=-1).transpose(1, 0, 2), p.T

    def _tip(self, q: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        N = len(q)
        cols = [np.repeat(np.eye(3)[:, k : k + 1], N, axis=1) for k in range(3)]
        p = np.zeros((3, N))
        for j, cj, pj, _, _ in self._walk(q):
            if j + 1 == self._tip_joint:
                cols, p = cj, pj
        t = self._tip_trans
        p = p + sum(cols[i] * t[i] for i in range(3) if t[i] != 0.0)
        return _times_constant(cols, self._tip_rot), p

    def tip_positions(self, q: np.ndarray) -> np.ndarray:
        """Positions (N, 3) of the tip frame."""
        return self._tip(self._check(q))[1].T

    def gravity_load(self, q: np.ndarray) -> np.ndarray:
        """Torque (force) that gravity exerts on each joint, shape (N, n).

        This is ``-g(q)`` of Pinocchio's ``computeGeneralizedGravity``: the
        generalized force of the bodies' weights, positive when gravity pulls the
        joint towards increasing q.
        """
        q = self._check(q)
        g = self.gravity
        torque = np.zeros((len(q), self.n))
        weighted = np.zeros((3, len(q)))  # sum over bodies k >= j of m_k c_k
        total = 0.0  # sum over bodies k >= j of m_k
        frames = list(self._walk(q))
        for j, cols, p, axis, origin in reversed(frames):
            lever = self._levers[j]
            com = p + sum(cols[i] * lever[i] for i in range(3) if lever[i] != 0.0)
            weighted = weighted + self.masses[j] * com
            total += self.masses[j]
            if self.revolute[j]:
                arm = weighted - total * origin
                moment = np.stack(
                    [
                        arm[1] * g[2] - arm[2] * g[1],
                        arm[2] * g[0] - arm[0] * g[2],
                        arm[0] * g[1] - arm[1] * g[0],
                    ]
                )
                torque[:, j] = np.einsum("in,in->n", axis, moment)
            else:
                torque[:, j] = total * (axis.T @ g)
        return torque
