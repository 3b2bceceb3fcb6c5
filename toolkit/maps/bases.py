"""The inputs of a base placement: tasks, the candidate bases of a floor region, their yaw
angles, a base's pose and the scene as a base sees it."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Scene
from ..common import validate as _validate
from ..errors import InvalidParameterError

__all__ = ["base_pose", "candidate_grid", "scene_from_base", "task_poses", "yaw_angles"]

MAX_CANDIDATES = 4_000_000


def base_pose(base: ArrayLike) -> np.ndarray:
    """The 4x4 world pose of an upright base (x, y, z [m], yaw [rad])."""
    x, y, z, yaw = (float(v) for v in _validate.array(base, "base", shape=(4,)))
    T = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = (x, y, z)
    return T


def scene_from_base(scene: Scene | None, base: ArrayLike) -> Scene | None:
    """``scene`` (objects in the world) as the robot at ``base`` sees it (a 4x4 pose, or
    x, y, z [m], yaw [rad]): every fixed object in the base frame; objects attached to
    links are unchanged."""
    if scene is not None and not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a toolkit Scene or None, got {scene!r:.80}")
    B = _validate.array(base, "base")
    if B.shape == (4,):
        B = base_pose(B)
    elif B.shape != (4, 4) or np.abs(B[:3, :3].T @ B[:3, :3] - np.eye(3)).max() > 1e-6:
        raise InvalidParameterError(
            f"base must be a 4x4 pose or (x, y, z, yaw), got shape {B.shape}"
        )
    if scene is None:
        return None
    inv = np.linalg.inv(B)
    moved = [
        o if o.link else replace(o, pose=tuple((inv @ np.array(o.pose).reshape(4, 4)).ravel()))
        for o in scene
    ]
    return Scene(moved)


def task_poses(tasks: ArrayLike) -> tuple[np.ndarray, bool]:
    """(poses (N, 4, 4), positions only) of tool poses (N, 4, 4) or positions (N, 3)."""
    arr = _validate.array(tasks, "tasks")
    if arr.ndim == 2 and arr.shape[1] == 3 and len(arr):
        poses = np.tile(np.eye(4), (len(arr), 1, 1))
        poses[:, :3, 3] = arr
        return poses, True
    if arr.ndim != 3 or arr.shape[1:] != (4, 4) or not len(arr):
        raise InvalidParameterError(
            f"tasks must be N >= 1 tool poses (N, 4, 4) or positions (N, 3), got shape {arr.shape}"
        )
    R = arr[:, :3, :3]
    if np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max() > 1e-6 or np.any(
        np.linalg.det(R) < 0
    ):
        raise InvalidParameterError("tasks: a 3x3 block is not a rotation matrix")
    return np.array(arr), False


def candidate_grid(region: ArrayLike, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The x and y of the candidate bases: ``region`` [[x0, y0], [x1, y1]] at ``step``."""
    box = _validate.array(region, "region", shape=(2, 2))
    if np.any(box[1] <= box[0]):
        raise InvalidParameterError(
            f"region is [[x_min, y_min], [x_max, y_max]] [m] with max > min on both axes, "
            f"got {box.tolist()} (zero area)"
        )
    axes = [np.arange(box[0, k], box[1, k] + step * 1e-6, step) for k in range(2)]
    if len(axes[0]) * len(axes[1]) > MAX_CANDIDATES:
        raise InvalidParameterError(
            f"region at a {step:g} m step makes {len(axes[0]) * len(axes[1]):,} candidate "
            f"bases (more than {MAX_CANDIDATES:,}): choose a larger step"
        )
    return axes[0], axes[1]


def yaw_angles(yaws: int, yaw_range: ArrayLike) -> np.ndarray:
    """``yaws`` angles over ``yaw_range`` [rad] (a full circle: its end not repeated)."""
    count = _validate.count(yaws, "yaws", minimum=1, maximum=3600)
    lo, hi = (float(v) for v in _validate.array(yaw_range, "yaw_range [rad]", shape=(2,)))
    if hi < lo:
        raise InvalidParameterError(f"yaw_range must be (low, high) with high >= low, got {lo, hi}")
    if hi - lo >= 2 * math.pi - 1e-12:  # a full circle: do not try its end twice
        return lo + 2 * math.pi * np.arange(count) / count
    return np.linspace(lo, hi, count) if count > 1 else np.array([(lo + hi) / 2])
