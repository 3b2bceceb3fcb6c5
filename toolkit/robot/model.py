"""The :class:`Robot`: a Pinocchio model with checked inputs, safe to share between threads.

A ``Robot`` owns one ``pinocchio.Model``; every query validates its joint vector
(shape, finiteness, continuous joints on the unit circle: :mod:`toolkit.kinematics.joints`) and
frame name first, so a mistake is reported in the toolkit's words instead of as a C++
exception. Each thread gets its own ``pinocchio.Data`` (and IK workspace), so one robot
may serve several threads; a robot pickles (for process pools and Dask workers).
Nothing is attached to the Pinocchio model itself.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import ByArguments, PerThread
from ..common import validate as _validate
from ..errors import ConfigurationError, FrameNotFoundError, InvalidParameterError
from ..ik import IKLoop, SolverState, loop_for
from ..kinematics import Backend, JointLayout, select
from .batches import BranchBatches
from .branches import BranchQueries
from .caches import Caches
from .collisions import CollisionQueries
from .solving import IKQueries

__all__ = ["Robot"]


def as_robot(value: object, what: str = "robot") -> Robot:
    """``value`` if it is a :class:`Robot`, else an :class:`InvalidParameterError`."""
    if not isinstance(value, Robot):
        raise InvalidParameterError(f"{what} must be a toolkit Robot, got {value!r:.100}")
    return value


class Robot(ByArguments, IKQueries, BranchQueries, BranchBatches, CollisionQueries):
    """A kinematic model built by Pinocchio, with the toolkit's checked API.

    A robot pickles and compares by its constructor arguments (model, name, tip,
    urdf_path, params, facts).

    Attributes:
        model: the ``pinocchio.Model`` (treat it as read-only).
        data: the ``pinocchio.Data`` used by this object's queries in the calling thread.
        joints: the joint-coordinate layout (:class:`toolkit.kinematics.JointLayout`).
        name: the catalogue or file name the robot was loaded from.
        tip: name of the tool frame, the default ``frame`` of every query.
        urdf_path: the URDF file the model was built from, if any.
        params: the xacro arguments a catalogue model was rendered with (read-only;
            empty for other robots).
        facts: per-model facts from the catalogue entry, e.g. ``nominal_torque`` of the
            Katana drives or ``structure`` of the positioning structures (read-only; empty for
            other robots).
        ik_state: the numeric IK's workspace for the calling thread
            (:class:`toolkit.ik.SolverState`).
        engine: the kinematics back end in use and why
            (:class:`toolkit.kinematics.EngineChoice`: ``compiled`` or ``pinocchio``).
        backend: the back end asked for (``"compiled"``, ``"pinocchio"``), or None for
            the automatic choice (compiled whenever it covers every joint).
    """

    _arguments = ("model", "name", "tip", "urdf_path", "params", "facts", "backend", "srdf_path")

    def __init__(
        self,
        model: pin.Model,
        *,
        name: str | None = None,
        tip: str | None = None,
        urdf_path: str | Path | None = None,
        params: Mapping[str, float | int | str] | None = None,
        facts: Mapping[str, object] | None = None,
        backend: str | None = None,
        srdf_path: str | Path | None = None,
    ) -> None:
        if not isinstance(model, pin.Model):
            raise InvalidParameterError(f"model must be a pinocchio.Model, got {model!r}")
        if name is not None and not isinstance(name, str):
            raise InvalidParameterError(f"name must be a string, got {name!r}")
        self.model = model
        self.name = name or model.name
        if urdf_path is not None and not isinstance(urdf_path, str | Path):
            raise InvalidParameterError(f"urdf_path must be a path or None, got {urdf_path!r:.100}")
        self.urdf_path = Path(urdf_path) if urdf_path is not None else None
        if srdf_path is not None and not isinstance(srdf_path, str | Path):
            raise InvalidParameterError(f"srdf_path must be a path or None, got {srdf_path!r:.100}")
        self.srdf_path = Path(srdf_path) if srdf_path is not None else None
        for what, value in (("params", params), ("facts", facts)):
            if value is not None and not isinstance(value, Mapping):
                raise InvalidParameterError(f"{what} must be a mapping or None, got {value!r:.80}")
        self.params: Mapping[str, float | int | str] = MappingProxyType(dict(params or {}))
        self.facts: Mapping[str, object] = MappingProxyType(dict(facts or {}))
        self._frames = {f.name: i for i, f in reversed(list(enumerate(model.frames)))}
        if tip is None:
            tip = model.frames[len(model.frames) - 1].name
        self.frame_id(tip)  # validates
        self.tip = tip
        self.joints = JointLayout(model)
        if backend is not None:
            _validate.one_of(backend, "backend", ("compiled", "pinocchio"))
        self.backend = backend
        self._backend, self.engine = select(model, backend)
        self._loop = loop_for(self._backend)
        self._lower, self._upper = self.joints.lower, self.joints.upper
        self._ranks: dict[int, int] = {}
        self._data = PerThread(model.createData)
        self._ik = PerThread(lambda: SolverState(model, self.joints, self.neutral()))
        self._caches = Caches()

    # ------------------------------------------------------------------ per thread
    @property
    def data(self) -> pin.Data:
        """The ``pinocchio.Data`` of this robot's queries in the calling thread."""
        return self._data.get()

    @property
    def ik_state(self) -> SolverState:
        """The numeric IK's workspace in the calling thread."""
        return self._ik.get()

    @property
    def kinematics(self) -> Backend:
        """The kinematics back end answering this robot's queries
        (:class:`toolkit.kinematics.Backend`; ``engine`` says which and why)."""
        return self._backend

    @property
    def ik_loop(self) -> IKLoop:
        """The IK loop on that back end (:func:`toolkit.ik.loop_for`)."""
        return self._loop

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
        """Lower joint limits, shape (nq,), read-only.

        Unlimited joints (no finite limits, or lower > upper in the file) get -inf;
        a continuous joint's (cos, sin) coordinates get -1 (see :mod:`toolkit.kinematics.joints`).
        """
        return self._lower

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits, shape (nq,), read-only (+inf where unlimited)."""
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
        the wrong length (saying which joints take two numbers), NaN or infinite values,
        a continuous joint's (cos, sin) off the unit circle.
        """
        if batch is not False and batch is not True:
            _validate.flag(batch, "batch")
        arr = self._checked(q, self.nq, "q", batch)
        self.joints.check_circle(arr, self.name)
        return arr

    def check_v(self, v: ArrayLike, what: str = "v", *, batch: bool = False) -> np.ndarray:
        """A velocity-like vector (one value per degree of freedom): shape (nv,) or (N, nv).

        ``what`` names the argument in error messages."""
        if not isinstance(what, str):
            raise InvalidParameterError(f"what must be a name (str), got {what!r:.100}")
        return self._checked(v, self.nv, what, _validate.flag(batch, "batch"))

    def _checked(self, value: ArrayLike, n: int, what: str, batch: bool) -> np.ndarray:
        arr = _validate.real_array(value, f"{self.name}: {what}", ConfigurationError)
        ok_shape = arr.ndim == 1 or (batch and arr.ndim == 2)
        if not ok_shape or arr.shape[-1] != n:
            want = f"({n},)" + (f" or (N, {n})" if batch else "")
            hint = self.joints.length_hint() if what == "q" else ""
            raise ConfigurationError(
                f"{self.name}: {what} must have shape {want} for joints {self.joint_names}, "
                f"got shape {arr.shape}{hint}"
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            columns = sorted(set(np.nonzero(bad)[-1].tolist()))
            raise ConfigurationError(
                f"{self.name}: {what} has NaN or infinite entries at index {columns}"
            )
        return arr

    def within_limits(self, q: ArrayLike, tol: float = 1e-12) -> bool:
        """True if every coordinate of q lies inside [lower - tol, upper + tol] (tol >= 0)."""
        arr = self.check_q(q, batch=True)
        tol = _validate.number(tol, "tol", lower=0.0)
        return bool(np.all(arr >= self._lower - tol) and np.all(arr <= self._upper + tol))

    def motion_rank(self, frame: str | None = None) -> int:
        """In how many independent directions (of three translations and three rotations)
        the joints move ``frame`` (default: the tip): the largest rank of its Jacobian at 16
        random configurations. A 5-joint arm answers 5: its tool cannot take an arbitrary
        orientation at a point, only the orientations of a 5-D family."""
        fid = self.frame_id(frame)
        rank = self._ranks.get(fid)
        if rank is None:
            J = self._backend.jacobian(self.random_q(16, seed=0), fid)
            rank = self._ranks[fid] = int(max(np.linalg.matrix_rank(j, tol=1e-9) for j in J))
        return rank

    # ------------------------------------------------------------------ one value per joint
    def q_from_angles(self, values: ArrayLike) -> np.ndarray:
        """Pinocchio's q from one value per joint (angle [rad] or stroke [m]), shape (nv,)
        or (N, nv): a continuous joint's angle becomes its (cos, sin) pair."""
        arr = self.check_v(values, "values", batch=True)
        return self.joints.q_from_angles(arr, self.name)

    def angles(self, q: ArrayLike) -> np.ndarray:
        """One value per joint (shape (nv,) or (N, nv)) of a configuration q; continuous
        joints' angles in (-pi, pi]."""
        return self.joints.angles(self.check_q(q, batch=True), self.name)

    # ------------------------------------------------------------------ sampling
    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (zero angles for revolute joints)."""
        return np.array(pin.neutral(self.model))

    def random_q(
        self, n: int | None = None, seed: int | np.random.Generator | None = None
    ) -> np.ndarray:
        """Uniform random configuration(s) within the joint limits, valid for every joint.

        Returns shape (nq,) when ``n`` is None, else (n, nq) (``n`` >= 0). Unlimited
        joints are sampled in [-pi, pi] rad (revolute) or [-1, 1] m (prismatic);
        continuous joints as a uniform angle stored as (cos, sin). ``seed``: a whole
        number >= 0, a ``numpy.random.Generator``, or None.
        """
        if isinstance(seed, np.random.Generator):
            rng = seed
        else:
            if seed is not None:
                _validate.count(seed, "seed", minimum=0, maximum=2**64 - 1)
            rng = np.random.default_rng(seed)
        shape = (self.nq,) if n is None else (_validate.count(n, "n", minimum=0), self.nq)
        return self.joints.sample(rng, shape)

    # ------------------------------------------------------------------ kinematics
    def fk(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Pose of ``frame`` (default: the tip) in the base frame, as a 4x4 matrix.

        ``q`` of shape (N, nq) gives an (N, 4, 4) stack (over all cores for large N on the
        compiled back end, ``robot.engine``). One q or many, the same back end answers.
        """
        fid = self.frame_id(frame)
        arr = self.check_q(q, batch=True)
        if arr.ndim == 2:
            return self._backend.fk(arr, fid)
        return np.asarray(self._backend.fk(arr[None], fid)[0])

    def jacobian(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Frame Jacobian, shape (6, nv): rows vx, vy, vz, wx, wy, wz.

        Velocities are expressed in a frame aligned with the base whose origin is
        the frame's origin (Pinocchio's ``LOCAL_WORLD_ALIGNED``). ``q`` of shape (N, nq)
        gives (N, 6, nv).
        """
        fid = self.frame_id(frame)
        arr = self.check_q(q, batch=True)
        if arr.ndim == 2:
            return self._backend.jacobian(arr, fid)
        return np.asarray(self._backend.jacobian(arr[None], fid)[0])

    def gravity(self, q: ArrayLike) -> np.ndarray:
        """Generalized gravity torques g(q) [N m or N], shape (nv,) or (N, nv): what the
        joints must exert to hold the arm still (Pinocchio's ``computeGeneralizedGravity``)."""
        arr = self.check_q(q, batch=True)
        if arr.ndim == 2:
            return self._backend.gravity(arr)
        return np.asarray(self._backend.gravity(arr[None])[0])

    def point_kinematics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        rho: ArrayLike = (0.0, 0.0, 0.0),
        frame: str | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity and acceleration of a point M fixed on a link (rigid-body motion).

        ``rho`` holds M's constant coordinates in ``frame`` (default: the tip).
        r_M = T rho; V_M = dT/dt rho = v_O + w x (R rho); a_M = d2T/dt2 rho =
        a_O + alpha x (R rho) + w x (w x (R rho)), with v_O, w, a_O (classical) and alpha
        of the frame from Pinocchio, all in base-frame axes [m, m/s, m/s^2].
        """
        fid = self.frame_id(frame)
        q_, v_, a_ = self.check_q(q), self.check_v(qd, "qd"), self.check_v(qdd, "qdd")
        r = _validate.vector3(rho, "rho")
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
