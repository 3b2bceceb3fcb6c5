"""Independent reference routes used by several tests (no toolkit code inside)."""

from __future__ import annotations

import numpy as np


def rot_log(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (for finite differences of orientation)."""
    cos = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    if angle < 1e-12:
        return np.zeros(3)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return angle * w / (2.0 * np.sin(angle))


def fd_jacobian(fk, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central finite-difference Jacobian (rows vx vy vz wx wy wz, base-aligned) of a pose map."""
    cols = []
    for i in range(len(q)):
        dq = np.zeros_like(q)
        dq[i] = h
        Tp, Tm = fk(q + dq), fk(q - dq)
        v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        w = rot_log(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
        cols.append(np.concatenate([v, w]))
    return np.array(cols).T
