"""Numeric inverse kinematics: damped least squares with adaptive damping, for any Robot.

The task (residual and its Jacobian) is built apart from the solver loop:

* residual ``e = [p_t - p ; log3(R^T R_t)]``: the position error in base-frame axes
  [m] and the orientation error as a rotation vector in the **tool frame's** axes [rad],
  so that masking ``rz`` frees the roll about the tool's own z axis (a 5-DOF arm);
* Jacobian ``J_e = [J_v ; R^T J_w]`` from Pinocchio's frame Jacobian
  (``LOCAL_WORLD_ALIGNED``); ``de/dq = -J_e`` to first order.

Each step solves ``(J_e^T W J_e + lambda I) dq = J_e^T W e`` with the
Levenberg-Marquardt damping ``lambda = E + lambda_min``, ``E = e^T W e / 2``
(Sugihara 2011): large far from the target, vanishing near it (Gauss-Newton, quadratic
convergence). Every step is clipped to the joint limits. A start that stalls is
restarted from a seeded random configuration; the answer is checked with an
independent forward-kinematics call before ``success`` is set.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from .errors import InvalidParameterError

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["IKResult", "PathResult", "parse_mask", "parse_target", "solve_ik", "solve_ik_path"]

_EYE3 = np.eye(3)
_LAMBDA_MIN = 1e-9
_DAMP = 0.05
_STALL = 4


class IKResult(NamedTuple):
    """Outcome of an IK solve.

    ``success`` is True only if ``q`` lies within the joint limits and its tool pose,
    recomputed independently, meets the tolerance on the axes the mask selects.
    ``position_error`` [m] and ``orientation_error`` [rad] are those residual norms
    (an axis the mask leaves out does not count; position-only solves report 0 rad).
    """

    q: np.ndarray
    success: bool
    position_error: float
    orientation_error: float
    iterations: int
    restarts: int


class PathResult(NamedTuple):
    """Outcome of a warm-started IK along a path of targets."""

    q: np.ndarray  # (N, nq)
    success: np.ndarray  # (N,) bool
    position_error: np.ndarray  # (N,)
    orientation_error: np.ndarray  # (N,)
    jumps: list[int]  # indices i where max |q[i] - q[i-1]| exceeded max_jump
    max_step: float  # the largest joint change between neighbours [rad or m]

    @property
    def all_succeeded(self) -> bool:
        return bool(np.all(self.success))


def parse_target(target: object) -> tuple[np.ndarray, np.ndarray, bool]:
    """(rotation, position, position_only) of a 4x4 pose or a 3-vector position."""
    try:
        arr = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"IK target must be numeric, got {target!r}") from None
    if arr.shape == (3,):
        if not np.all(np.isfinite(arr)):
            raise InvalidParameterError("IK target position has NaN or infinite entries")
        return np.eye(3), arr.copy(), True
    if arr.shape != (4, 4):
        raise InvalidParameterError(
            f"IK target must be a 4x4 pose or a 3-vector position, got shape {arr.shape}"
        )
    if not np.isfinite(arr).all():
        raise InvalidParameterError("IK target pose has NaN or infinite entries")
    R = arr[:3, :3]
    (a, b, c), (d, e, f), (g, h, i) = R.tolist()
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if np.abs(R.T @ R - _EYE3).max() > 1e-6 or det < 0:
        raise InvalidParameterError("IK target's 3x3 block is not a rotation matrix")
    if np.abs(arr[3] - [0, 0, 0, 1]).max() > 1e-12:
        raise InvalidParameterError("IK target's last row must be (0, 0, 0, 1)")
    return R.copy(), arr[:3, 3].copy(), False


def parse_mask(mask: Sequence[float] | np.ndarray | None, position_only: bool) -> np.ndarray:
    """The six weights (x, y, z, rx, ry, rz); default all ones, or position only."""
    if mask is None:
        return np.array([1.0, 1, 1, 0, 0, 0]) if position_only else np.ones(6)
    w = np.asarray(mask, dtype=float)
    if w.shape != (6,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InvalidParameterError(
            f"mask must be six non-negative weights (x, y, z, rx, ry, rz), got {mask!r}"
        )
    if not w.any():
        raise InvalidParameterError("mask selects no axis")
    if position_only and w[3:].any():
        raise InvalidParameterError(
            "a 3-vector target has no orientation: mask rx, ry, rz must be 0"
        )
    return w


def _masked_norms(e: np.ndarray, wl: list[float], use_rot: bool) -> tuple[float, float]:
    """Norms of the selected position and rotation components of a residual (plain floats)."""
    v = e.tolist()
    pos = math.sqrt(sum(v[i] * v[i] for i in range(3) if wl[i] > 0))
    rot = math.sqrt(sum(v[i] * v[i] for i in range(3, 6) if wl[i] > 0)) if use_rot else 0.0
    return pos, rot


try:  # eigenpy ships with Pinocchio; its Cholesky is ~3x faster than numpy's solve at 6x6
    from eigenpy import LLT as _LLT
except ImportError:  # pragma: no cover - pinocchio always brings eigenpy
    _LLT = None


def _spd_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve A x = b for a symmetric positive-definite A (the damped normal equations)."""
    if _LLT is not None:
        x = _LLT(A).solve(b)
        if np.isfinite(x).all():
            return x
    return np.linalg.solve(A, b)


class _State:
    """What every IK solve on one robot reuses: Pinocchio Data, bounds, identity."""

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.data = model.createData()  # the solver's own workspace
        self.verify_data = model.createData()  # a separate one for the independent check
        self.euclidean = model.nq == model.nv
        clip = np.zeros(model.nq, dtype=bool)
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.nq == joint.nv and joint.idx_q >= 0:
                clip[joint.idx_q : joint.idx_q + joint.nq] = True
        clip &= np.isfinite(robot.lower) & np.isfinite(robot.upper)
        # coordinates that are not clipped get infinite bounds: one np.clip call per step
        self.clip_lower = np.where(clip, robot.lower, -np.inf)
        self.clip_upper = np.where(clip, robot.upper, np.inf)
        self.sample_lower = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
        self.sample_upper = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
        self.limit_lower, self.limit_upper = robot.lower - 1e-12, robot.upper + 1e-12
        self.mid = _mid_range(robot)


def _state(robot: Robot) -> _State:
    state = robot.__dict__.get("_ik_state")
    if state is None or state.data is None:
        state = _State(robot)
        robot.__dict__["_ik_state"] = state
    return state


class _Task:
    """Residual and Jacobian of 'put frame fid on (R_t, p_t)' with weights w."""

    def __init__(self, robot: Robot, fid: int, R_t: np.ndarray, p_t: np.ndarray, w: np.ndarray):
        self.model, self.data, self.fid = robot.model, _state(robot).data, fid
        self.R_t, self.p_t, self.w = R_t, p_t, w
        self.use_rot = bool(w[3:].any())

    def residual(self, q: np.ndarray, with_jacobian: bool) -> tuple[np.ndarray, np.ndarray | None]:
        m, d = self.model, self.data
        if with_jacobian:
            pin.computeJointJacobians(m, d, q)
        else:
            pin.forwardKinematics(m, d, q)
        M = pin.updateFramePlacement(m, d, self.fid)
        R = M.rotation
        e = np.empty(6)
        e[:3] = self.p_t - M.translation
        e[3:] = pin.log3(R.T @ self.R_t) if self.use_rot else 0.0
        if not with_jacobian:
            return e, None
        J = pin.getFrameJacobian(m, d, self.fid, pin.LOCAL_WORLD_ALIGNED)
        if self.use_rot:
            J[3:] = R.T @ J[3:]
        return e, J


class _Solver:
    """The damped-least-squares loop on a task, with limit clipping.

    The loop is written for few Python-level operations per iteration (one Pinocchio
    call for kinematics and Jacobians, scalar arithmetic for the errors, one clip and one
    linear solve): about half the cost of composing the task's own methods.
    """

    def __init__(self, robot: Robot, task: _Task, tol: float, max_iter: int):
        self.robot, self.task, self.tol, self.max_iter = robot, task, tol, max_iter
        state = _state(robot)
        self.euclidean = state.euclidean
        self.lower, self.upper = state.clip_lower, state.clip_upper
        w = task.w
        self.wl = w.tolist()
        self.unit_w = all(k == 1.0 for k in self.wl)

    def _errors(self, e: np.ndarray) -> tuple[float, float]:
        return _masked_norms(e, self.wl, self.task.use_rot)

    def run(self, q: np.ndarray) -> tuple[np.ndarray, float, int, bool]:
        """Iterate from q; returns (best q, its weighted cost, iterations, converged)."""
        task = self.task
        model, data, fid = task.model, task.data, task.fid
        R_t, p_t, w, use_rot = task.R_t, task.p_t, task.w, task.use_rot
        lower, upper, tol = self.lower, self.upper, self.tol
        nv = model.nv
        # cost = e^T W e / 2 <= tol^2 whenever both norms are <= tol (weights <= 1 aside)
        tol2 = tol * tol * max(1.0, float(w.max()))
        log3, lwa = pin.log3, pin.LOCAL_WORLD_ALIGNED
        q = np.clip(q, lower, upper)
        best_q, best_cost, since_best = q, np.inf, 0
        e = np.zeros(6)
        for it in range(1, self.max_iter + 1):
            pin.computeJointJacobians(model, data, q)
            M = pin.updateFramePlacement(model, data, fid)
            R = M.rotation
            e[:3] = p_t - M.translation
            J = pin.getFrameJacobian(model, data, fid, lwa)
            if use_rot:
                e[3:] = log3(R.T @ R_t)
                J[3:] = R.T @ J[3:]
            cost = 0.5 * float(e @ e) if self.unit_w else 0.5 * float(e @ (w * e))
            if cost < best_cost * (1 - 1e-3):
                since_best = 0
            else:
                since_best += 1
            if cost < best_cost:
                best_q, best_cost = q, cost
            if cost <= tol2:  # necessary for both errors <= tol: only then compute them
                pos, rot = self._errors(e)
                if pos <= tol and rot <= tol:
                    return q, cost, it, True
            if since_best >= _STALL:  # stalled (local minimum, or the target is out of reach)
                return best_q, best_cost, it, False
            JtW = J.T if self.unit_w else J.T * w
            A = JtW @ J
            A.flat[:: nv + 1] += _DAMP * cost + _LAMBDA_MIN  # + lambda I
            dq = _spd_solve(A, JtW @ e)
            q = q + dq if self.euclidean else pin.integrate(model, q, dq)
            q = np.minimum(np.maximum(q, lower), upper)
        return best_q, best_cost, self.max_iter, False


def _mid_range(robot: Robot) -> np.ndarray:
    lo, hi = robot.lower, robot.upper
    finite = np.isfinite(lo) & np.isfinite(hi)
    q = robot.neutral()
    q[finite] = 0.5 * (lo[finite] + hi[finite])
    return q


def solve_ik(
    robot: Robot,
    target: object,
    q0: Sequence[float] | np.ndarray | None = None,
    *,
    frame: str | None = None,
    mask: Sequence[float] | np.ndarray | None = None,
    tol: float = 1e-6,
    max_iter: int = 100,
    restarts: int = 50,
    seed: int | None = 0,
    timeout: float | None = None,
) -> IKResult:
    """Put ``frame`` (default: the tip) on ``target``; see :meth:`toolkit.Robot.ik`.

    ``timeout`` [s] stops starting new restarts once that much time has passed (the
    TRAC-IK benchmark protocol); ``None`` means no time limit.
    """
    R_t, p_t, position_only = parse_target(target)
    w = parse_mask(mask, position_only)
    if not (math.isfinite(tol) and tol > 0):
        raise InvalidParameterError(f"tol must be > 0, got {tol}")
    if int(max_iter) < 1 or int(restarts) < 0:
        raise InvalidParameterError("max_iter must be >= 1 and restarts >= 0")
    fid = robot.frame_id(frame)
    state = _state(robot)
    q_start = state.mid if q0 is None else robot.check_q(q0)
    task = _Task(robot, fid, R_t, p_t, w)
    solver = _Solver(robot, task, tol, int(max_iter))
    rng = None  # created on the first restart
    deadline = None if timeout is None else time.perf_counter() + float(timeout)
    best_q, best_cost, total_iter, attempt = q_start, np.inf, 0, 0
    for attempt in range(int(restarts) + 1):
        if attempt == 0:
            start = q_start
        else:
            rng = np.random.default_rng(seed) if rng is None else rng
            start = rng.uniform(state.sample_lower, state.sample_upper)
        q, cost, iters, converged = solver.run(start)
        total_iter += iters
        if cost < best_cost:
            best_q, best_cost = q, cost
        if converged or (deadline is not None and time.perf_counter() > deadline):
            break
    return verify(robot, best_q, fid, R_t, p_t, w, tol, total_iter, attempt)


def verify(
    robot: Robot,
    q: np.ndarray,
    fid: int,
    R_t: np.ndarray,
    p_t: np.ndarray,
    w: np.ndarray,
    tol: float,
    iterations: int,
    restarts: int,
) -> IKResult:
    """An IKResult for q, its errors recomputed by a separate forward-kinematics call
    (on a Pinocchio Data object the solver never touches)."""
    state = _state(robot)
    data = state.verify_data
    pin.forwardKinematics(robot.model, data, q)
    M = pin.updateFramePlacement(robot.model, data, fid)
    wl = w.tolist()
    use_rot = any(k > 0 for k in wl[3:])
    e = np.zeros(6)
    e[:3] = p_t - M.translation
    if use_rot:
        e[3:] = pin.log3(M.rotation.T @ R_t)
    pos, rot = _masked_norms(e, wl, use_rot)
    inside = bool((q >= state.limit_lower).all() and (q <= state.limit_upper).all())
    ok = pos <= tol and rot <= tol and inside
    return IKResult(np.array(q), ok, pos, rot, int(iterations), int(restarts))


def solve_ik_path(
    robot: Robot,
    targets: Sequence[object],
    q0: Sequence[float] | np.ndarray | None = None,
    *,
    frame: str | None = None,
    mask: Sequence[float] | np.ndarray | None = None,
    tol: float = 1e-6,
    max_iter: int = 100,
    restarts: int = 50,
    seed: int | None = 0,
    max_jump: float = 0.5,
) -> PathResult:
    """Warm-started IK along targets: each solve starts from the previous answer.

    A neighbour is first solved with no restart (so the branch is kept); only if that
    fails are seeded restarts tried. Any step whose largest joint change exceeds
    ``max_jump`` is reported in ``jumps``.
    """
    targets = list(targets)
    if not targets:
        raise InvalidParameterError("ik_path needs at least one target")
    q_prev = _mid_range(robot) if q0 is None else robot.check_q(q0)
    results = []
    for k, target in enumerate(targets):
        kw = dict(frame=frame, mask=mask, tol=tol, max_iter=max_iter, seed=seed)
        res = solve_ik(robot, target, q_prev, restarts=0, **kw)
        if not res.success and restarts > 0:
            retry = solve_ik(robot, target, q_prev, restarts=restarts, **kw)
            res = retry if retry.success or k == 0 else res
        results.append(res)
        q_prev = res.q
    qs = np.array([r.q for r in results])
    steps = np.abs(np.diff(qs, axis=0)).max(axis=1) if len(qs) > 1 else np.zeros(0)
    return PathResult(
        q=qs,
        success=np.array([r.success for r in results]),
        position_error=np.array([r.position_error for r in results]),
        orientation_error=np.array([r.orientation_error for r in results]),
        jumps=[int(i) + 1 for i in np.nonzero(steps > max_jump)[0]],
        max_step=float(steps.max()) if len(steps) else 0.0,
    )
