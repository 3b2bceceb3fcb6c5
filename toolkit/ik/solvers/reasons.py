"""Why ``Robot.ik_all`` found no row that succeeds: a sentence for
:attr:`toolkit.ik.IKAllResult.reason`, computed only when nothing succeeded (never on the
fast path of a target that has a branch)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analytic import branches
from ..numeric import IKOptions, PoseTask, solve_ik

__all__ = ["why_none"]

PROBE = IKOptions(restarts=20, max_iter=100, seed=0)  # the numeric probe of an empty answer


def why_none(
    analytic: Any, frame: str | None, target: object, answer: branches.IKAllResult, tol: float,
    locked: object,
) -> str:  # fmt: skip
    """The reason no row of ``answer`` succeeds: out of reach (with how far the numeric IK's
    nearest pose stays), an orientation the arm cannot hold, outside the joint limits, or a
    pose the subproblems miss that the numeric IK reaches."""
    if len(answer.q) == 0:
        return _empty(analytic, frame, target, answer, tol, locked)
    err = np.maximum(answer.position_error, answer.orientation_error)
    best = int(np.argmin(err))
    reached = err <= tol
    if reached.any():  # the pose is held, but never within the limits
        names = _outside(analytic, answer.q[reached])
        return (f"every branch that holds the target is outside the joint limits (of "
                f"{', '.join(names)}); the rows keep their values")  # fmt: skip
    pos, rot = answer.position_error[best], answer.orientation_error[best]
    text = (f"no branch holds the target to tol={tol:g}: the nearest (row {best}, "
            f"{answer.labels[best]}) misses it by {pos:.3g} m and {rot:.3g} rad")  # fmt: skip
    if pos <= tol and len(answer.structure.joints) < 6:
        joints = len(answer.structure.joints)
        text += f"; a {joints}-joint arm cannot hold every orientation: row {best} is the nearest"
    return text


def _empty(
    analytic: Any, frame: str | None, target: object, answer: branches.IKAllResult, tol: float,
    locked: object,
) -> str:  # fmt: skip
    if locked:
        return "no branch: the target is out of reach with the locked joints at their angles"
    task = PoseTask.from_target(analytic.frames.id(frame), target, None)
    probe = solve_ik(analytic.numeric.ik_loop, analytic.numeric.ik_state, task, None, PROBE)
    pos, rot = probe.position_error, probe.orientation_error
    if probe.success:
        family = answer.structure.family
        return (f"no branch, yet the numeric IK reaches the target (to {pos:.2g} m, {rot:.2g} "
                f"rad): a pose the {family} subproblems miss; use ik()")  # fmt: skip
    return (f"no branch: the target is out of reach; the nearest pose the numeric IK found "
            f"({PROBE.restarts} starts) is {pos:.3g} m and {rot:.3g} rad away")  # fmt: skip


def _outside(analytic: Any, Q: np.ndarray) -> list[str]:
    """The joints with a coordinate outside its limits in some row of ``Q`` (M, nq), as
    ``Robot.within_limits`` reads the limits (per coordinate of q)."""
    low, high = np.asarray(analytic.joints.lower), np.asarray(analytic.joints.upper)
    out = np.asarray(((Q < low - 1e-12) | (Q > high + 1e-12)).any(axis=0), dtype=bool)
    model = analytic.model
    joints = [model.joints[j] for j in range(1, model.njoints)]
    return [model.names[j] for j, joint in enumerate(joints, start=1)
            if out[joint.idx_q : joint.idx_q + joint.nq].any()]  # fmt: skip
