"""The joint-offset layer of [P1] (eqs. 16-17) on any robot: :class:`Backlash`.

Conventions (see docs/backlash.md):

* **The torque acting on the joint** is the torque the links and the payload exert on
  the joint output, about the joint axis, positive towards increasing theta. For a
  static arm it is minus Pinocchio's generalized gravity ``-g(theta)``; along a
  trajectory it is ``-rnea(theta, dtheta, ddtheta)``. With this sign the offset moves
  the output the way the load pulls it: the arm sags.
* **sign(0) = 0 (a dead zone)**, see :mod:`toolkit.backlash.law`.
* The torque depends on the output angles, so :meth:`Backlash.solve` solves the fixed
  point ``theta = q_cmd + dtheta(M(theta))`` (:mod:`toolkit.backlash.fixed_point`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ...common import ByArguments, PerThread
from ...common import validate as _validate
from ...dynamics import require_inertia
from ...errors import (
    ConfigurationError,
    ConvergenceError,
    InvalidParameterError,
    UnsupportedModelError,
)
from ...ik import IKOptions, IKResult, PoseTask
from ...kinematics import parallel, select
from ...robot import Robot
from . import _kernels
from .fixed_point import (
    SETTLE_ITERATIONS,
    OutputAngles,
    needs_settling,
    settle,
    solve_fixed_point,
)
from .law import DEFAULT_DELTA, DEFAULT_K_H, TORQUE_TOL, eq17

__all__ = ["Backlash"]


def _delta(value: ArrayLike, n: int) -> np.ndarray:
    """Backlash per joint, in [0, pi) [rad]."""
    delta = _validate.per_joint(value, "delta", n, lower=0.0)
    if np.any(delta >= np.pi):
        raise InvalidParameterError(f"delta must be below pi rad, got {delta.tolist()}")
    return delta


class Backlash(ByArguments):
    """The joint-offset layer of [P1] on any :class:`~toolkit.robot.Robot`.

    Args:
        robot: the robot whose joints have backlash.
        delta: backlash [rad] in [0, pi), scalar or one per joint (default 0.035, [P1]).
        k_h: stiffness-like coefficient >= 0, scalar or per joint ([P1]: 0.05 ... 0.4;
            the plain iteration converges while delta k_H |dM/dtheta| / M_H < 1; past
            that, settling on the arm's energy finds the rest, and :meth:`output_angles`
            raises where neither converged).
        nominal_torque: M_H per joint [N m]; defaults to the model's ``nominal_torque``
            fact (the Katana models carry eq. 1's values), required otherwise.
        payload: point mass [kg] at the robot's tip frame.

    A layer pickles and compares by these arguments.
    """

    _arguments = ("robot", "delta", "k_h", "nominal_torque", "payload")

    def __init__(
        self,
        robot: Robot,
        delta: ArrayLike = DEFAULT_DELTA,
        k_h: ArrayLike = DEFAULT_K_H,
        nominal_torque: ArrayLike | None = None,
        payload: float = 0.0,
    ) -> None:
        if not isinstance(robot, Robot):
            raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r}")
        self.robot = robot
        if robot.nq != robot.joints.nv or robot.joints.has_other:
            raise UnsupportedModelError(
                f"{robot.name}: the backlash layer needs one angle or stroke per joint "
                f"(nq = nv); this robot has nq = {robot.nq}, nv = {robot.joints.nv}"
            )
        require_inertia(robot, "the backlash layer's torques")
        n = robot.nq
        self.delta = _delta(delta, n)
        self.k_h = _validate.per_joint(k_h, "k_h", n, lower=0.0)
        if nominal_torque is None:
            facts = robot.facts.get("nominal_torque")
            if facts is None:
                raise InvalidParameterError(
                    f"{robot.name}: give nominal_torque (one M_H per joint, N m); only models "
                    "whose catalogue entry carries it (the Katanas, [P1] eq. 1) have a default"
                )
            nominal_torque = facts  # type: ignore[assignment]
        self.nominal_torque = _validate.per_joint(nominal_torque, "nominal_torque", n)
        if np.any(self.nominal_torque <= 0):
            raise InvalidParameterError("nominal_torque must be > 0 for every joint")
        self._law = np.vstack([self.nominal_torque, self.delta, self.k_h])  # eq. 17, per joint
        self.payload = _validate.number(payload, "payload [kg]", lower=0.0)
        self.model = self._model_with_payload(robot, self.payload)
        self._data = PerThread(self.model.createData)
        self._check_data = PerThread(robot.model.createData)  # independent pose checks
        # the payload model on the robot's kind of back end: gravity, and the compiled
        # fixed point when that back end packs the tree for kernels
        self._backend, _ = select(self.model, robot.kinematics.name)
        self._tree = getattr(self._backend, "tree", None)

    # ------------------------------------------------------------------ per thread, pickling
    @property
    def data(self) -> pin.Data:
        """Pinocchio Data of the payload model, one per calling thread."""
        return self._data.get()

    @staticmethod
    def _model_with_payload(robot: Robot, payload: float) -> pin.Model:
        """A copy of the robot's model with a point mass at the tip frame."""
        model = pin.Model(robot.model)
        if payload > 0:
            frame = model.frames[robot.frames.id(None)]
            point = pin.Inertia(payload, np.zeros(3), np.zeros((3, 3)))
            joint = frame.parentJoint
            model.inertias[joint] = model.inertias[joint] + frame.placement.act(point)
        return model

    def with_parameters(self, delta: ArrayLike, k_h: ArrayLike) -> Backlash:
        """A copy of this layer with other delta and k_H (same robot, torques and payload)."""
        other = object.__new__(Backlash)  # shares the payload model and engine (read-only)
        other.__dict__.update(self.__dict__)
        other.delta = _delta(delta, self.robot.nq)
        other.k_h = _validate.per_joint(k_h, "k_h", self.robot.nq, lower=0.0)
        other._law = np.vstack([other.nominal_torque, other.delta, other.k_h])
        return other

    def with_payload(self, payload: float) -> Backlash:
        """A copy of this layer carrying another ``payload`` [kg] at the tip (same robot,
        delta, k_H and nominal torques)."""
        return Backlash(self.robot, self.delta, self.k_h, self.nominal_torque, payload)

    def __repr__(self) -> str:
        return (
            f"Backlash({self.robot.name!r}, delta={self.delta.tolist()}, "
            f"k_h={self.k_h.tolist()}, payload={self.payload})"
        )

    # ------------------------------------------------------------------ torques
    def torques(
        self,
        theta: ArrayLike,
        dtheta: ArrayLike | None = None,
        ddtheta: ArrayLike | None = None,
    ) -> np.ndarray:
        """Torque acting on each joint [N m] at the output angles theta.

        Static (no velocities): ``-g(theta)``, the weight of the links and the payload.
        Along a trajectory: ``-rnea(theta, dtheta, ddtheta)``. Accepts (n,) or (N, n).
        """
        q = self.robot.joints.check(theta, batch=True)
        if dtheta is None and ddtheta is None:
            out = self._static_torques(np.atleast_2d(q))
            return out if q.ndim == 2 else out[0]
        v = self.robot.joints.check(np.zeros_like(q) if dtheta is None else dtheta, batch=True)
        a = self.robot.joints.check(np.zeros_like(q) if ddtheta is None else ddtheta, batch=True)
        if v.shape != q.shape or a.shape != q.shape:
            raise ConfigurationError("theta, dtheta and ddtheta must have the same shape")
        rows = zip(np.atleast_2d(q), np.atleast_2d(v), np.atleast_2d(a), strict=True)
        out = np.array([-pin.rnea(self.model, self.data, *r) for r in rows])
        return out if q.ndim == 2 else out[0]

    def offsets(self, torque: ArrayLike) -> np.ndarray:
        """Eq. 17 with this layer's delta, k_H and nominal torques [rad]; torque [N m] of
        shape (n,) or (N, n)."""
        m = _validate.array(torque, "torque")
        n = self.robot.nq
        if m.ndim not in (1, 2) or m.shape[-1] != n:
            raise InvalidParameterError(f"torque must have shape ({n},) or (N, {n}), got {m.shape}")
        return self._offsets(m)

    def _static_torques(self, theta: np.ndarray) -> np.ndarray:
        """torques(theta) for a checked (N, n) array, without re-validating it."""
        return -self._backend.gravity(theta)

    def _offsets(self, torque: np.ndarray) -> np.ndarray:
        """offsets(torque) for a checked array, without validating it again."""
        return eq17(torque, self.nominal_torque, self.delta, self.k_h)

    # ------------------------------------------------------------------ fixed point
    def solve(
        self,
        q_cmd: ArrayLike,
        *,
        tol: float = 1e-12,
        max_iter: int = 100,
        start: ArrayLike | None = None,
    ) -> OutputAngles:
        """The joint-output angles of commands q_cmd, with residual and convergence.

        Solves theta = q_cmd + dtheta(M(theta)) ([P1], eqs. 16-17), from theta = q_cmd.
        A joint whose torque changes sign inside its gap (a pendulum-like load hanging in
        the middle of the gap) is placed where its torque vanishes, inside
        [q - delta/2, q + delta/2] (``in_gap``). Where a joint's load pushes away from the
        middle of its gap (an inverted pendulum), both contact sides are equilibria and the
        output depends on the side the joint came from: the iteration starts from
        ``start`` (default: the command itself) and settles on the side nearest to it.

        Returns an :class:`OutputAngles` ((n,) fields for one command, (N, n) for N).
        """
        q = self.robot.joints.check(q_cmd, batch=True)
        tol = _validate.number(tol, "tol", lower=0.0, strict=True)
        max_iter = _validate.count(max_iter, "max_iter")
        q2 = np.atleast_2d(q)
        if start is None:
            theta0 = q2.copy()
        else:
            theta0 = np.array(np.broadcast_to(self.robot.joints.check(start, batch=True), q2.shape))
        out = self._fixed_point(q2, theta0, tol, max_iter)
        if q.ndim == 2:
            return out
        return OutputAngles(
            out.theta[0],
            out.torque[0],
            float(out.residual[0]),  # type: ignore[index]
            out.iterations,
            bool(out.converged[0]),  # type: ignore[index]
            out.in_gap[0],
        )

    def _fixed_point(
        self, q: np.ndarray, start: np.ndarray, tol: float, max_iter: int
    ) -> OutputAngles:
        """The rest of every row: the iteration of [P1]'s eq. 16 (compiled, :mod:`._kernels`,
        on a compiled back end, else the NumPy form of :mod:`.fixed_point`), then the rows
        with a joint in its gap settled by :func:`.fixed_point.settle` (Newton's method on
        the joints' equations: a joint in its gap carries no torque)."""
        if self._tree is None:
            out = solve_fixed_point(
                q, start, self.delta, lambda th, _: self._static_torques(th), self._offsets,
                tol, max_iter,
            )  # fmt: skip
            rows = needs_settling(out)
            if rows.size == 0:
                return out
            return settle(
                q, out, self._law, lambda th, _: self._static_torques(th),
                self._gravity_jacobian, tol, rows, self._potential_energy,
            )  # fmt: skip
        q, start = np.ascontiguousarray(q), np.ascontiguousarray(start)
        args = (q, start, self._law, tol, max_iter, TORQUE_TOL, self._tree)
        theta, torque, residual, iters, in_gap = _kernels.backlash_batch(parallel(len(q)), *args)
        converged = residual <= max(10 * tol, 1e-10)
        out = OutputAngles(theta, torque, residual, 0, converged, in_gap)
        rows = needs_settling(out)
        if rows.size:
            _kernels.settle_batch(
                parallel(4 * len(rows)), rows, q, theta, torque, residual, converged, in_gap,
                self._law, tol, SETTLE_ITERATIONS, TORQUE_TOL, self._tree,
            )  # fmt: skip
        iterations = int(iters.max()) if len(iters) else 0
        return OutputAngles(theta, torque, residual, iterations, converged, in_gap)

    def _potential_energy(self, theta: np.ndarray) -> float:
        """The potential energy of the links and the payload at theta [J]."""
        return float(pin.computePotentialEnergy(self.model, self.data, theta))

    def _gravity_jacobian(self, theta: np.ndarray, _row: int = 0) -> np.ndarray:
        """dM/dtheta (n, n) of the static torque M = -g(theta) at one configuration."""
        return -np.asarray(pin.computeGeneralizedGravityDerivatives(self.model, self.data, theta))

    def output_angles(self, q_cmd: ArrayLike, **solve_options: Any) -> np.ndarray:
        """Joint-output angles theta ((n,) or (N, n)) of commands q_cmd: :meth:`solve`'s
        ``theta`` alone (keywords ``tol``, ``max_iter``, ``start`` as for :meth:`solve`).

        Raises :class:`~toolkit.errors.ConvergenceError` when the fixed point did not
        converge for some command (e.g. a k_H so large that the iteration diverges);
        :meth:`solve` reports that per command instead.
        """
        out = self.solve(q_cmd, **solve_options)
        failed = ~np.atleast_1d(out.converged)
        if failed.any():
            worst = float(np.max(out.residual))
            raise ConvergenceError(
                f"{self.robot.name}: the backlash fixed point did not converge for "
                f"{int(failed.sum())} of {failed.size} command(s) (worst residual {worst:.3g} "
                f"rad after {out.iterations} iterations; k_h = {self.k_h.tolist()}); "
                "Backlash.solve reports it per command",
                worst,
            )
        return out.theta

    def fk(self, q_cmd: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Actual pose (4x4, or (N, 4, 4)) of ``frame`` when the joints are commanded to q_cmd."""
        return self.robot.fk(self.output_angles(q_cmd), frame)

    def tip_positions(self, q_cmd: ArrayLike) -> np.ndarray:
        """Actual tip positions (N, 3) for commands (N, n): vectorised where the chain allows."""
        return self.tips(np.atleast_2d(self.output_angles(q_cmd)))

    def tips(self, q: np.ndarray) -> np.ndarray:
        """Tip positions (N, 3) at joint values q (N, n) (no backlash), vectorised where the
        chain allows."""
        q = np.atleast_2d(self.robot.joints.check(q, batch=True))
        return self.robot.fk(q)[:, :3, 3]  # compiled over all cores for batches

    # ------------------------------------------------------------------ compensation
    def command_for(self, theta: ArrayLike) -> np.ndarray:
        """The command that makes the joint outputs reach theta: q_cmd = theta - dtheta(M(theta)).

        Exact, because the torque depends on the output angles only.
        """
        t = self.robot.joints.check(theta, batch=True)
        return t - self.offsets(self.torques(t))

    def compensate(self, target: object, q0: ArrayLike | None = None, **ik: Any) -> IKResult:
        """The command that puts the actual (backlash-affected) tool on ``target``.

        Solves the IK for the output angles theta (keywords ``frame``, ``mask``,
        ``options`` and the option overrides ``tol``, ``restarts``, ... as for
        :meth:`toolkit.Robot.ik`), then commands q_cmd = theta - dtheta(M(theta)).
        ``success`` is True only when the command is inside the joint limits and the
        actual pose, recomputed through the fixed point (started at the intended outputs,
        see :meth:`solve`), meets ``tol`` on the masked axes.
        """
        mask, frame = ik.pop("mask", None), ik.pop("frame", None)
        opts = IKOptions.build(**ik)
        res = self.robot.ik(target, q0, frame=frame, mask=mask, options=opts)
        q_cmd = self.command_for(res.q)
        # the fixed point from the intended outputs: if a joint has two equilibria, the
        # arm reaches the target when it approaches from that side
        actual = self.solve(q_cmd, start=res.q)
        task = PoseTask.from_target(self.robot.frames.id(frame), target, mask)
        p_err, r_err = task.errors(self.robot.model, self._check_data.get(), actual.theta)
        inside = self.robot.joints.within_limits(q_cmd)
        ok = res.success and p_err <= opts.tol and r_err <= opts.tol and inside
        ok = bool(ok and actual.converged)
        return IKResult(q_cmd, ok, p_err, r_err, res.iterations, res.restarts, method=res.method)
