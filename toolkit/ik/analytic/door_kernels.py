"""Every verified branch of N targets in one compiled call: the door of ``Robot.ik_all`` (one
target: a batch of one) and ``Robot.ik_all_batch`` on the compiled families.

Per target, :func:`branch_rows` checks the pose, runs the family's kernel (on the reversed
chain at T^-1 where the family was found from the frame's end), drops branches equal up to
whole turns, writes each branch into a full configuration with every revolute joint at its
turn within the limits nearest the rest configuration's angle (the wrapped angle in
[-pi, pi) where none fits), and verifies it by the kinematics kernels' forward kinematics
(which share no code with the subproblems). What it cannot finish it flags for the Python
door: a rotation that is not orthonormal to :data:`~toolkit.ik.targets.ORTHONORMAL` (projected
there, then solved again), a row that misses ``tol`` by rounding only (polished there), an
entry that is not a pose (refused there with the reason).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ...kinematics import inline_kernel, kernel, kernels, twin_kernel
from ..checks import check_pose, pose_errors
from ..targets import ORTHONORMAL
from .branch_kernels import EDGE, TWO_PI, distinct_rows
from .family_kernels import five_r_parallel, three_parallel
from .wrist_kernels import meeting_shoulder, spherical_wrist

__all__ = [
    "MOVE",
    "NOT_POSE",
    "ROUGH",
    "ROUGH_ROWS",
    "branch_rows",
    "nearest_turn",
    "nearest_turn_rows",
]

ROUGH = 1e-6
"""[m, rad] A branch of an exact arm that misses ``tol`` by no more than this (rounding at a
singular pose or a tangent) is polished on the real model instead of dropped."""

MOVE, ROUGH_ROWS, NOT_POSE = 1, 2, 4
"""The flags of a target: its rotation must be projected first; a row of it missed ``tol``
by rounding only; it is not a pose (NaN, not a rotation within 1e-6, last row)."""


@inline_kernel
def nearest_turn(a, lo, hi, rest):
    """The angle a + 2 pi k within [lo, hi] (inclusive to :data:`EDGE`) nearest ``rest``; a
    wrapped to [-pi, pi) where none fits or a limit is infinite."""
    x = (a + math.pi) % TWO_PI - math.pi
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return x
    first = math.ceil((lo - EDGE - x) / TWO_PI)
    last = math.floor((hi + EDGE - x) / TWO_PI)
    if last < first:
        return x
    k = min(max(math.floor((rest - x) / TWO_PI + 0.5), first), last)
    return x + TWO_PI * k


@kernel
def nearest_turn_rows(A, lo, hi, rest, turn):
    """Rows A (B, n) with each joint where ``turn`` at :func:`nearest_turn` of ``rest`` (n,)."""
    out = A.copy()
    for b in range(A.shape[0]):
        for j in range(A.shape[1]):
            if turn[j]:
                out[b, j] = nearest_turn(A[b, j], lo[j], hi[j], rest[j])
    return out


@inline_kernel
def _solve(family, geometry, T, near, pref, out, roots, free):
    """The compiled family ``family`` (its index in :data:`toolkit.ik.analytic.chain.COMPILED`)."""
    h, o, tip_R, tip_p = geometry
    if family == 0:
        return three_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free)
    if family == 1:
        return spherical_wrist(h, o, tip_R, tip_p, T, near, pref, out, roots, free)
    if family == 2:
        return meeting_shoulder(h, o, tip_R, tip_p, T, near, pref, out, roots, free)
    return five_r_parallel(h, o, tip_R, tip_p, T, near, pref, out, roots, free)


@inline_kernel
def _reversed_solve(family, geometry, T, near, pref, out, roots, free, work):
    """:func:`_solve` on the reversed chain at T^-1 (``work``: (4, 4) and (n,) scratch),
    its angles turned back (q_i = -q'_{n+1-i}) and its free bits reversed."""
    Ti, back = work
    n = pref.shape[0]
    Ti[:] = 0.0
    Ti[3, 3] = 1.0
    for r in range(3):
        for c in range(3):
            Ti[r, c] = T[c, r]
            Ti[r, 3] -= T[c, r] * T[c, 3]
    for j in range(n):
        back[j] = -pref[n - 1 - j]
    count = _solve(family, geometry, Ti, near, back, out, roots, free)
    for b in range(count):
        bits = 0
        for j in range(n):
            back[j] = -out[b, n - 1 - j]
            if free[b] & (1 << (n - 1 - j)):
                bits |= 1 << j
        out[b, :n] = back
        free[b] = bits
    return count


@inline_kernel
def _target_rows(i, arm, setup, Ts, rest, pref, res, work):  # long: one target's rows
    """Target i's verified rows into ``res`` (Q, E, K, S, C): see :func:`branch_rows`."""
    Q, E, K, S, C = res
    geometry, layout, fk = arm
    family, rev, near, tol = setup
    qcol, circle, lo, hi, qlo, qhi = layout
    ints, flts, tip_pl = fk
    out, rts, fr, W, H, Ti, back, turning = work
    T = Ts[i]
    if check_pose(T) != 0:
        C[i, 1] = NOT_POSE
        return
    off = 0.0
    for a in range(3):
        for b in range(3):
            d = T[0, a] * T[0, b] + T[1, a] * T[1, b] + T[2, a] * T[2, b]
            off = max(off, abs(d - (1.0 if a == b else 0.0)))
    if off > ORTHONORMAL:
        C[i, 1] = MOVE
        return
    rts[:] = -1
    fr[:] = 0
    if rev:
        found = _reversed_solve(family, geometry, T, near, pref, out, rts, fr, (Ti, back))
    else:
        found = _solve(family, geometry, T, near, pref, out, rts, fr)
    n = qcol.shape[0]
    keep = distinct_rows(out[:found], turning)
    k = 0
    for b in range(found):
        if not keep[b]:
            continue
        q = Q[i, k]
        q[:] = rest
        far = 0.0
        for c in range(n):
            a = (out[b, c] + math.pi) % TWO_PI - math.pi
            if not near:
                a = nearest_turn(a, lo[c], hi[c], pref[c])
            far += abs(a - pref[c])
            if circle[c]:
                q[qcol[c]], q[qcol[c] + 1] = math.cos(a), math.sin(a)
            else:
                q[qcol[c]] = a
        kernels.frames(q, ints, flts, W)
        kernels.tip(W, tip_pl, H[:3, :3], H[:3, 3])
        pos, rot = pose_errors(H, T)
        E[i, k, 0], E[i, k, 1], E[i, k, 2] = pos, rot, far
        within = True
        for m in range(q.shape[0]):
            if not (qlo[m] <= q[m] <= qhi[m]):
                within = False
        reached = pos <= tol and rot <= tol
        S[i, k, 0] = within
        S[i, k, 1] = within and reached
        if not reached and not near and pos <= ROUGH and rot <= ROUGH:
            C[i, 1] |= ROUGH_ROWS
        K[i, k, :3] = rts[b]
        K[i, k, 3] = fr[b]
        k += 1
    C[i, 0] = k


@twin_kernel
def branch_rows(arm, setup, Ts, rest, pref):
    """Every branch of targets Ts (N, 4, 4), verified, in five arrays (each a boxed result:
    fewer is faster): Q (N, 8, nq); E (N, 8, 3): position [m] and orientation [rad] errors
    and the sum of the chain's |angle - pref| [rad]; K (N, 8, 4): roots (shoulder, elbow,
    wrist: 0, 1 or -1) and free bits; S (N, 8, 2): within the limits, verified to ``tol``
    and within; C (N, 2): how many branches, flags (:data:`MOVE`, :data:`ROUGH_ROWS`,
    :data:`NOT_POSE`). NaN, -1 or 0 past each target's count.

    ``arm``: (geometry: (axes, points, tip rotation, tip position) of the chain it is
    solved on; layout: per chain joint its place in q, (cos, sin) pair or not, limits, then
    the limits of q; the kinematics kernels' chain (ints, floats, tip)); ``setup``: (the
    family's index in :data:`toolkit.ik.analytic.chain.COMPILED`, solved on the reversed chain, the
    arm only near its family (rows wrapped, to be polished; none flagged rough), tol);
    ``rest`` (1 or N, nq): the other joints' values, one for all targets or one each;
    ``pref`` (1 or N, n): the chain's angles in it."""
    N = Ts.shape[0]
    n = pref.shape[1]
    nq = rest.shape[1]
    per = rest.shape[0] > 1  # one rest per target, else one for all
    Q = np.full((N, 8, nq), np.nan)
    E = np.full((N, 8, 3), np.nan)
    K = np.full((N, 8, 4), -1, np.int64)
    K[:, :, 3] = 0
    S = np.zeros((N, 8, 2), np.bool_)
    C = np.zeros((N, 2), np.int64)
    # a parallel loop takes arrays, not tuples of them: unpacked here, packed in each chunk
    (h, o, tip_R, tip_p), (qcol, circle, lo, hi, qlo, qhi), (ints, flts, tip_pl) = arm
    family, rev, near, tol = setup
    chunk = 64
    for c in prange((N + chunk - 1) // chunk):
        work = (np.zeros((8, n)), np.full((8, 3), -1, np.int64), np.zeros(8, np.int64),
                np.empty((ints.shape[0] + 1, 15)), np.zeros((4, 4)), np.empty((4, 4)),
                np.empty(n), np.zeros(n, np.bool_))  # fmt: skip
        chain = ((h, o, tip_R, tip_p), (qcol, circle, lo, hi, qlo, qhi), (ints, flts, tip_pl))
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            r = i if per else 0
            _target_rows(i, chain, (family, rev, near, tol), Ts, rest[r], pref[r],
                         (Q, E, K, S, C), work)  # fmt: skip
    return Q, E, K, S, C
