"""The fast door of ``Robot.ik_all`` (an exact compiled family: one compiled call through
:class:`toolkit.ik.BranchDoor`) and the expansion of one row per branch into every turn."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...kinematics import parallel
from ..analytic import BranchDoor, branches, door_kernels
from ..analytic import structure as arm
from ..numeric import IKResult
from ..targets import nearest_rotations

__all__ = [
    "door_answer",
    "door_pose",
    "every_turn",
    "keep_template",
    "nearest_branches",
    "nearest_verified",
    "relocked",
]

_F64 = np.dtype(np.float64)  # compared as a dtype: cheaper than with np.float64
_REGULAR = tuple(((),) * k for k in range(17))
_BRANCH = tuple(np.arange(k, dtype=np.int64) for k in range(17))
for _b in _BRANCH:  # shared by every answer: read-only
    _b.flags.writeable = False


def _free_names(bits: list[float], names: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    """Per row, the names of the joints its free bits name (() for a regular row)."""
    return tuple(branches.free_joints(int(b), names) if b else () for b in bits)


def _tail(fid: int, lock: tuple[tuple[int, float], ...]) -> object | None:
    """The template key of ``lock`` on ``fid``'s chain: ("tail", fid, its joints), or None
    where it is empty."""
    return ("tail", fid, tuple(j for j, _ in lock)) if lock else None


def keep_template(
    analytic: Any, fid: int, lock: tuple[tuple[int, float], ...],
    found: tuple[arm.Chain | None, arm.Structure],
) -> None:  # fmt: skip
    """Keep a structure found with ``lock`` as the template of that lock's other angles
    when every locked joint comes after every chain joint (their angles move the frame
    only, and a pose family's conditions, on the axes alone, hold at any of them; a
    family that places a point reads the frame's origin too, so it is found anew)."""
    chain, structure = found
    key = _tail(fid, lock)
    if key is None or chain is None or not structure or structure.places_point:
        return
    if min(j for j, _ in lock) > max(chain.joints):
        analytic.caches.keep(analytic.caches.structures, key, found)


def relocked(
    analytic: Any, fid: int, lock: tuple[tuple[int, float], ...]
) -> tuple[arm.Chain, arm.Structure] | None:
    """The structure of ``lock``'s joints at new angles from its template
    (:func:`keep_template`): the chain re-tipped at the frame's pose with the joints at
    those angles and every other joint at zero (:func:`toolkit.ik.analytic.chain.retipped`);
    None without a template."""
    key = _tail(fid, lock)
    template = None if key is None else analytic.caches.structures.get(key)
    if template is None:
        return None
    q = analytic.joints.q_from_angles(np.zeros(analytic.joints.nv))
    for j, angle in lock:
        joint = analytic.model.joints[j]
        if joint.nq == 2:
            q[joint.idx_q : joint.idx_q + 2] = (np.cos(angle), np.sin(angle))
        else:
            q[joint.idx_q] = angle
    tip = np.asarray(analytic.kinematics.fk(q[None], fid)[0])
    return arm.retipped(template[0], template[1], tip)


def door_pose(door: BranchDoor, target: object) -> np.ndarray | None:
    """The target as the door takes it, without a copy where it can: a C-contiguous float64
    pose (4, 4), or for a family placing a point a float64 position (3,) as a pose of no
    rotation; None for anything else (the general path checks it and says why)."""
    if type(target) is not np.ndarray or target.dtype != _F64:
        return None
    if target.shape == (4, 4):
        return None if door.places else np.ascontiguousarray(target)
    if target.shape == (3,) and door.places:
        pose = np.eye(4)
        pose[:3, 3] = target
        return pose
    return None


def door_answer(
    analytic: Any, door: BranchDoor, pose: np.ndarray, tol: float, q_rest: ArrayLike | None,
    locked: tuple[tuple[int, float], ...], turns: bool,
) -> branches.IKAllResult | None:  # fmt: skip
    """``Robot.ik_all`` of an exact compiled family through its door; None where the
    general path must answer (a row to polish, an entry that is not a pose)."""
    if q_rest is None:
        rest, pref = door.mid2, door.mid_pref2
    else:
        rest = analytic._rest(q_rest, locked)
        rest, pref = rest[None], door.pref_of(rest)[None]
    Ts = pose.reshape(1, 4, 4)  # C-contiguous (door_pose)
    floats, ints = door.packed
    P = door.serial(floats, ints, False, tol, False, False, Ts, rest, pref)[0]
    k, flags, _, loose = P[-1, :4].tolist()
    moved = 0.0
    if flags == door_kernels.MOVE:  # float32 or rounded: solved at the nearest rotation
        Ts, shift = nearest_rotations(Ts)
        P = door.call(Ts, tol, rest, pref)[0]
        moved = float(shift[0])
        k, flags, _, loose = P[-1, :4].tolist()
    if flags:
        return None
    k, nq = int(k), P.shape[1] - door_kernels.WIDE
    rows = P[:k]
    cols = rows.T  # a column of rows as a row of this view: the cheapest slice
    ok = cols[nq + 7 : nq + 9].astype(bool)  # within, verified: the kernel's 0.0 or 1.0
    free = _REGULAR[k] if not loose else _free_names(cols[nq + 6].tolist(), door.chain.names)
    result = branches.IKAllResult(  # positional: the fields' order
        rows[:, :nq], ok[1], ok[0], door.named(cols[nq + 9]), cols[nq], cols[nq + 1],
        door.found, False, 0, _BRANCH[k], free, moved,
    )  # fmt: skip
    return every_turn(analytic, result, door.chain, tol) if turns else result


def nearest_verified(
    analytic: Any, door: BranchDoor, pose: np.ndarray, q0: ArrayLike | None, tol: float,
    checker: Any = None,
) -> tuple[bool, IKResult | None]:  # fmt: skip
    """``Robot.ik`` of a pose (a C-contiguous float64 (4, 4)) through an exact compiled
    family's door, in one serial call: (answered, the verified branch nearest ``q0``
    (default: mid-range; each branch at its turns nearest it), collision-free with a
    ``checker``, ``iterations`` 0; None where none is). Without a checker the kernel
    verifies the nearest rows first and stops at the first verified. Not answered (False,
    None) where the door hands the target back: a rotation to project, an entry that is
    not a pose, a row to polish."""
    if q0 is None:
        rest, pref = door.mid2, door.mid_pref2
    else:  # checked as Robot._rest does (no joint locked here), the angles read directly
        rest = np.array(analytic.joints.check(q0), dtype=float)[None]
        pref = door.pref_of(rest[0])[None]
    floats, ints = door.packed
    P = door.serial(floats, ints, False, tol, checker is None, False, pose[None], rest, pref)
    # the target's row: count, flags, the nearest verified row (-1: none), free bits, its errors
    count, flags, best, _, pos, rot = P[0, -1, :6].tolist()
    if flags:
        return False, None
    nq = rest.shape[1]
    if checker is None:  # the kernel verified the nearest rows first, up to the first verified
        if best < 0:
            return True, None
        q = P[0, int(best), :nq].copy()  # not a view: a result keeps only its own q
        return True, IKResult(q, True, pos, rot, 0, 0, None, "analytic")
    P = P[0]
    for i in np.argsort(P[: int(count), nq + 2], kind="stable").tolist():  # nearest first
        row = P[i].tolist()
        if row[nq + 8] and checker.first_collision(P[i, :nq]) is None:
            return True, IKResult(P[i, :nq].copy(), True, row[nq], row[nq + 1], 0, 0, None,
                                  "analytic")  # fmt: skip
    return True, None


def every_turn(
    analytic: Any, r: branches.IKAllResult, chain: arm.Chain, tol: float
) -> branches.IKAllResult:
    """``r`` (one row per branch) with every turn of each branch within the limits (one
    row, wrapped to [-pi, pi), where none fits), rows of a branch sharing ``branch``."""
    lo, hi, one, at = analytic._chain_layout(chain)
    cols = list(chain.columns)
    chosen, owner = branches.turns_many(analytic.joints.angles(r.q)[:, cols], lo, hi, chain.sliding)
    Q = r.q[owner]  # each turn in the coordinate of its joint (a (cos, sin) pair has none)
    Q[:, at] = chosen[:, one]
    inside = np.asarray(analytic.numeric.ik_state.valid_rows(Q), dtype=bool).reshape(-1)
    reached = (r.position_error <= tol) & (r.orientation_error <= tol)
    rows = owner.tolist()
    return r._replace(
        q=Q, success=reached[owner] & inside, within_limits=inside,
        labels=[r.labels[i] for i in rows], position_error=r.position_error[owner],
        orientation_error=r.orientation_error[owner], branch=r.branch[owner],
        free=tuple(r.free[i] for i in rows),
    )  # fmt: skip


def nearest_branches(
    analytic: Any, door: BranchDoor, poses: np.ndarray, Q0: np.ndarray, tol: float,
    checker: Any = None,
) -> tuple[np.ndarray, ...]:  # fmt: skip
    """``Robot.ik_batch(..., method="analytic")`` through the door: per target (N, 4, 4) the
    verified branch nearest its start (Q0 (N, nq); each branch at its turns nearest it),
    collision-free with a ``checker``: (q (N, nq), found (N,), position and orientation
    errors (N,)); a target without one (none verified, or one the door hands back: a
    rotation to project, a row to polish) is not found, for the numeric solver."""
    cols = list(door.chain.columns)
    pref = np.ascontiguousarray(analytic.joints.raw_angles(Q0, analytic.name)[:, cols])
    Ts, Q0 = np.ascontiguousarray(poses, dtype=float), np.ascontiguousarray(Q0, dtype=float)
    spread = parallel(8 * len(poses))
    P = door.call(Ts, tol, Q0, pref, spread=spread, first=checker is None)
    Q, E, _, S, C = door_kernels.split(P, spread)
    rows = np.arange(len(poses))
    if checker is None:  # the kernel's nearest verified row
        best = P[:, -1, 2].astype(np.int64)
        found = (best >= 0) & (C[:, 1] == 0)
        best = np.maximum(best, 0)
    else:
        ok = S[..., 1] & (C[:, 1] == 0)[:, None]
        if ok.any():
            hits = np.asarray(checker.in_collision_many(Q[ok]), dtype=bool)
            ok[ok] = ~hits
        best = np.argmin(np.where(ok, E[..., 2], np.inf), axis=1)
        found = ok[rows, best]
    q = np.where(found[:, None], Q[rows, best], Q0)
    return q, found, E[rows, best, 0], E[rows, best, 1]
