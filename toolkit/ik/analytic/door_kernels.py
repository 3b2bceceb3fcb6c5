"""The pieces of every family's door kernel (:func:`toolkit.ik.analytic.batch_kernels.door_of`):
every verified branch of N targets in one compiled call, the door of ``Robot.ik_all`` (one
target: a batch of one) and ``Robot.ik_all_batch`` on the compiled families.

Per target, the door checks the pose (:func:`pose_flag`), has the family solve it (on the
reversed chain at T^-1 where the family was found from the frame's end:
:func:`reversed_target`), and :func:`target_rows` drops branches equal up to whole turns,
writes each branch into a full configuration with every revolute joint at its turn within
the limits nearest the rest configuration's angle (the wrapped angle in [-pi, pi) where
none fits), and verifies it by the kinematics' forward kinematics (which share no code
with the subproblems; :mod:`toolkit.kinematics.poses`, the rows of many targets at once:
:func:`verified_rows`). What it cannot finish it flags for the Python door: a rotation
that is not orthonormal to :data:`~toolkit.ik.targets.ORTHONORMAL` (projected there, then
solved again), a row that misses ``tol`` by rounding only (polished there), an entry that
is not a pose (refused there with the reason).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ...kinematics import inline_kernel, kernel, poses, twin_kernel
from ..checks import check_pose, pose_errors
from ..targets import ORTHONORMAL
from .branch_kernels import EDGE, TWO_PI, distinct_rows, wrap
from .family import COMPILED

__all__ = [
    "FIRST_POSITION",
    "MANY",
    "MOVE",
    "NOT_POSE",
    "ROUGH",
    "ROUGH_ROWS",
    "WIDE",
    "code_roots",
    "flag_columns",
    "label_code",
    "nearest_turn",
    "nearest_turn_rows",
    "pack",
    "pose_flag",
    "reversed_target",
    "split",
    "target_rows",
    "unpack",
    "verified_rows",
]

ROUGH = 1e-6
"""[m, rad] A branch of an exact arm that misses ``tol`` by no more than this (rounding at a
singular pose or a tangent) is polished on the real model instead of dropped."""

FIRST_POSITION = min(i for i, family in enumerate(COMPILED) if family.places_point)
"""The compiled families' index (:data:`toolkit.ik.analytic.family.COMPILED`) from which on
they place a point (:mod:`toolkit.ik.analytic.position_kernels`, in its order)."""

MOVE, ROUGH_ROWS, NOT_POSE, MANY = 1, 2, 4, 8
"""The flags of a target: its rotation must be projected first; a row of it missed ``tol``
by rounding only; it is not a pose (NaN, not a rotation within 1e-6, last row); it has
more branches than the door's rows (left to the family's Python form)."""


@inline_kernel
def nearest_turn(a, lo, hi, rest):
    """The angle a + 2 pi k within [lo, hi] (inclusive to :data:`EDGE`) nearest ``rest``; a
    wrapped to [-pi, pi) where none fits or a limit is infinite."""
    x = wrap(a)
    if lo - EDGE <= x <= hi + EDGE and abs(rest - x) < 3.0:  # k = 0 below, found at once
        return x
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
def _turned_back(count, out, free, turned, bits):
    """Rows of the reversed chain (solved at T^-1) as the chain's: q_i = -q'_{n+1-i}, the
    free bits reversed, into ``turned`` and ``bits``."""
    n = turned.shape[1]
    for b in range(count):
        flags = 0
        for j in range(n):
            turned[b, j] = -out[b, n - 1 - j]
            if free[b] & (1 << (n - 1 - j)):
                flags |= 1 << j
        bits[b] = flags


@inline_kernel
def pose_flag(T):
    """0 for a pose the family can solve; :data:`NOT_POSE` (NaN, not a rotation within 1e-6,
    last row) or :data:`MOVE` (a rotation to project to
    :data:`~toolkit.ik.targets.ORTHONORMAL` first)."""
    if check_pose(T) != 0:
        return NOT_POSE
    off = 0.0
    for a in range(3):
        for b in range(3):
            d = T[0, a] * T[0, b] + T[1, a] * T[1, b] + T[2, a] * T[2, b]
            off = max(off, abs(d - (1.0 if a == b else 0.0)))
    return MOVE if off > ORTHONORMAL else 0


@inline_kernel
def reversed_target(T, pref, Ti, back):
    """T^-1 (R^T, -R^T p) into ``Ti`` and the reversed chain's angles (-pref reversed) into
    ``back``: what a family found from the frame's end solves."""
    for a in range(3):
        s = 0.0
        for b in range(3):
            Ti[a, b] = T[b, a]
            s -= T[b, a] * T[b, 3]
        Ti[a, 3] = s
        Ti[3, a] = 0.0
    Ti[3, 3] = 1.0
    n = pref.shape[0]
    for c in range(n):
        back[c] = -pref[n - 1 - c]


@inline_kernel
def target_rows(arm, setup, T, rest, pref, raw, P, work):  # long: one target's rows
    """One target's rows into ``P`` (B + 1, nq + :data:`WIDE`) from its raw branches ``raw``
    (angles (B, n), roots (B, 3), count, free bits (B,); of the reversed chain where
    ``setup``'s reversed is set): see :func:`toolkit.ik.analytic.batch_kernels.door_of`."""
    layout, fk = arm
    family, rev, near, tol, first, later = setup
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    turned, bits, W, H = work
    out, rts, found, fr = raw
    head = P.shape[0] - 1  # the target's row of count, flags and nearest verified row
    if rev:
        _turned_back(found, out, fr, turned, bits)
        out, fr = turned, bits
    n = qcol.shape[0]
    nq = rest.shape[0]
    keep = distinct_rows(out[:found], sliding)
    k, loose = 0, 0
    for b in range(found):
        if not keep[b]:
            continue
        q = P[k, :nq]
        q[:] = rest
        far = 0.0
        for c in range(n):
            a = out[b, c]
            if not sliding[c]:
                a = wrap(a)
                if not near:
                    a = nearest_turn(a, lo[c], hi[c], pref[c])
            far += abs(a - pref[c])
            if circle[c]:
                q[qcol[c]], q[qcol[c] + 1] = math.cos(a), math.sin(a)
            else:
                q[qcol[c]] = a
        P[k, nq + 2] = far
        within = True
        for m in range(nq):
            if not (qlo[m] <= q[m] <= qhi[m]):
                within = False
        P[k, nq + 7] = 1.0 if within else 0.0
        for j in range(3):
            P[k, nq + 3 + j] = rts[b, j]
        P[k, nq + 6] = fr[b]
        loose |= fr[b]
        P[k, nq + 9] = 400 * rts[b, 0] + 20 * rts[b, 1] + rts[b, 2] + 421  # label_code
        k += 1
    P[head, 0], P[head, 3] = k, loose
    best = -1
    kind = (near, family >= FIRST_POSITION)
    if later:  # every row verified after, many targets' at once (verified_rows)
        P[head, 2] = -1
        return
    for t in range(k):  # every row in order; or (first) the nearest within until one verifies
        r = t
        if first:
            r, nearest = -1, math.inf
            for m in range(k):
                if math.isnan(P[m, nq]) and P[m, nq + 2] < nearest and P[m, nq + 7] != 0.0:
                    r, nearest = m, P[m, nq + 2]
            if r < 0:
                break
        ok = _verify(P[r], nq, T, fk, (H, W), tol, kind)
        if ok == 2:
            P[head, 1] = ROUGH_ROWS
        elif ok == 1 and (best < 0 or P[r, nq + 2] < P[best, nq + 2]):
            best = r  # the verified row nearest pref (first: the first verified)
            if first:
                break
    P[head, 2] = best
    if best >= 0:
        P[head, 4], P[head, 5] = P[best, nq], P[best, nq + 1]


@inline_kernel
def _verify(row, nq, T, fk, scratch, tol, kind):
    """Row's errors by the kinematics kernels' forward kinematics against T into it (a
    family placing a point: the position's alone, the orientation's 0): 1 if it is
    verified to ``tol`` and within the limits, 2 if it misses by rounding only
    (:data:`ROUGH`; an exact arm), else 0. ``kind``: (near, places a point)."""
    ints, flts, tip_pl = fk
    H, W = scratch
    poses.chain_pose(row[:nq], ints, flts, tip_pl, W, H)
    return _judged(row, nq, H, T, tol, kind)


@inline_kernel
def _judged(row, nq, H, T, tol, kind):
    """:func:`_verify`'s verdict on the row's pose H (4, 4), its errors written into it."""
    near, point = kind
    pos, rot = pose_errors(H, T)
    if point:
        rot = 0.0
    row[nq], row[nq + 1] = pos, rot
    reached = pos <= tol and rot <= tol
    if reached and row[nq + 7] != 0.0:
        row[nq + 8] = 1.0
        return 1
    if not reached and not near and pos <= ROUGH and rot <= ROUGH:
        return 2
    return 0


@twin_kernel
def verified_rows(P, Ts, ints, flts, tip_pl, tol, near, point):
    """The rows the door kernel left for later (from
    :data:`~toolkit.ik.analytic.batch_kernels.LATER` targets on) verified as :func:`_verify`
    does, 64 targets' rows at a time, their poses by
    :func:`~toolkit.kinematics.poses.chain_poses` (vectorized over the rows): each row's
    errors and verified flag, the targets' rough flag, nearest verified row and its errors
    into P. ``ints``, ``flts``, ``tip_pl``: the kinematics chain; ``near``, ``point`` as
    the door's (an arm only near its family, a family placing a point). One kernel for
    every family (inside each door kernel it doubled their compile time)."""
    N, B, nq = P.shape[0], P.shape[1] - 1, P.shape[2] - WIDE
    chunk = 64
    for c in prange((N + chunk - 1) // chunk):
        R = chunk * B
        Qc, X, S = np.empty((R, nq)), np.empty((12, R)), np.empty((2, R))
        H, at = np.zeros((4, 4)), np.empty((R, 2), np.int64)
        start, stop = c * chunk, min(N, (c + 1) * chunk)
        m = 0
        for i in range(start, stop):
            for r in range(int(P[i, B, 0])):
                Qc[m, :] = P[i, r, :nq]
                at[m, 0], at[m, 1] = i, r
                m += 1
        poses.chain_poses(Qc, m, ints, flts, tip_pl, X, S)
        H[3, 3] = 1.0
        for j in range(m):
            i, r = at[j, 0], at[j, 1]
            for a in range(3):
                H[a, 0], H[a, 1], H[a, 2] = X[3 * a, j], X[3 * a + 1, j], X[3 * a + 2, j]
                H[a, 3] = X[9 + a, j]
            ok = _judged(P[i, r], nq, H, Ts[i], tol, (near, point))
            if ok == 2:
                P[i, B, 1] = ROUGH_ROWS
            elif ok == 1:
                best = int(P[i, B, 2])
                if best < 0 or P[i, r, nq + 2] < P[i, best, nq + 2]:
                    P[i, B, 2] = r
        for i in range(start, stop):
            best = int(P[i, B, 2])
            if best >= 0:
                P[i, B, 4], P[i, B, 5] = P[i, best, nq], P[i, best, nq + 1]
    return P


@inline_kernel
def unpack(F, J):
    """The arm of the door kernel out of its two packed arrays (:func:`pack`): ((axes,
    points, tip rotation, tip position), (per chain joint its place in q, (cos, sin) pair
    or not, limits; the limits of q; per chain joint prismatic or not), (the kinematics
    kernels' chain: ints, floats, tip), (family, reversed, the most branches))."""
    n, nq, m, cols, tips = J[0], J[1], J[2], J[3], J[4]
    a = 0
    h = F[a : a + 3 * n].reshape((n, 3))
    a += 3 * n
    o = F[a : a + 3 * n].reshape((n, 3))
    a += 3 * n
    tip_R = F[a : a + 9].reshape((3, 3))
    tip_p = F[a + 9 : a + 12]
    a += 12
    lo, hi = F[a : a + n], F[a + n : a + 2 * n]
    a += 2 * n
    qlo, qhi = F[a : a + nq], F[a + nq : a + 2 * nq]
    a += 2 * nq
    flts = F[a : a + m * cols].reshape((m, cols))
    tip_pl = F[a + m * cols : a + m * cols + tips]
    qcol, circle = J[HEAD : HEAD + n], J[HEAD + n : HEAD + 2 * n]
    sliding = J[HEAD + 2 * n : HEAD + 3 * n] != 0
    ints = J[HEAD + 3 * n : HEAD + 3 * n + 6 * m].reshape((m, 6))
    return ((h, o, tip_R, tip_p), (qcol, circle, lo, hi, qlo, qhi, sliding),
            (ints, flts, tip_pl), (J[5], J[6] != 0, J[7]))  # fmt: skip


HEAD = 8
"""The ints of :func:`pack` before its columns: n, nq, the kinematics chain's rows, its
floats' columns, the tip's length, the family's index, reversed, the most branches."""


def pack(
    geometry: tuple[np.ndarray, ...], layout: tuple[np.ndarray, ...], fk: tuple[np.ndarray, ...],
    family: int, reversed_: bool, most: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """An arm for the door kernel in two arrays (floats, ints): a compiled call takes arrays
    faster than tuples of them. ``geometry`` (axes, points, tip rotation and position of
    the chain solved), ``layout`` (per chain joint its place in q, (cos, sin) pair or not,
    lower and upper limits; then q's lower and upper limits; per chain joint prismatic or
    not), ``fk`` (the kinematics kernels' chain: ints (m, 6), floats (m, c), tip),
    ``family`` (:attr:`~toolkit.ik.analytic.family.Family.kernel_index`), ``reversed_``,
    ``most`` (the rows of branches a target may have)."""
    h, o, tip_R, tip_p = geometry
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    ints, flts, tip_pl = fk
    F = np.concatenate([np.ravel(a) for a in (h, o, tip_R, tip_p, lo, hi, qlo, qhi, flts, tip_pl)])
    head = [
        len(qcol),
        len(qlo),
        len(ints),
        flts.shape[1],
        len(tip_pl),
        family,
        int(reversed_),
        most,
    ]
    J = np.concatenate([head, qcol, np.asarray(circle, np.int64), np.asarray(sliding, np.int64),
                        np.ravel(ints)])  # fmt: skip
    return np.ascontiguousarray(F, dtype=float), np.ascontiguousarray(J, dtype=np.int64)


WIDE = 10
"""The columns of a row of the door kernel's array past its nq joint values: position and
orientation errors, the distance to ``pref``, the three roots, the free bits, within the
limits, verified (and within), the roots as one number (:func:`label_code`)."""


def label_code(roots: tuple[int, int, int]) -> int:
    """The number the door kernel writes for a branch's roots (each -1 to 18: a root's
    index, -1 where its subproblem had one); :func:`code_roots` reads it back."""
    a, b, c = roots
    return 400 * (a + 1) + 20 * (b + 1) + (c + 1)


def code_roots(code: float) -> tuple[int, int, int]:
    """The roots of a :func:`label_code`."""
    k = int(code)
    return k // 400 - 1, k // 20 % 20 - 1, k % 20 - 1


def split(P: np.ndarray, spread: bool = False) -> tuple[np.ndarray, ...]:
    """The door kernel's array as (Q (N, B, nq), E (N, B, 3), K (N, B, 4) roots and free
    bits, S (N, B, 2) within and verified, C (N, 2) count and flags), B its rows of
    branches (8; 16 for the search): Q and E views of P, the others read in one compiled
    pass (:func:`flag_columns`; numpy's casts of P's strided columns took 6 ms for 20,000
    targets; over the cores where ``spread``)."""
    nq = P.shape[2] - WIDE
    rows = P[:, :-1]
    K, S, C = flag_columns(spread, P, nq)
    return rows[..., :nq], rows[..., nq : nq + 3], K, S, C


@twin_kernel
def flag_columns(P, nq):
    """(K, S, C) of :func:`split` from the door's array P: its roots and free bits as
    integers, within and verified as booleans, each target's count and flags as integers
    (the kernel writes whole numbers there: -1, 0 or 1 for roots)."""
    N, B = P.shape[0], P.shape[1] - 1
    K = np.empty((N, B, 4), np.int64)
    S = np.empty((N, B, 2), np.bool_)
    C = np.empty((N, 2), np.int64)
    for i in prange(N):
        for j in range(B):
            for c in range(4):
                K[i, j, c] = np.int64(P[i, j, nq + 3 + c])
            S[i, j, 0] = P[i, j, nq + 7] != 0.0
            S[i, j, 1] = P[i, j, nq + 8] != 0.0
        C[i, 0], C[i, 1] = np.int64(P[i, B, 0]), np.int64(P[i, B, 1])
    return K, S, C
