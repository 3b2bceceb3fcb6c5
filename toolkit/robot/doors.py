"""The fast door of ``Robot.ik_all`` (an exact compiled family: one compiled call through
:class:`toolkit.ik.BranchDoor`) and the expansion of one row per branch into every turn."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..ik import BranchDoor, branches, door_kernels, nearest_rotations
from ..ik import structure as arm
from ..kinematics import parallel

__all__ = ["door_answer", "every_turn", "nearest_branches", "rest_pref"]

_REGULAR = tuple(((),) * k for k in range(9))


def _free_names(bits: list[int], names: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    """Per row, the names of the joints its free bits name (() for a regular row)."""
    if not any(bits) and len(bits) < len(_REGULAR):
        return _REGULAR[len(bits)]
    return tuple(branches.free_joints(b, names) if b else () for b in bits)


def rest_pref(
    robot: Any, chain: arm.Chain, q_rest: ArrayLike | None, locked: tuple[tuple[int, float], ...]
) -> tuple[np.ndarray, np.ndarray]:
    """(the rest configuration ``Robot._rest`` gives, its chain joints' angles): what a door
    call takes."""
    rest = robot._rest(q_rest, locked)
    pref = robot.joints.angles(rest, robot.name)[list(chain.columns)]  # rest is checked
    return rest, np.ascontiguousarray(pref)


def door_answer(
    robot: Any, door: BranchDoor, pose: np.ndarray, tol: float, q_rest: ArrayLike | None,
    locked: tuple[tuple[int, float], ...], turns: bool,
) -> branches.IKAllResult | None:  # fmt: skip
    """``Robot.ik_all`` of an exact compiled family through its door; None where the
    general path must answer (a row to polish, an entry that is not a pose)."""
    rest, pref = (door.mid, door.mid_pref) if q_rest is None else rest_pref(
        robot, door.chain, q_rest, locked)  # fmt: skip
    Ts = pose.reshape(1, 4, 4) if pose.flags.c_contiguous else np.ascontiguousarray(pose)[None]
    Q, E, K, S, C = door.rows(Ts, tol, rest, pref)
    moved = 0.0
    if C[0, 1] == door_kernels.MOVE:  # float32 or rounded: solved at the nearest rotation
        Ts, shift = nearest_rotations(Ts)
        Q, E, K, S, C = door.rows(Ts, tol, rest, pref)
        moved = float(shift[0])
    k, flags = C[0].tolist()
    if flags:
        return None
    names = door.chain.names
    result = branches.IKAllResult(
        q=Q[0, :k],
        success=S[0, :k, 1],
        within_limits=S[0, :k, 0],
        labels=door.labels(K[0, :k, :3]),
        position_error=E[0, :k, 0],
        orientation_error=E[0, :k, 1],
        structure=door.found,
        polished=False,
        lost=0,
        branch=np.arange(k, dtype=np.int64),
        free=_free_names(K[0, :k, 3].tolist(), names),
        target_moved=moved,
    )
    return every_turn(robot, result, door.chain, tol) if turns else result


def every_turn(
    robot: Any, r: branches.IKAllResult, chain: arm.Chain, tol: float
) -> branches.IKAllResult:
    """``r`` (one row per branch) with every turn of each branch within the limits (one
    row, wrapped to [-pi, pi), where none fits), rows of a branch sharing ``branch``."""
    lo, hi, one, at = robot._chain_layout(chain)
    cols = list(chain.columns)
    chosen, owner = branches.turns_many(robot.angles(r.q)[:, cols], lo, hi, chain.sliding)
    Q = r.q[owner]  # each turn in the coordinate of its joint (a (cos, sin) pair has none)
    Q[:, at] = chosen[:, one]
    inside = np.asarray(robot.ik_state.valid_rows(Q), dtype=bool).reshape(-1)
    reached = (r.position_error <= tol) & (r.orientation_error <= tol)
    rows = owner.tolist()
    return r._replace(
        q=Q, success=reached[owner] & inside, within_limits=inside,
        labels=[r.labels[i] for i in rows], position_error=r.position_error[owner],
        orientation_error=r.orientation_error[owner], branch=r.branch[owner],
        free=tuple(r.free[i] for i in rows),
    )  # fmt: skip


def nearest_branches(
    robot: Any, door: BranchDoor, poses: np.ndarray, Q0: np.ndarray, tol: float,
    checker: Any = None,
) -> tuple[np.ndarray, ...]:  # fmt: skip
    """``Robot.ik_batch(..., method="analytic")`` through the door: per target (N, 4, 4) the
    verified branch nearest its start (Q0 (N, nq); each branch at its turns nearest it),
    collision-free with a ``checker``: (q (N, nq), found (N,), position and orientation
    errors (N,)); a target without one (none verified, or one the door hands back: a
    rotation to project, a row to polish) is not found, for the numeric solver."""
    cols = list(door.chain.columns)
    pref = np.ascontiguousarray(robot.joints.angles(Q0, robot.name)[:, cols])
    Q, E, _, S, C = door.rows(np.ascontiguousarray(poses, dtype=float), tol,
                              np.ascontiguousarray(Q0, dtype=float), pref,
                              spread=parallel(8 * len(poses)))  # fmt: skip
    ok = S[..., 1] & (C[:, 1] == 0)[:, None]
    if checker is not None and ok.any():
        hits = np.asarray(checker.in_collision_many(Q[ok]), dtype=bool)
        ok[ok] = ~hits
    far = np.where(ok, E[..., 2], np.inf)
    best = np.argmin(far, axis=1)
    rows = np.arange(len(poses))
    found = ok[rows, best]
    q = np.where(found[:, None], Q[rows, best], Q0)
    return q, found, E[rows, best, 0], E[rows, best, 1]
