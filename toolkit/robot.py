"""The :class:`Robot`: a Pinocchio model and its data, with checked inputs.

A ``Robot`` owns one ``pinocchio.Model`` and one ``pinocchio.Data``; every query
validates its joint vector (shape, finiteness) and frame name first, so a
mistake is reported in the toolkit's words instead of as a C++ exception.
Nothing is attached to the Pinocchio model itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ._validate import vector3
from .errors import ConfigurationError, FrameNotFoundError, InvalidParameterError
from .ik import IKOptions, IKResult, PathResult, PoseTask, SolverState, solve_ik, solve_ik_path

__all__ = ["Robot"]


class Robot:
    """A kinematic model built by Pinocchio, with the toolkit's checked API.

    Attributes:
        model: the ``pinocchio.Model`` (treat it as read-only).
        data: the ``pinocchio.Data`` used by this object's queries.
        name: the catalogue or file name the robot was loaded from.
        tip: name of the tool frame, the default ``frame`` of every query.
        urdf_path: the URDF file the model was built from, if any.
        params: the xacro arguments a catalogue model was rendered with (read-only;
            empty for other robots).
        facts: per-model facts from the catalogue entry, e.g. ``nominal_torque`` of the
            Katana drives or ``structure`` of [P3]'s models (read-only; empty for
            other robots).
        ik_state: the numeric IK's per-robot workspace (:class:`toolkit.ik.SolverState`).
    """

    def __init__(
        self,
        model: pin.Model,
        *,
        name: str | None = None,
        tip: str | None = None,
        urdf_path: str | Path | None = None,
    ) -> None:
        self.model = model
        self.data = model.createData()
        self.name = name or model.name
        self.urdf_path = Path(urdf_path) if urdf_path is not None else None
        self.params: Mapping[str, float | int | str] = MappingProxyType({})
        self.facts: Mapping[str, object] = MappingProxyType({})
        self._frames = {f.name: i for i, f in reversed(list(enumerate(model.frames)))}
        if tip is None:
            tip = model.frames[len(model.frames) - 1].name
        self.frame_id(tip)  # validates
        self.tip = tip
        lower = np.array(model.lowerPositionLimit, dtype=float)
        upper = np.array(model.upperPositionLimit, dtype=float)
        lower.setflags(write=False)
        upper.setflags(write=False)
        self._lower, self._upper = lower, upper
        self.ik_state = SolverState(model, lower, upper, self.neutral())

    # ------------------------------------------------------------------ facts
    @property
    def nq(self) -> int:
        """Size of the configuration vector q."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Size of the velocity vector (columns of the Jacobian)."""
        return int(self.model.nv)

    @property
    def lower(self) -> np.ndarray:
        """Lower joint limits, shape (nq,), read-only."""
        return self._lower

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits, shape (nq,), read-only."""
        return self._upper

    @property
    def joint_names(self) -> list[str]:
        """Names of the joints that own coordinates of q, in q's order."""
        return [
            self.model.names[j]
            for j in range(1, self.model.njoints)
            if self.model.joints[j].nq > 0 and self.model.joints[j].idx_q >= 0
        ]

    @property
    def frame_names(self) -> list[str]:
        """Every frame name of the model (links, joints, fixed frames)."""
        return list(self._frames)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, tip={self.tip!r})"

    # ------------------------------------------------------------------ checks
    def frame_id(self, frame: str | None) -> int:
        """Index of a frame by name (default: the tip); unknown names list the valid ones."""
        if frame is None:
            frame = self.tip
        if not isinstance(frame, str) or frame not in self._frames:
            raise FrameNotFoundError(str(frame), self._frames, robot=self.name)
        return int(self._frames[frame])

    def check_q(self, q: ArrayLike, *, batch: bool = False) -> np.ndarray:
        """q as a float64 array of shape (nq,) (or (N, nq) with ``batch=True``).

        Raises :class:`ConfigurationError` naming the problem: non-numeric entries,
        the wrong length, NaN or infinite values.
        """
        try:
            arr = np.asarray(q, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(f"{self.name}: q must be numeric, got {q!r}") from None
        ok_shape = arr.ndim == 1 or (batch and arr.ndim == 2)
        if not ok_shape or arr.shape[-1] != self.nq:
            want = f"({self.nq},)" + (f" or (N, {self.nq})" if batch else "")
            raise ConfigurationError(
                f"{self.name}: q must have shape {want} for joints {self.joint_names}, "
                f"got shape {arr.shape}"
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            columns = sorted(set(np.nonzero(bad)[-1].tolist()))
            raise ConfigurationError(
                f"{self.name}: q has NaN or infinite entries at index {columns}"
            )
        return arr

    def within_limits(self, q: ArrayLike, tol: float = 1e-12) -> bool:
        """True if every coordinate of q lies inside [lower - tol, upper + tol]."""
        arr = self.check_q(q, batch=True)
        return bool(np.all(arr >= self._lower - tol) and np.all(arr <= self._upper + tol))

    # ------------------------------------------------------------------ sampling
    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (zero angles for revolute joints)."""
        return np.array(pin.neutral(self.model))

    def random_q(
        self, n: int | None = None, seed: int | np.random.Generator | None = None
    ) -> np.ndarray:
        """Uniform random configuration(s) within the joint limits.

        Returns shape (nq,) when ``n`` is None, else (n, nq). Joints without
        finite limits are sampled in [-pi, pi].
        """
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        lo = np.where(np.isfinite(self._lower), self._lower, -np.pi)
        hi = np.where(np.isfinite(self._upper), self._upper, np.pi)
        shape = (self.nq,) if n is None else (int(n), self.nq)
        return rng.uniform(lo, hi, size=shape)

    # ------------------------------------------------------------------ kinematics
    def fk(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Pose of ``frame`` (default: the tip) in the base frame, as a 4x4 matrix.

        ``q`` of shape (N, nq) gives an (N, 4, 4) stack.
        """
        fid = self.frame_id(frame)
        arr = self.check_q(q, batch=True)
        if arr.ndim == 2:
            return (
                np.stack([self._fk(row, fid) for row in arr]) if len(arr) else np.zeros((0, 4, 4))
            )
        return self._fk(arr, fid)

    def _fk(self, q: np.ndarray, fid: int) -> np.ndarray:
        pin.forwardKinematics(self.model, self.data, q)
        return np.array(pin.updateFramePlacement(self.model, self.data, fid).homogeneous)

    def jacobian(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Frame Jacobian, shape (6, nv): rows vx, vy, vz, wx, wy, wz.

        Velocities are expressed in a frame aligned with the base whose origin is
        the frame's origin (Pinocchio's ``LOCAL_WORLD_ALIGNED``).
        """
        fid = self.frame_id(frame)
        arr = self.check_q(q)
        return np.array(
            pin.computeFrameJacobian(self.model, self.data, arr, fid, pin.LOCAL_WORLD_ALIGNED)
        )

    def point_kinematics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        rho: ArrayLike = (0.0, 0.0, 0.0),
        frame: str | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity and acceleration of a point M fixed on a link ([P3], eqs. 2-4).

        ``rho`` holds M's constant coordinates in ``frame`` (default: the tip).
        r_M = T rho; V_M = dT/dt rho = v_O + w x (R rho); a_M = d2T/dt2 rho =
        a_O + alpha x (R rho) + w x (w x (R rho)), with v_O, w, a_O (classical) and alpha
        of the frame from Pinocchio, all in base-frame axes [m, m/s, m/s^2].
        """
        fid = self.frame_id(frame)
        q_, v_, a_ = self.check_q(q), self.check_q(qd), self.check_q(qdd)
        r = vector3(rho, "rho")
        ref = pin.LOCAL_WORLD_ALIGNED
        pin.forwardKinematics(self.model, self.data, q_, v_, a_)
        placement = pin.updateFramePlacement(self.model, self.data, fid)
        vel = pin.getFrameVelocity(self.model, self.data, fid, ref)
        acc = pin.getFrameClassicalAcceleration(self.model, self.data, fid, ref)
        spatial = pin.getFrameAcceleration(self.model, self.data, fid, ref)
        arm = placement.rotation @ r
        w = vel.angular
        position = placement.translation + arm
        velocity = vel.linear + np.cross(w, arm)
        acceleration = acc.linear + np.cross(spatial.angular, arm) + np.cross(w, np.cross(w, arm))
        return position, velocity, acceleration

    # ------------------------------------------------------------------ inverse kinematics
    def ik(
        self,
        target: object,
        q0: ArrayLike | None = None,
        *,
        frame: str | None = None,
        mask: ArrayLike | None = None,
        options: IKOptions | None = None,
        **overrides: object,
    ) -> IKResult:
        """Joint values that put ``frame`` (default: the tip) on ``target``.

        Damped least squares with adaptive (Levenberg-Marquardt) damping on
        Pinocchio's frame Jacobian; steps never leave the joint limits; a stalled
        start is restarted from seeded random configurations (same ``seed``, same
        answer). See :mod:`toolkit.ik` and docs/ik.md.

        Args:
            target: 4x4 pose in the base frame, or a 3-vector position (position only).
            q0: start configuration (default: the middle of the joint ranges).
            mask: six weights (x, y, z, rx, ry, rz); positions in base axes, rotations
                about the tool frame's own axes, so ``(1, 1, 1, 1, 1, 0)`` frees the roll
                about the tool z axis.
            options: an :class:`~toolkit.ik.IKOptions`; keyword ``overrides`` set its
                fields one by one: ``tol`` (1e-6, on position [m] and orientation [rad]),
                ``max_iter`` (100, per start), ``restarts`` (50), ``seed`` (0) and
                ``timeout`` (None: wall-clock budget [s] after which no restart begins).

        Returns:
            :class:`toolkit.ik.IKResult`; an unreachable target gives ``success=False``
            with the best q found and its residuals (it never raises for that).
        """
        opts = IKOptions.build(options, **overrides)
        task = PoseTask.from_target(self.frame_id(frame), target, mask)
        start = None if q0 is None else self.check_q(q0)
        return solve_ik(self.model, self.ik_state, task, start, opts)

    def ik_path(
        self,
        targets: Sequence[object] | np.ndarray,
        q0: ArrayLike | None = None,
        *,
        frame: str | None = None,
        mask: ArrayLike | None = None,
        max_jump: float = 0.5,
        options: IKOptions | None = None,
        **overrides: object,
    ) -> PathResult:
        """Warm-started IK along a sequence of targets (see :func:`toolkit.ik.solve_ik_path`).

        Options as for :meth:`ik`. Returns a :class:`toolkit.ik.PathResult`: q per target,
        success flags, residuals, and the indices where a joint jumped by more than
        ``max_jump`` [rad or m].
        """
        opts = IKOptions.build(options, **overrides)
        fid = self.frame_id(frame)
        tasks = [PoseTask.from_target(fid, t, mask) for t in targets]
        if not tasks:
            raise InvalidParameterError("ik_path needs at least one target")
        start = None if q0 is None else self.check_q(q0)
        return solve_ik_path(self.model, self.ik_state, tasks, start, opts, max_jump)
