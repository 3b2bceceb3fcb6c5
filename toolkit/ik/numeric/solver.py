"""Numeric inverse kinematics: damped least squares with adaptive damping, for any Robot.

The problem is built apart from the solver loop (a :class:`PoseTask`):

* residual ``e = [p_t - p ; log3(R^T R_t)]``: the position error in base-frame axes
  [m] and the orientation error as a rotation vector in the **tool frame's** axes [rad],
  so that masking ``rz`` frees the roll about the tool's own z axis (a 5-DOF arm);
* Jacobian ``J_e = [J_v ; R^T J_w]`` from Pinocchio's frame Jacobian
  (``LOCAL_WORLD_ALIGNED``); ``de/dq = -J_e`` to first order.

Each step solves ``(J_e^T W J_e + lambda I) dq = J_e^T W e`` with the
Levenberg-Marquardt damping ``lambda = DAMPING * E + LAMBDA_MIN``, ``E = e^T W e / 2``
(after Sugihara 2011): large far from the target, vanishing near it (Gauss-Newton,
quadratic convergence). Every step is clipped to the joint limits. A start whose cost has
not improved by 0.1 % for ``STALL`` iterations is restarted from a seeded random
configuration; the answer is checked with an independent forward-kinematics call before
``success`` is set. The same :class:`PoseTask` measures the errors of the backlash
compensation (:meth:`toolkit.backlash.Backlash.compensate`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ...kinematics import CIRCLE_TOL, JointLayout, kernels
from ..checks import valid_q
from .task import PoseTask

__all__ = [
    "DAMPING",
    "LAMBDA_MIN",
    "STALL",
    "IKResult",
    "PathResult",
    "SolverState",
    "kernel_seed",
    "run_pinocchio",
    "verify",
]

DAMPING = 0.05
"""Factor of the cost E in the Levenberg-Marquardt damping lambda = DAMPING E + LAMBDA_MIN."""
LAMBDA_MIN = 1e-9
"""Floor of the damping (keeps the normal equations positive definite at a singularity)."""
STALL = 4
"""Iterations without a 0.1 % cost improvement after which a start counts as stalled."""

_EYE3 = np.eye(3)


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
    collision: tuple[str, str] | None = None
    """With ``collision_free=True``: the pair that collides at the best reached q when no
    collision-free solution was found ("reached, but link5 hits table"), else None."""
    method: str = "numeric"
    """How ``q`` was found: ``"numeric"`` (the damped least squares solver) or
    ``"analytic"`` (an analytic branch, verified the same way; ``iterations`` 0)."""


class PathResult(NamedTuple):
    """Outcome of a warm-started IK along a path of targets."""

    q: np.ndarray  # (N, nq)
    success: np.ndarray  # (N,) bool
    position_error: np.ndarray  # (N,)
    orientation_error: np.ndarray  # (N,)
    jumps: list[int]  # indices i where max |q[i] - q[i-1]| exceeded max_jump
    max_step: float  # the largest joint change between neighbours [rad or m]
    collision_step: int | None = None  # with collision_free: the first step that collides

    @property
    def all_succeeded(self) -> bool:
        return bool(np.all(self.success))


_Idle = tuple[np.ndarray, np.ndarray, np.ndarray, list[tuple[int, float, float]]]
"""The joints that do not move a frame: (q columns, lower, upper, those as scalars)."""


class SolverState:
    """What every IK solve on one robot reuses: Pinocchio Data, bounds, the start, and the
    one stream of restart configurations.

    Built once per thread by :class:`~toolkit.robot.Robot` (its ``ik_state`` attribute).
    """

    def __init__(self, model: pin.Model, layout: JointLayout, neutral: np.ndarray) -> None:
        lower, upper = layout.lower, layout.upper
        self.model = model
        self.layout = layout
        self._data: pin.Data | None = None
        self._verify_data: pin.Data | None = None
        self.euclidean = model.nq == model.nv
        scalar = layout.scalar_q
        clip = scalar & np.isfinite(lower) & np.isfinite(upper)
        # coordinates that are not clipped get infinite bounds: one clip per step
        self.clip_lower = np.where(clip, lower, -np.inf)
        self.clip_upper = np.where(clip, upper, np.inf)
        # restarts draw valid configurations (continuous joints on the unit circle)
        self.sample_lower, self.sample_upper = layout.sample_lower, layout.sample_upper
        self.limit_lower, self.limit_upper = lower - 1e-12, upper + 1e-12
        pairs = [g for g in layout.units if len(g) == 2]
        quaternions = [g for g in layout.units if len(g) == 4]
        self._groups = (
            None
            if len(pairs) + len(quaternions) < len(layout.units)
            else (
                self.limit_lower,
                self.limit_upper,
                np.array(pairs, np.int64).reshape(-1, 2),
                np.array(quaternions, np.int64).reshape(-1, 4),
            )
        )
        # the first start: mid-range for limited scalar joints, neutral for the others
        self.mid = np.array(neutral, dtype=float)
        self.mid[clip] = 0.5 * (lower[clip] + upper[clip])

    @property
    def data(self) -> pin.Data:
        """The Pinocchio loop's own workspace (made on first use: Pinocchio takes seconds to
        build the Data of a chain of hundreds of joints, and the compiled loop needs none)."""
        if self._data is None:
            self._data = self.model.createData()
        return self._data

    @property
    def verify_data(self) -> pin.Data:
        """A separate Data for the independent check (made on first use)."""
        if self._verify_data is None:
            self._verify_data = self.model.createData()
        return self._verify_data

    def restart(self, seed: int, attempt: int) -> np.ndarray:
        """The start of restart ``attempt`` (>= 1) under a kernel ``seed`` (see
        :func:`kernel_seed`): the same configuration on both back ends."""
        q = np.empty(self.model.nq)
        layout = self.layout
        kernels.restart_sample(seed, attempt, layout.qlay, self.sample_lower, self.sample_upper, q)
        if self.layout.has_other:
            q = np.asarray(pin.normalize(self.model, q))
        return q

    def _idle(self, frame_id: int) -> _Idle:
        """(q columns, lower, upper, the same as (column, lower, upper) scalars) of the joints
        that do not move frame ``frame_id`` (a hand's fingers for the tool), kept per frame."""
        kept = self.__dict__.setdefault("_idle_of", {})
        if frame_id not in kept:
            model = self.model
            moving = set(model.supports[model.frames[frame_id].parentJoint])
            joints = [model.joints[j] for j in range(1, model.njoints) if j not in moving]
            cols = [k for joint in joints for k in range(joint.idx_q, joint.idx_q + joint.nq)]
            at = np.array(cols, dtype=np.int64)
            low, high = self.clip_lower[at], self.clip_upper[at]
            scalars = list(zip(cols, low.tolist(), high.tolist(), strict=True))
            kept[frame_id] = (at, low, high, scalars)
        idle: _Idle = kept[frame_id]
        return idle

    def held(self, frame_id: int, q: np.ndarray, start: np.ndarray) -> np.ndarray:
        """``q`` (..., nq) with the joints that do not move the frame at ``start``'s values
        (nq,) or (..., nq), brought within their limits (restarts draw them at random, and
        the frame's pose does not depend on them): an answer keeps them at its start."""
        at, low, high, scalars = self._idle(frame_id)
        if not len(at):
            return q
        q = np.array(q, dtype=float)
        if q.ndim == 1 and np.ndim(start) == 1:  # one answer (the common call): scalars
            for k, lo, hi in scalars:
                q[k] = min(max(float(start[k]), lo), hi)
            return q
        q[..., at] = np.minimum(np.maximum(np.asarray(start)[..., at], low), high)
        return q

    def valid(self, q: np.ndarray) -> bool:
        """True if q is inside the limits and every (cos, sin) pair and quaternion is unit."""
        if self._groups is None or q.dtype != np.float64 or q.shape != self.limit_lower.shape:
            return bool(self.valid_rows(q))
        lower, upper, pairs, quaternions = self._groups
        return bool(valid_q(q, lower, upper, pairs, quaternions, CIRCLE_TOL))

    def valid_rows(self, q: np.ndarray) -> np.ndarray:
        """:meth:`valid` per configuration of q (..., nq)."""
        ok = ((q >= self.limit_lower) & (q <= self.limit_upper)).all(axis=-1)
        if self.layout.units:
            ok &= ~self.layout.off_manifold(q).any(axis=-1)
        return np.asarray(ok)


def kernel_seed(seed: int | None) -> int:
    """The 31-bit seed of the restart stream; None draws a fresh one (one place for both
    back ends, single and batch solves)."""
    if seed is None:
        return int(np.random.SeedSequence().entropy % (2**31))  # type: ignore[operator]
    return int(seed % (2**31))


try:  # eigenpy ships with Pinocchio; its Cholesky is ~3x faster than numpy's solve at 6x6
    from eigenpy import LLT as _LLT
except ImportError:  # pragma: no cover - pinocchio always brings eigenpy
    _LLT = None


def _spd_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve A x = b for a symmetric positive-definite A (the damped normal equations)."""
    if _LLT is not None:
        x = np.asarray(_LLT(A).solve(b))
        if np.isfinite(x).all():
            return x
    return np.asarray(np.linalg.solve(A, b))


def run_pinocchio(
    state: SolverState, task: PoseTask, q: np.ndarray, tol: float, max_iter: int
) -> tuple[np.ndarray, float, int, bool]:
    """The IK loop on Pinocchio, from q: (best q, its weighted cost, iterations, converged).

    One Pinocchio call per iteration for kinematics and Jacobians, scalar arithmetic for
    the errors, one clip and one Cholesky solve (the compiled loop is the same, step for
    step: :func:`toolkit.ik.numeric.kernels.solve`).
    """
    model = state.model
    data, fid, w, unit_w = state.data, task.frame_id, task.weights, task.unit_weights
    lower, upper, nv = state.clip_lower, state.clip_upper, model.nv
    # cost = e^T W e / 2 <= tol^2 whenever both norms are <= tol (weights <= 1 aside)
    tol2 = tol * tol * max(1.0, float(w.max()))
    lwa = pin.LOCAL_WORLD_ALIGNED
    q = np.clip(q, lower, upper)
    best_q, best_cost, since_best = q, np.inf, 0
    e = np.zeros(6)
    for it in range(1, max_iter + 1):
        pin.computeJointJacobians(model, data, q)
        M = pin.updateFramePlacement(model, data, fid)
        task.residual_into(e, M)
        J = pin.getFrameJacobian(model, data, fid, lwa)
        if J.ndim == 1:  # eigenpy returns the 6x1 Jacobian of a 1-DOF robot as (6,)
            J = J.reshape(6, 1)
        J = task.tool_jacobian(J, M)
        cost = 0.5 * float(e @ e) if unit_w else 0.5 * float(e @ (w * e))
        since_best = 0 if cost < best_cost * (1 - 1e-3) else since_best + 1
        if cost < best_cost:
            best_q, best_cost = q, cost
        if cost <= tol2:  # necessary for both errors <= tol: only then compute them
            pos, rot = task.norms(e)
            if pos <= tol and rot <= tol:
                return q, cost, it, True
        if since_best >= STALL:  # stalled (local minimum, or the target is out of reach)
            return best_q, best_cost, it, False
        JtW = J.T if unit_w else J.T * w
        A = JtW @ J
        A.flat[:: nv + 1] += DAMPING * cost + LAMBDA_MIN  # + lambda I
        dq = _spd_solve(A, JtW @ e)
        q = q + dq if state.euclidean else pin.integrate(model, q, dq)
        q = np.minimum(np.maximum(q, lower), upper)
    return best_q, best_cost, max_iter, False


def verify(
    state: SolverState,
    task: PoseTask,
    q: np.ndarray,
    tol: float,
    iterations: int = 0,
    restarts: int = 0,
) -> IKResult:
    """An IKResult for q, its errors recomputed by Pinocchio's forward kinematics on a Data
    object the solver never touches; ``success`` also needs a valid q (limits, unit
    (cos, sin) pairs and quaternions: what ``Robot.fk`` accepts)."""
    pos, rot = task.errors(state.model, state.verify_data, q)
    ok = pos <= tol and rot <= tol and state.valid(q)
    return _RESULT((np.array(q), ok, pos, rot, int(iterations), int(restarts), None, "numeric"))


_RESULT = IKResult._make
