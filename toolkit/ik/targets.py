"""IK targets, shared by both solvers: a pose or a position checked (:func:`parse_target`,
:func:`parse_pose`), a mask's six weights (:func:`parse_mask`), and a rotation block that is
not quite orthonormal moved to the nearest rotation (:func:`nearest_rotations`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError
from .checks import check_pose, pair_errors

__all__ = ["ORTHONORMAL", "nearest_rotations", "parse_mask", "parse_pose", "parse_target"]

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
    moved[bad] = pair_errors(out[bad], np.ascontiguousarray(poses[bad]))[1]
    return out, moved


def parse_target(target: object) -> tuple[np.ndarray, np.ndarray, bool]:
    """(rotation, position, position_only) of a 4x4 pose or a 3-vector position."""
    pose, position_only = parse_pose(target)
    return pose[:3, :3].copy(), pose[:3, 3].copy(), position_only


def parse_pose(target: object) -> tuple[np.ndarray, bool]:
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
        return (POSITION if position_only else UNIT).copy()
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


UNIT = np.ones(6)
"""The weights of a pose target (every axis); never written."""
POSITION = np.array([1.0, 1, 1, 0, 0, 0])
"""The weights of a position target (x, y, z); never written."""
_FLOAT64 = np.dtype(np.float64)
