"""Every verified branch of N targets in one compiled call: the door of ``Robot.ik_all`` (one
target: a batch of one) and ``Robot.ik_all_batch`` on the compiled families.

Per target, :func:`branch_rows` checks the pose, takes the branches the family's batch kernel
found (on the reversed chain at T^-1 where the family was found from the frame's end; run
first by :meth:`toolkit.ik.analytic.door.BranchDoor.call`), drops branches equal up to
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

__all__ = [
    "FIRST_POSITION",
    "MANY",
    "MOVE",
    "NOT_POSE",
    "ROUGH",
    "ROUGH_ROWS",
    "WIDE",
    "branch_rows",
    "code_roots",
    "label_code",
    "nearest_turn",
    "nearest_turn_rows",
    "pack",
    "split",
]

ROUGH = 1e-6
"""[m, rad] A branch of an exact arm that misses ``tol`` by no more than this (rounding at a
singular pose or a tangent) is polished on the real model instead of dropped."""

FIRST_POSITION = 5
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
def _target_rows(i, arm, setup, Ts, rest, pref, P, work):  # long: one target's rows
    """Target i's rows into ``P``: see :func:`branch_rows`."""
    layout, fk, raw = arm
    family, rev, near, tol, first = setup
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    turned, bits, W, H = work
    head = P.shape[1] - 1  # the target's row of count, flags and nearest verified row
    T = Ts[i]
    if check_pose(T) != 0:
        P[i, head, 1] = NOT_POSE
        return
    off = 0.0
    for a in range(3):
        for b in range(3):
            d = T[0, a] * T[0, b] + T[1, a] * T[1, b] + T[2, a] * T[2, b]
            off = max(off, abs(d - (1.0 if a == b else 0.0)))
    if off > ORTHONORMAL:
        P[i, head, 1] = MOVE
        return
    found = raw[2][i]
    if found < 0:
        P[i, head, 1] = MANY
        return
    out, rts, fr = raw[0][i], raw[1][i], raw[3][i]
    if rev:
        _turned_back(found, out, fr, turned, bits)
        out, fr = turned, bits
    n = qcol.shape[0]
    nq = rest.shape[0]
    keep = distinct_rows(out[:found], sliding)
    k = 0
    for b in range(found):
        if not keep[b]:
            continue
        q = P[i, k, :nq]
        q[:] = rest
        far = 0.0
        for c in range(n):
            a = out[b, c]
            if not sliding[c]:
                a = (a + math.pi) % TWO_PI - math.pi
                if not near:
                    a = nearest_turn(a, lo[c], hi[c], pref[c])
            far += abs(a - pref[c])
            if circle[c]:
                q[qcol[c]], q[qcol[c] + 1] = math.cos(a), math.sin(a)
            else:
                q[qcol[c]] = a
        P[i, k, nq + 2] = far
        within = True
        for m in range(nq):
            if not (qlo[m] <= q[m] <= qhi[m]):
                within = False
        P[i, k, nq + 7] = 1.0 if within else 0.0
        for j in range(3):
            P[i, k, nq + 3 + j] = rts[b, j]
        P[i, k, nq + 6] = fr[b]
        P[i, k, nq + 9] = 400 * rts[b, 0] + 20 * rts[b, 1] + rts[b, 2] + 421  # label_code
        k += 1
    P[i, head, 0] = k
    best = -1
    for _ in range(k):  # verify every row, or (first) the nearest until one is verified
        r, nearest = -1, math.inf
        for m in range(k):
            if math.isnan(P[i, m, nq]) and P[i, m, nq + 2] < nearest and (
                    not first or P[i, m, nq + 7] != 0.0):  # fmt: skip
                r, nearest = m, P[i, m, nq + 2]
        if r < 0:
            break
        ok = _verify(P[i, r], nq, T, fk, (H, W), tol, (near, family >= FIRST_POSITION))
        if ok == 2:
            P[i, head, 1] = ROUGH_ROWS
        elif ok == 1:
            if best < 0:
                best = r
            if first:
                break
    P[i, head, 2] = best


@inline_kernel
def _verify(row, nq, T, fk, scratch, tol, kind):
    """Row's errors by the kinematics kernels' forward kinematics against T into it (a
    family placing a point: the position's alone, the orientation's 0): 1 if it is
    verified to ``tol`` and within the limits, 2 if it misses by rounding only
    (:data:`ROUGH`; an exact arm), else 0. ``kind``: (near, places a point)."""
    ints, flts, tip_pl = fk
    H, W = scratch
    near, point = kind
    kernels.frames(row[:nq], ints, flts, W)
    kernels.tip(W, tip_pl, H[:3, :3], H[:3, 3])
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


@inline_kernel
def unpack(F, J):
    """The arm of :func:`branch_rows` out of its two packed arrays (:func:`pack`): ((axes,
    points, tip rotation, tip position), (per chain joint its place in q, (cos, sin) pair
    or not, limits; the limits of q; per chain joint prismatic or not), (the kinematics
    kernels' chain: ints, floats, tip), (family, reversed))."""
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
            (ints, flts, tip_pl), (J[5], J[6] != 0))  # fmt: skip


HEAD = 7
"""The ints of :func:`pack` before its columns: n, nq, the kinematics chain's rows, its
floats' columns, the tip's length, the family's index, reversed."""


def pack(
    geometry: tuple[np.ndarray, ...], layout: tuple[np.ndarray, ...], fk: tuple[np.ndarray, ...],
    family: int, reversed_: bool,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """An arm for :func:`branch_rows` in two arrays (floats, ints): a compiled call takes
    arrays faster than tuples of them. ``geometry`` (axes, points, tip rotation and
    position of the chain solved), ``layout`` (per chain joint its place in q, (cos, sin)
    pair or not, lower and upper limits; then q's lower and upper limits; per chain joint
    prismatic or not), ``fk`` (the kinematics kernels' chain: ints (m, 6), floats (m, c),
    tip)."""
    h, o, tip_R, tip_p = geometry
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    ints, flts, tip_pl = fk
    F = np.concatenate([np.ravel(a) for a in (h, o, tip_R, tip_p, lo, hi, qlo, qhi, flts, tip_pl)])
    head = [len(qcol), len(qlo), len(ints), flts.shape[1], len(tip_pl), family, int(reversed_)]
    J = np.concatenate([head, qcol, np.asarray(circle, np.int64), np.asarray(sliding, np.int64),
                        np.ravel(ints)])  # fmt: skip
    return np.ascontiguousarray(F, dtype=float), np.ascontiguousarray(J, dtype=np.int64)


WIDE = 10
"""The columns of a row of :func:`branch_rows` past its nq joint values: position and
orientation errors, the distance to ``pref``, the three roots, the free bits, within the
limits, verified (and within), the roots as one number (:func:`label_code`)."""


@twin_kernel
def branch_rows(F, J, near, tol, first, Ts, rest, pref, out, roots, counts, free):
    """Every branch of targets Ts (N, 4, 4), verified, in one array P (N, B + 1, nq + 10)
    (one boxed result: a call returning five arrays took 3 us more), from the family's
    raw branches (its batch kernel's ``out`` (N, B, n) angles, ``roots`` (N, B, 3),
    ``counts`` (N,), -1 where it has more than B, and ``free`` (N, B) bits; of the
    reversed chain at T^-1 where the family was found from the frame's end). Rows 0 to
    B - 1 are branches: q (nq), position [m] and orientation [rad] errors, the sum of the
    chain's |angle - pref| [rad], the roots (shoulder, elbow, wrist: 0, 1 or -1), the free
    bits, within the limits (1 or 0), verified to ``tol`` and within (1 or 0), the roots as
    one number (:func:`label_code`); NaN past each target's count, its roots -1 and the
    rest 0. Row B holds the target's count of branches, its flags (:data:`MOVE`,
    :data:`ROUGH_ROWS`, :data:`NOT_POSE`, :data:`MANY`) and the verified row nearest
    ``pref`` (the least sum of |angle - pref|, the first of equals; -1 where none is).
    :func:`split` reads P as five arrays. No family is compiled into it: each family's
    batch kernel is compiled when the family is first used.

    ``F``, ``J``: the arm (:func:`pack`); ``near``: the arm is only near its family (rows
    wrapped, to be polished; none flagged rough); ``first``: verify the rows within the
    limits nearest ``pref`` first and stop at the first verified (the others keep NaN
    errors: what ``Robot.ik`` needs); ``rest`` (1 or N, nq): the other
    joints' values, one for all targets or one each; ``pref`` (1 or N, n): the chain's
    angles in it."""
    N = Ts.shape[0]
    n = pref.shape[1]
    nq = rest.shape[1]
    per = rest.shape[0] > 1  # one rest per target, else one for all
    B = out.shape[1]  # the branches' rows; row B: the target's
    P = np.full((N, B + 1, nq + WIDE), np.nan)
    # a parallel loop takes arrays, not tuples of them: unpacked here, packed in each chunk
    _, layout, (ints, flts, tip_pl), fr = unpack(F, J)
    qcol, circle, lo, hi, qlo, qhi, sliding = layout
    family, rev = fr
    chunk = 64
    for c in prange((N + chunk - 1) // chunk):
        work = (np.zeros((B, n)), np.zeros(B, np.int64), np.empty((ints.shape[0] + 1, 15)),
                np.zeros((4, 4)))  # fmt: skip
        arm = ((qcol, circle, lo, hi, qlo, qhi, sliding), (ints, flts, tip_pl),
               (out, roots, counts, free))  # fmt: skip
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            r = i if per else 0
            P[i, :, nq + 3 :] = 0.0
            P[i, :B, nq + 3 : nq + 6] = -1.0
            P[i, B, :] = 0.0
            P[i, B, 2] = -1.0
            _target_rows(i, arm, (family, rev, near, tol, first), Ts, rest[r], pref[r], P,
                         work)  # fmt: skip
    return P


def label_code(roots: tuple[int, int, int]) -> int:
    """The number :func:`branch_rows` writes for a branch's roots (each -1 to 18: a root's
    index, -1 where its subproblem had one); :func:`code_roots` reads it back."""
    a, b, c = roots
    return 400 * (a + 1) + 20 * (b + 1) + (c + 1)


def code_roots(code: float) -> tuple[int, int, int]:
    """The roots of a :func:`label_code`."""
    k = int(code)
    return k // 400 - 1, k // 20 % 20 - 1, k % 20 - 1


def split(P: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`branch_rows`'s array as (Q (N, B, nq), E (N, B, 3), K (N, B, 4) roots and free
    bits, S (N, B, 2) within and verified, C (N, 2) count and flags), B its rows of
    branches (8; 16 for the search)."""
    nq = P.shape[2] - WIDE
    rows = P[:, :-1]
    return (rows[..., :nq], rows[..., nq:nq + 3], rows[..., nq + 3:nq + 7].astype(np.int64),
            rows[..., nq + 7:nq + 9] != 0.0, P[:, -1, :2].astype(np.int64))  # fmt: skip
