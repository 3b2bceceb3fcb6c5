"""The :class:`Robot`: a Pinocchio model with checked inputs, safe to share between threads.

A ``Robot`` owns one ``pinocchio.Model``; every query validates its joint vector
(shape, finiteness, continuous joints on the unit circle: :mod:`toolkit.kinematics.joints`) and
frame name first, so a mistake is reported in the toolkit's words instead of as a C++
exception. Each thread gets its own ``pinocchio.Data`` (and IK workspace), so one robot
may serve several threads; a robot pickles (for process pools and Dask workers).
Nothing is attached to the Pinocchio model itself.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Concatenate, ParamSpec, TypeVar

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .. import dynamics as _dynamics
from ..common import ByArguments, PerThread, caller_level
from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..ik import AnalyticIK, BranchCaches, NumericIK, RobotIK, Structure
from ..kinematics import Backend, Frames, JointLayout, select
from .caches import Caches
from .collisions import CollisionQueries

__all__ = ["Robot"]

P = ParamSpec("P")
R = TypeVar("R")


def as_robot(value: object, what: str = "robot") -> Robot:
    """``value`` if it is a :class:`Robot`, else an :class:`InvalidParameterError`."""
    if not isinstance(value, Robot):
        raise InvalidParameterError(f"{what} must be a toolkit Robot, got {value!r:.100}")
    return value


def _answered_by(
    part: str, method: Callable[Concatenate[Any, P], R]
) -> Callable[Concatenate[Any, P], R]:
    """A method of :class:`Robot` that one of its parts answers: ``robot.ik(...)`` is
    ``robot._ik.ik(...)``, with that method's signature and docstring."""
    name = method.__name__

    @functools.wraps(method)
    def answer(robot: Any, /, *args: P.args, **kwargs: P.kwargs) -> R:
        return getattr(getattr(robot, part), name)(*args, **kwargs)  # type: ignore[no-any-return]

    return answer


_MOVED: dict[str, tuple[str, Callable[[Any], object]]] = {
    "nv": ("robot.joints.nv", lambda r: r.joints.nv),
    "lower": ("robot.joints.lower", lambda r: r.joints.lower),
    "upper": ("robot.joints.upper", lambda r: r.joints.upper),
    "joint_names": ("robot.joints.names", lambda r: r.joints.names),
    "check_q": ("robot.joints.check", lambda r: r.joints.check),
    "check_v": ("robot.joints.check_v", lambda r: r.joints.check_v),
    "within_limits": ("robot.joints.within_limits", lambda r: r.joints.within_limits),
    "q_from_angles": ("robot.joints.q_from_angles", lambda r: r.joints.q_from_angles),
    "angles": ("robot.joints.angles", lambda r: r.joints.angles),
    "neutral": ("robot.joints.neutral", lambda r: r.joints.neutral),
    "frame_id": ("robot.frames.id", lambda r: r.frames.id),
    "frame_names": ("list(robot.frames)", lambda r: list(r.frames)),
    "motion_rank": ("robot.frames.rank", lambda r: r.frames.rank),
    "engine": ("robot.kinematics.engine", lambda r: r.kinematics.engine),
    "backend": ("robot.kinematics.engine (the back end in use, and why)", lambda r: r._asked),
    "collisions": ("robot.collision_checker(scene).collisions", lambda r: r._collide.collisions),
    "min_distance": (
        "robot.collision_checker(scene).min_distance",
        lambda r: r._collide.min_distance,
    ),
    "base_collisions": (
        "robot.collision_checker(scene).base_hits",
        lambda r: r._collide.base_collisions,
    ),
    "ik_state": ("nothing public (the numeric IK's own)", lambda r: r._numeric.ik_state),
    "ik_loop": ("nothing public (the numeric IK's own)", lambda r: r._numeric.ik_loop),
}
"""The names :class:`Robot` had before its face was thinned, and where each went; each still
answers, with a ``DeprecationWarning``, until the next release."""


class Robot(ByArguments):
    """A kinematic model built by Pinocchio, with the toolkit's checked API.

    A thin face over the packages: its joint space (``joints``), its frames (``frames``),
    its kinematics back end (``kinematics``); the IK (:mod:`toolkit.ik`), collisions
    (:mod:`toolkit.collision`) and planning (:mod:`toolkit.planning`) answer through its
    methods. A robot pickles and compares by its constructor arguments (model, name, tip,
    urdf_path, params, facts, backend, srdf_path).

    Attributes:
        model: the ``pinocchio.Model`` (treat it as read-only).
        data: the ``pinocchio.Data`` used by this object's queries in the calling thread.
        joints: the joint space (:class:`toolkit.kinematics.JointLayout`): ``nv``,
            ``names``, ``lower``, ``upper``, ``neutral()``, ``check(q)``, ``angles(q)``,
            ``q_from_angles(values)``, ``within_limits(q)``.
        frames: every frame by name (:class:`toolkit.kinematics.Frames`): ``frames[name]``
            its index, ``frames.id(None)`` the tip's, ``frames.rank(frame)`` in how many
            directions the joints move it.
        kinematics: the back end answering the kinematics
            (:class:`toolkit.kinematics.Backend`; ``kinematics.engine`` says which,
            ``compiled`` or ``pinocchio``, and why).
        name: the catalogue or file name the robot was loaded from.
        tip: name of the tool frame, the default ``frame`` of every query.
        urdf_path: the URDF file the model was built from, if any.
        srdf_path: the SRDF file of its self-collision pairs, if any.
        params: the xacro arguments a catalogue model was rendered with (read-only;
            empty for other robots).
        facts: per-model facts from the catalogue entry, e.g. ``nominal_torque`` of the
            Katana drives or ``structure`` of the positioning structures (read-only; empty for
            other robots).
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
        if backend is not None:
            _validate.one_of(backend, "backend", ("compiled", "pinocchio"))
        self._asked = backend
        self.kinematics: Backend = select(model, backend)[0]
        self.joints = JointLayout(model, self.name)
        self.frames = Frames(model, self.joints, self.kinematics, tip)
        self._data = PerThread(model.createData)
        self._caches = Caches()
        self._numeric = NumericIK(model, self.joints, self.kinematics)
        self._analytic = AnalyticIK(model, self.name, self.joints, self.frames,
                                    self.kinematics, BranchCaches(), self._numeric)  # fmt: skip
        self._collide = CollisionQueries(self, self.joints)
        self._ik = RobotIK(self._analytic, self._collide.checker)

    def _argument(self, name: str) -> object:
        return self._asked if name == "backend" else getattr(self, name)

    if not TYPE_CHECKING:  # the old names: at run time only (the type checker refuses them)

        def __getattr__(self, name: str) -> object:
            moved = _MOVED.get(name)
            if moved is None or name.startswith("__"):
                raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
            warnings.warn(
                f"Robot.{name} is now {moved[0]}; the old name goes in the next release",
                DeprecationWarning,
                stacklevel=caller_level(),
            )
            return moved[1](self)

    # ------------------------------------------------------------------ per thread
    @property
    def data(self) -> pin.Data:
        """The ``pinocchio.Data`` of this robot's queries in the calling thread."""
        return self._data.get()

    @property
    def tip(self) -> str:
        """The tool frame's name: the default ``frame`` of every query."""
        return self.frames.tip

    @property
    def nq(self) -> int:
        """Size of the configuration vector q (``joints.nv`` is the velocity's)."""
        return int(self.model.nq)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, tip={self.tip!r})"

    # ------------------------------------------------------------------ sampling
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
        fid = self.frames.id(frame)
        arr = self.joints.check(q, batch=True)
        if arr.ndim == 2:
            return self.kinematics.fk(arr, fid)
        return np.asarray(self.kinematics.fk(arr[None], fid)[0])

    def jacobian(self, q: ArrayLike, frame: str | None = None) -> np.ndarray:
        """Frame Jacobian, shape (6, nv): rows vx, vy, vz, wx, wy, wz.

        Velocities are expressed in a frame aligned with the base whose origin is
        the frame's origin (Pinocchio's ``LOCAL_WORLD_ALIGNED``). ``q`` of shape (N, nq)
        gives (N, 6, nv).
        """
        fid = self.frames.id(frame)
        arr = self.joints.check(q, batch=True)
        if arr.ndim == 2:
            return self.kinematics.jacobian(arr, fid)
        return np.asarray(self.kinematics.jacobian(arr[None], fid)[0])

    def gravity(self, q: ArrayLike, *, payload: object = None) -> np.ndarray:
        """Generalized gravity torques g(q) [N m or N], shape (nv,) or (N, nv): what the
        joints must exert to hold the arm still, with an optional ``payload``
        (:func:`toolkit.dynamics.gravity`)."""
        return _dynamics.gravity(self, q, payload=payload)

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
        fid = self.frames.id(frame)
        q_, v_, a_ = (
            self.joints.check(q),
            self.joints.check_v(qd, "qd"),
            self.joints.check_v(qdd, "qdd"),
        )
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

    # ------------------------------------------------------------------ inverse kinematics
    ik = _answered_by("_ik", RobotIK.ik)
    ik_batch = _answered_by("_ik", RobotIK.ik_batch)
    ik_path = _answered_by("_ik", RobotIK.ik_path)
    ik_all = _answered_by("_analytic", AnalyticIK.ik_all)
    ik_all_batch = _answered_by("_analytic", AnalyticIK.ik_all_batch)
    structure_of = _answered_by("_analytic", AnalyticIK.structure_of)

    @property
    def structure(self) -> Structure:
        """What makes the IK to the tip solvable in closed form: the family, its joints and
        why (or why none fits); see :func:`toolkit.ik.analytic.structure.find_structure`."""
        return self._analytic.structure

    # ------------------------------------------------------------------ groups and states
    def group(self, group: str | Sequence[str], at: ArrayLike | None = None) -> Robot:
        """The robot of a planning group: an SRDF ``<group>``'s name (``"panda_arm"``) or
        joint names. Its joints move; the others are locked at ``at`` (a configuration of
        this robot, nq) or at their neutral values within their limits, so its IK, plans,
        trajectories and maps move only the group's joints (its ``q`` holds only them).
        An unknown group is refused naming the SRDF's groups."""
        from .groups import group_robot

        robot: Robot = group_robot(self, group, at)
        return robot

    @property
    def states(self) -> Mapping[str, np.ndarray]:
        """The SRDF's named states (``<group_state>``, ``"ready"``) as configurations (nq)
        of this robot: the state's joints at its values, the others at their neutral
        values within their limits (read-only; empty without an SRDF)."""
        from .groups import named_states

        return MappingProxyType(named_states(self))

    # ------------------------------------------------------------------ collisions, planning
    in_collision = _answered_by("_collide", CollisionQueries.in_collision)
    collision_checker = _answered_by("_collide", CollisionQueries.collision_checker)
    plan = _answered_by("_collide", CollisionQueries.plan)
