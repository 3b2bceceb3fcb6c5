"""The IK task: a target pose or position, checked, with the six axis weights of a mask
(:class:`PoseTask`, the one pose residual of the toolkit)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError
from . import branch_kernels
from .checks import check_pose, pose_errors

__all__ = ["PoseTask", "nearest_rotations", "parse_mask", "parse_target"]

ORTHONORMAL = 1e-13
"""A target rotation closer than this to orthonormal (every entry of R^T R - I) is solved
as given; a less exact one (float32, rounded, from a tracker; up to the 1e-6 the pose
checks accept) is first moved to the nearest rotation matrix."""


def nearest_rotations(poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(poses (N, 4, 4) with each rotation block the nearest rotation matrix (in the
    Frobenius norm, by SVD), how far each moved [rad] (N,): the angle of the chord
    between them, 0 for a block already orthonormal to :data:`ORTHONORMAL`). The poses
    are a new array only where one moved."""
    R = poses[:, :3, :3]
    off = np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(axis=(1, 2), initial=0.0)
    moved = np.zeros(len(poses))
    bad = np.flatnonzero(off > ORTHONORMAL)
    if not len(bad):
        return poses, moved
    out = np.array(poses, dtype=float, order="C")
    U, _, Vt = np.linalg.svd(R[bad])
    D = np.ones((len(bad), 3))
    D[:, 2] = np.sign(np.linalg.det(U @ Vt))
    out[bad, :3, :3] = np.einsum("nij,nj,njk->nik", U, D, Vt)
    moved[bad] = branch_kernels.pair_errors(out[bad], np.ascontiguousarray(poses[bad]))[1]
    return out, moved


def parse_target(target: object) -> tuple[np.ndarray, np.ndarray, bool]:
    """(rotation, position, position_only) of a 4x4 pose or a 3-vector position."""
    pose, position_only = _parse(target)
    return pose[:3, :3].copy(), pose[:3, 3].copy(), position_only


def _parse(target: object) -> tuple[np.ndarray, bool]:
    """(a new C-contiguous 4x4 pose, position_only) of a pose or a position, checked."""
    if type(target) is np.ndarray and target.dtype is _FLOAT64:
        arr = target
    else:
        arr = _validate.real_array(target, "IK target")
    if arr.shape == (4, 4):
        pose = arr.copy()
        problem = check_pose(pose)  # compiled: a tenth of the time of the same checks here
        if problem:
            raise InvalidParameterError(_POSE_PROBLEMS[problem - 1])
        return pose, False
    if arr.shape == (3,):
        if not np.all(np.isfinite(arr)):
            raise InvalidParameterError("IK target position has NaN or infinite entries")
        pose = np.eye(4)
        pose[:3, 3] = arr
        return pose, True
    raise InvalidParameterError(
        f"IK target must be a 4x4 pose or a 3-vector position, got shape {arr.shape}"
    )


_POSE_PROBLEMS = (
    "IK target pose has NaN or infinite entries",
    "IK target's 3x3 block is not a rotation matrix",
    "IK target's last row must be (0, 0, 0, 1)",
)


def parse_mask(mask: ArrayLike | None, position_only: bool) -> np.ndarray:
    """The six weights (x, y, z, rx, ry, rz); default all ones, or position only."""
    position_only = _validate.flag(position_only, "position_only")
    if mask is None:
        return (_POSITION if position_only else _UNIT).copy()
    try:
        w = _validate.real_array(mask, "mask")
    except InvalidParameterError:
        w = np.zeros(0)
    if w.shape != (6,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InvalidParameterError(
            f"mask must be six non-negative weights (x, y, z, rx, ry, rz), got {mask!r}"
        )
    if not w.any():
        raise InvalidParameterError("mask selects no axis")
    if position_only and w[3:].any():
        raise InvalidParameterError(
            "a 3-vector target has no orientation: mask rx, ry, rz must be 0"
        )
    return w


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
        pose, position_only = _parse(target)
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


_UNIT = np.ones(6)
_UNIT_LIST = [1.0] * 6
_POSITION = np.array([1.0, 1, 1, 0, 0, 0])
_POSITION_LIST = _POSITION.tolist()
_FLOAT64 = np.dtype(np.float64)
