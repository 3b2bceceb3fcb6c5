"""Compiled checks of inputs and answers (numba): a target pose, a configuration's limits
and unit groups. They share no code with the solver's kernels (:mod:`toolkit.ik.numeric.kernels`):
the IK's verification judges the solver's answer with them and Pinocchio."""

from __future__ import annotations

import numpy as np
from numba import prange

from ..kinematics import kernel, poses, twin_kernel


@kernel
def check_pose(T):
    """0 if T (4, 4) is a pose; else 1 (NaN or infinite entries), 2 (its 3x3 block is not a
    rotation: R^T R = I and det R > 0 within 1e-6) or 3 (its last row is not 0 0 0 1)."""
    s = 0.0
    for i in range(4):
        for j in range(4):
            s += T[i, j]
    if not np.isfinite(s):
        return 1
    for a in range(3):
        for b in range(a, 3):
            d = T[0, a] * T[0, b] + T[1, a] * T[1, b] + T[2, a] * T[2, b]
            if abs(d - (1.0 if a == b else 0.0)) > 1e-6:
                return 2
    minor0 = T[1, 1] * T[2, 2] - T[1, 2] * T[2, 1]
    minor1 = T[1, 0] * T[2, 2] - T[1, 2] * T[2, 0]
    minor2 = T[1, 0] * T[2, 1] - T[1, 1] * T[2, 0]
    if not T[0, 0] * minor0 - T[0, 1] * minor1 + T[0, 2] * minor2 > 0.0:
        return 2
    if max(abs(T[3, 0]), abs(T[3, 1]), abs(T[3, 2]), abs(T[3, 3] - 1.0)) > 1e-12:
        return 3
    return 0


@kernel
def valid_q(q, lower, upper, pairs, quaternions, tol):
    """True if lower <= q <= upper (NaN fails), every (cos, sin) pair ``pairs`` (k, 2) and
    every quaternion ``quaternions`` (m, 4) (indices into q) of unit norm within tol."""
    for i in range(q.shape[0]):
        if not (lower[i] <= q[i] <= upper[i]):
            return False
    for k in range(pairs.shape[0]):
        c, s = q[pairs[k, 0]], q[pairs[k, 1]]
        if abs(c * c + s * s - 1.0) > tol:
            return False
    for k in range(quaternions.shape[0]):
        n = 0.0
        for j in range(4):
            n += q[quaternions[k, j]] * q[quaternions[k, j]]
        if abs(n - 1.0) > tol:
            return False
    return True


@kernel
def pose_errors(H, T):
    """(||p - p_t||, the angle between R and R_t) of poses H and T (4, 4), the angle from
    the chord ||R - R_t||_F = 2 sqrt 2 sin(angle / 2): exact to rounding near 0, where
    tolerances are judged (within 3e-8 rad near pi)."""
    pos = 0.0
    for i in range(3):
        pos += (H[i, 3] - T[i, 3]) ** 2
    chord = 0.0
    for i in range(3):
        for j in range(3):
            chord += (H[i, j] - T[i, j]) ** 2
    return np.sqrt(pos), 2.0 * np.arcsin(min(1.0, np.sqrt(chord) / (2.0 * np.sqrt(2.0))))


@kernel
def pair_errors(F, T):
    """(position errors (B,), orientation errors (B,)) of poses F (B, 4, 4) against their
    own targets T (B, 4, 4), row by row (:func:`pose_errors`)."""
    B = F.shape[0]
    pos = np.empty(B)
    rot = np.empty(B)
    for b in range(B):
        pos[b], rot[b] = pose_errors(F[b], T[b])
    return pos, rot


_CHUNK = 256  # rows per work item of :func:`owned_errors`: one set of buffers each


@kernel
def _owned_rows(Q, chain, Ts, owner, pos, rot, start, stop):
    ints, flts, tip_pl = chain
    W, H = np.empty((ints.shape[0] + 1, 15)), np.empty((4, 4))
    for i in range(start, stop):
        poses.chain_pose(Q[i], ints, flts, tip_pl, W, H)
        pos[i], rot[i] = pose_errors(H, Ts[owner[i]])


@twin_kernel
def owned_errors(Q, ints, flts, tip_pl, Ts, owner):
    """(position errors (M,), orientation errors (M,)) of the frame of a kinematics chain
    (``ints``, ``flts``, ``tip_pl``: :mod:`toolkit.kinematics.kernels`) at configurations Q
    (M, nq) against targets Ts[owner] (:func:`pose_errors`), without a pose made per row:
    several rows (the branches of one target) share a target."""
    M = Q.shape[0]
    pos, rot = np.empty(M), np.empty(M)
    for c in prange((M + _CHUNK - 1) // _CHUNK):
        _owned_rows(Q, (ints, flts, tip_pl), Ts, owner, pos, rot, c * _CHUNK,
                    min(M, (c + 1) * _CHUNK))  # fmt: skip
    return pos, rot
