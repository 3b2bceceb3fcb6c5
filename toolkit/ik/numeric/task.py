"""The IK task: a checked target with the six axis weights of a mask (:class:`PoseTask`,
the one pose residual of the toolkit)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..checks import pose_errors
from ..targets import POSITION as _POSITION
from ..targets import UNIT as _UNIT
from ..targets import parse_mask, parse_pose

__all__ = ["PoseTask"]


class PoseTask:
    """'Put frame ``frame_id`` on the pose (rotation, position)' with six axis weights.

    The one pose residual of the toolkit: the IK loop, the IK's independent check and the
    backlash compensation all measure errors through it.
    """

    __slots__ = ("_wl", "frame_id", "pose", "unit_weights", "use_rot", "weights")

    def __init__(
        self, frame_id: int, pose: np.ndarray, weights: np.ndarray, wl: list[float] | None = None
    ) -> None:
        """``pose``: a checked (4, 4) float64 C-contiguous target, kept (not copied);
        ``wl``: the weights as floats, if the caller has them."""
        wl = weights.tolist() if wl is None else wl
        self.frame_id, self.pose, self.weights, self._wl = frame_id, pose, weights, wl
        self.use_rot = wl[3] > 0 or wl[4] > 0 or wl[5] > 0
        self.unit_weights = wl == _UNIT_LIST

    @classmethod
    def from_target(cls, frame_id: int, target: object, mask: ArrayLike | None = None) -> PoseTask:
        """The task of a 4x4 pose or 3-vector ``target`` (checked) with an optional mask."""
        pose, position_only = parse_pose(target)
        if mask is None:  # the two unmasked tasks share their (never written) weights
            if position_only:
                return cls(frame_id, pose, _POSITION, _POSITION_LIST)
            return cls(frame_id, pose, _UNIT, _UNIT_LIST)
        return cls(frame_id, pose, parse_mask(mask, position_only))

    @classmethod
    def many(cls, frame_id: int, poses: np.ndarray, weights: np.ndarray) -> list[PoseTask]:
        """The tasks of checked (N, 4, 4) float64 C-contiguous ``poses`` (views of them,
        not copies), one mask for all."""
        wl = weights.tolist()
        return [cls(frame_id, pose, weights, wl) for pose in poses]

    @property
    def rotation(self) -> np.ndarray:
        """The target rotation (3, 3), a view of :attr:`pose`."""
        return self.pose[:3, :3]

    @property
    def position(self) -> np.ndarray:
        """The target position (3,) [m], a view of :attr:`pose`."""
        return self.pose[:3, 3]

    def residual_into(self, e: np.ndarray, placement: pin.SE3) -> None:
        """Write the residual e (6,) of the frame at ``placement`` into ``e``."""
        e[:3] = self.position - placement.translation
        if self.use_rot:
            e[3:] = pin.log3(placement.rotation.T @ self.rotation)
        else:
            e[3:] = 0.0

    def tool_jacobian(self, J: np.ndarray, placement: pin.SE3) -> np.ndarray:
        """J_e = [J_v ; R^T J_w] from a ``LOCAL_WORLD_ALIGNED`` frame Jacobian (in place)."""
        if self.use_rot:
            J[3:] = placement.rotation.T @ J[3:]
        return J

    def norms(self, e: np.ndarray) -> tuple[float, float]:
        """Norms of the selected position [m] and rotation [rad] components of e."""
        v, wl = e.tolist(), self._wl
        pos = math.sqrt(sum(v[i] * v[i] for i in range(3) if wl[i] > 0))
        rot = math.sqrt(sum(v[i] * v[i] for i in range(3, 6) if wl[i] > 0)) if self.use_rot else 0
        return pos, float(rot)

    def errors(self, model: pin.Model, data: pin.Data, q: np.ndarray) -> tuple[float, float]:
        """(position, orientation) errors at q, by a forward-kinematics call on ``data``.

        Without a mask the angle comes from the chord: ||R - R_t||_F = 2 sqrt 2 sin(theta / 2)
        (exact to rounding near 0, where tolerances are judged; within 3e-8 rad near pi)."""
        pin.forwardKinematics(model, data, q)
        placement = pin.updateFramePlacement(model, data, self.frame_id)
        wl = self._wl
        if self.unit_weights or wl is _POSITION_LIST:
            pos, rot = pose_errors(placement.homogeneous, self.pose)
            return float(pos), float(rot) if self.use_rot else 0.0
        dx, dy, dz = (self.position - placement.translation).tolist()
        pos = math.sqrt(
            (dx * dx if wl[0] > 0 else 0.0)
            + (dy * dy if wl[1] > 0 else 0.0)
            + (dz * dz if wl[2] > 0 else 0.0)
        )
        if not self.use_rot:
            return pos, 0.0
        rx, ry, rz = pin.log3(placement.rotation.T @ self.rotation).tolist()
        rot = math.sqrt(
            (rx * rx if wl[3] > 0 else 0.0)
            + (ry * ry if wl[4] > 0 else 0.0)
            + (rz * rz if wl[5] > 0 else 0.0)
        )
        return pos, rot


_UNIT_LIST = _UNIT.tolist()
_POSITION_LIST = _POSITION.tolist()
