"""What a map returns: :class:`ReachabilityMap` and :class:`AccuracyMap`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .grid import Grid

__all__ = ["AccuracyMap", "ReachabilityMap"]


@dataclass(frozen=True)
class ReachabilityMap:
    """A reachability map (:func:`reachability`); arrays in the base frame.

    Attributes:
        centers: voxel centres (nx, ny, nz, 3) [m].
        index: fraction of the orientations solved (nx, ny, nz), in [0, 1].
        best_q: the solved q of the best orientation (nx, ny, nz, nq); NaN where none.
        best_rotation: its tool orientation (nx, ny, nz, 3, 3); NaN where none.
        orientations: the orientations tried (K, 3, 3) (one identity when position-only).
        grid: the voxel grid.
        figures: chunks computed, IK solves and seconds of this run.
    """

    centers: np.ndarray
    index: np.ndarray
    best_q: np.ndarray
    best_rotation: np.ndarray
    orientations: np.ndarray
    grid: Grid
    position_only: bool
    figures: dict[str, float] = field(default_factory=dict)
    robot_name: str = ""


@dataclass(frozen=True)
class AccuracyMap:
    """A backlash-accuracy map (:func:`backlash_accuracy`). Error arrays have shape
    (P, H, nx, ny, nz): payload, k_H, voxel; NaN where no orientation was solved.

    Attributes:
        centers: voxel centres (nx, ny, nz, 3) [m].
        payloads: [kg]; k_h: one per-joint k_H per map layer.
        mean, p95, max: tool position error caused by backlash [m].
        rotation_mean, rotation_p95, rotation_max: tool orientation error [rad].
        compensated_mean, compensated_p95, compensated_max: position error after
            compensation [m] (None unless ``compensate``; NaN where no compensated
            command is inside the joint limits).
        reachable: voxels with at least one solved orientation (nx, ny, nz).
    """

    centers: np.ndarray
    payloads: tuple[float, ...]
    k_h: tuple[tuple[float, ...], ...]
    mean: np.ndarray
    p95: np.ndarray
    max: np.ndarray
    rotation_mean: np.ndarray
    rotation_p95: np.ndarray
    rotation_max: np.ndarray
    reachable: np.ndarray
    grid: Grid
    compensated_mean: np.ndarray | None = None
    compensated_p95: np.ndarray | None = None
    compensated_max: np.ndarray | None = None
    figures: dict[str, float] = field(default_factory=dict)
    robot_name: str = ""
