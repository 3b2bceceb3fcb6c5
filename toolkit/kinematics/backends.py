"""The kinematics back end: one interface (:class:`Backend`), two implementations.

* **compiled** (:class:`CompiledBackend`): every model whose joints are revolute or
  prismatic on any axis, **continuous** (Pinocchio's (cos, sin) joints), **mimic** joints
  with any multiplier and offset, and a **free-flyer** root (a floating base): all the
  catalogue models, UR, Panda, Kinova Jaco 2, PR2, TIAGo, Talos, Solo, ... Joint placements,
  axes (read from each joint's motion subspace, a mimic joint's divided by its
  multiplier), mimic relations and inertias are read from the Pinocchio model once;
  forward kinematics, frame Jacobians and generalized gravity then run as numba kernels
  (:mod:`toolkit.kinematics.kernels`), whose packed chains (:meth:`CompiledBackend.chain`,
  :attr:`CompiledBackend.tree`) the IK loop (:mod:`toolkit.ik`), the collision pre-filter
  and the backlash fixed point build on.
* **pinocchio** (:class:`PinocchioBackend`): the reference, and the back end of what is
  left (spherical, planar, helical or composite joints), with the same API and results.

A :class:`~toolkit.robot.Robot` chooses its back end once (:func:`select`); every query,
the IK (through its loop for this back end, :func:`toolkit.ik.loop_for`) and the backlash
layer go through it, and ``robot.kinematics.engine`` says which one and why. **One
policy** decides how a batch runs: on the compiled back end, fewer than
:data:`PARALLEL_MIN` rows run on one core (no thread launch), more are spread over every core (under
:data:`toolkit.common.compiler.PARALLEL_LOCK`).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import NamedTuple, Protocol

import numpy as np
import pinocchio as pin

from ..common import PerThread
from ..errors import UnsupportedModelError
from . import kernels as _kernels
from .joints import CIRCLE, FREE_FLYER, PRISMATIC, REVOLUTE

__all__ = [
    "PARALLEL_MIN",
    "Backend",
    "CompiledBackend",
    "EngineChoice",
    "PinocchioBackend",
    "parallel",
    "select",
    "serial",
]

PARALLEL_MIN = 64
"""Rows from which a compiled batch is spread over the cores (fewer run on one core)."""

_LOCAL = threading.local()


def parallel(rows: int) -> bool:
    """The one size policy: spread a compiled batch of ``rows`` over the cores? (Not inside
    :func:`serial`, and not below :data:`PARALLEL_MIN` rows.)"""
    return rows >= PARALLEL_MIN and not getattr(_LOCAL, "serial", False)


@contextmanager
def serial() -> Iterator[None]:
    """Within the block, this thread's compiled batches run on one core, without the launch
    lock: threads that each run serial batches use every core at once (the kernels release
    the GIL). The maps' local thread pool runs each chunk so."""
    before = getattr(_LOCAL, "serial", False)
    _LOCAL.serial = True
    try:
        yield
    finally:
        _LOCAL.serial = before


class EngineChoice(NamedTuple):
    """The back end a robot uses, and why."""

    name: str  # "compiled" or "pinocchio"
    reason: str


class Backend(Protocol):
    """What every back end computes; inputs are checked by the caller (``Robot``)."""

    name: str
    engine: EngineChoice  # which back end a robot uses, and why (set by ``select``)

    def fk(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        """Poses (N, 4, 4) of a frame at configurations Q (N, nq)."""
        ...

    def jacobian(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        """Frame Jacobians (N, 6, nv), ``LOCAL_WORLD_ALIGNED``."""
        ...

    def gravity(self, Q: np.ndarray) -> np.ndarray:
        """Generalized gravity g(q) (N, nv)."""
        ...


# ---------------------------------------------------------------------- Pinocchio
class PinocchioBackend:
    """Pinocchio's own algorithms, one configuration at a time (any joint type)."""

    name = "pinocchio"
    engine = EngineChoice("pinocchio", "chosen by the caller")

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.nv = int(model.nv)
        self._data = PerThread(model.createData)

    def fk(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        model, data = self.model, self._data.get()
        out = np.empty((len(Q), 4, 4))
        for i, q in enumerate(Q):
            pin.forwardKinematics(model, data, q)
            out[i] = pin.updateFramePlacement(model, data, frame_id).homogeneous
        return out

    def jacobian(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        model, data = self.model, self._data.get()
        out = np.empty((len(Q), 6, self.nv))
        for i, q in enumerate(Q):
            J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)
            out[i] = np.asarray(J).reshape(6, self.nv)  # eigenpy gives a 6x1 matrix as (6,)
        return out

    def gravity(self, Q: np.ndarray) -> np.ndarray:
        model, data = self.model, self._data.get()
        out = np.empty((len(Q), self.nv))
        for i, q in enumerate(Q):
            out[i] = np.asarray(pin.computeGeneralizedGravity(model, data, q)).reshape(self.nv)
        return out


# ---------------------------------------------------------------------- compiled
def _motion_axis(S: np.ndarray, what: str) -> tuple[int, np.ndarray]:
    """(kind, unit axis) of a 1-DoF motion subspace (6,) = (linear, angular)."""
    lin, ang = S[:3], S[3:]
    nl, na = float(np.linalg.norm(lin)), float(np.linalg.norm(ang))
    if na > 0 and nl == 0:
        return REVOLUTE, ang / na
    if nl > 0 and na == 0:
        return PRISMATIC, lin / nl
    raise ValueError(f"{what}: neither a pure rotation nor a pure translation")


def _joint(model: pin.Model, data: pin.Data, j: int) -> tuple[int, np.ndarray, float, float]:
    """(kind, unit axis, scale, offset) of joint j; ValueError when not compiled."""
    joint, short = model.joints[j], model.joints[j].shortname()
    what = f"joint {model.names[j]!r} ({short})"
    S = np.asarray(data.joints[j].S, dtype=float).reshape(6, -1)
    if short == "JointModelFreeFlyer":
        return FREE_FLYER, np.zeros(3), 1.0, 0.0
    if short == "JointModelMimic":
        mimic = joint.extract()
        scale, offset = float(mimic.scaling), float(mimic.offset)
        copied = [k for k in range(1, model.njoints) if model.joints[k].idx_q == mimic.idx_q]
        if not copied or model.joints[copied[0]].nq != 1:
            raise ValueError(f"{what}: copies a joint that is not a 1-DoF joint")
        if scale != 0.0:  # S = multiplier * the joint's own axis
            kind, axis = _motion_axis(S[:, 0] / scale, what)
            return kind, axis, scale, offset
        motion = pin.log6(data.joints[j].M).vector  # a constant placement (value = offset)
        if offset == 0.0 or not np.any(motion):
            return REVOLUTE, np.array([0.0, 0.0, 1.0]), 0.0, 0.0
        kind, axis = _motion_axis(motion / offset, what)
        return kind, axis, 0.0, offset
    if joint.nv != 1 or joint.nq not in (1, 2):
        raise ValueError(what)
    kind, axis = _motion_axis(S[:, 0], what)
    if joint.nq == 2:
        if kind != REVOLUTE:
            raise ValueError(what)
        return CIRCLE, axis, 1.0, 0.0
    return kind, axis, 1.0, 0.0


class CompiledBackend:
    """Compiled kinematics of one Pinocchio model (see the module doc for the scope)."""

    name = "compiled"
    engine = EngineChoice("compiled", "chosen by the caller")

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.nq, self.nv = int(model.nq), int(model.nv)
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        joints = list(range(1, model.njoints))
        index = {j: k for k, j in enumerate(joints)}
        rows = [_joint(model, data, j) for j in joints]
        n = len(joints)
        self._index = index
        self.parent = np.array([index.get(int(model.parents[j]), -1) for j in joints], np.int64)
        self.rot = np.array([model.jointPlacements[j].rotation for j in joints]).reshape(n, 3, 3)
        self.trans = np.array([model.jointPlacements[j].translation for j in joints]).reshape(n, 3)
        self.kind = np.array([r[0] for r in rows], np.int64)
        self.axis = np.array([r[1] for r in rows]).reshape(n, 3)
        self.scale = np.array([r[2] for r in rows])
        self.offset = np.array([r[3] for r in rows])
        self.qi = np.array([model.joints[j].idx_q for j in joints], np.int64)
        self.vi = np.array([model.joints[j].idx_v for j in joints], np.int64)
        mass = np.array([model.inertias[j].mass for j in joints])
        lever = np.array([model.inertias[j].lever for j in joints]).reshape(n, 3)
        self.gravity_vector = np.array(model.gravity.linear, dtype=float)
        self._chains: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._tree = self._pack(np.arange(n, dtype=np.int64), self.parent)
        self._body = np.column_stack([mass, lever])

    def joint_row(self, joint: int) -> int:
        """The row of Pinocchio joint ``joint`` in the kernels' frame array (the base,
        joint 0, is the last row)."""
        return self._index[joint] if joint > 0 else len(self._index)

    @property
    def tree(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(ints, flts, body, gravity) of the whole tree, for kernels built on
        :func:`toolkit.kinematics.kernels.gravity_row` (read-only)."""
        return (*self._tree, self._body, self.gravity_vector)

    def _pack(self, rows: np.ndarray, parents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(ints, flts) of :mod:`toolkit.kinematics.kernels` for the joint rows ``rows``."""
        n = len(rows)
        ints = np.empty((n, 6), np.int64)
        ints[:, 0] = np.where(parents < 0, n, parents)
        ints[:, 1], ints[:, 2], ints[:, 3] = self.kind[rows], self.qi[rows], self.vi[rows]
        # shortcuts of the kernels' frames(): an axis along +-x, +-y or +-z (its index, else
        # -1) and a placement without rotation (1, else 0); exact tests, same results
        axis = self.axis[rows]
        principal = (np.count_nonzero(axis, axis=1) == 1) & (np.abs(axis).max(axis=1) == 1.0)
        ints[:, 4] = np.where(principal, np.abs(axis).argmax(axis=1), -1)
        ints[:, 5] = (self.rot[rows] == np.eye(3)).all(axis=(1, 2))
        flts = np.empty((n, 17))
        flts[:, 0:9] = self.rot[rows].reshape(n, 9)
        flts[:, 9:12] = self.trans[rows]
        flts[:, 12:15] = self.axis[rows]
        flts[:, 15], flts[:, 16] = self.scale[rows], self.offset[rows]
        return ints, flts

    def chain(self, frame_id: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The kernels' description of the path from the base to a frame."""
        found = self._chains.get(frame_id)
        if found is not None:
            return found
        frame = self.model.frames[frame_id]
        path = []
        j = int(frame.parentJoint)
        while j > 0:
            path.append(self._index[j])
            j = int(self.model.parents[j])
        path.reverse()
        rows = np.array(path, np.int64)
        ints, flts = self._pack(rows, np.arange(len(path), dtype=np.int64) - 1)
        tip = np.concatenate(
            [np.asarray(frame.placement.rotation).ravel(), np.asarray(frame.placement.translation)]
        )
        chain = (ints, flts, tip)
        self._chains[frame_id] = chain
        return chain

    # ------------------------------------------------------------------ batches
    def fk(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        Q = np.ascontiguousarray(Q, dtype=float)
        return np.asarray(_kernels.fk_batch(parallel(len(Q)), Q, *self.chain(frame_id)))

    def jacobian(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        Q = np.ascontiguousarray(Q, dtype=float)
        chain = self.chain(frame_id)
        return np.asarray(_kernels.jacobian_batch(parallel(len(Q)), Q, *chain, self.nv))

    def gravity(self, Q: np.ndarray) -> np.ndarray:
        Q = np.ascontiguousarray(Q, dtype=float)
        return np.asarray(_kernels.gravity_batch(parallel(len(Q)), Q, *self.tree, self.nv))


def select(model: pin.Model, prefer: str | None = None) -> tuple[Backend, EngineChoice]:
    """The back end of ``model``: compiled when it covers every joint, else Pinocchio.

    ``prefer``: None (that rule), ``"pinocchio"`` (the reference, always possible) or
    ``"compiled"`` (an :class:`~toolkit.errors.UnsupportedModelError` naming the joint it
    cannot take)."""
    if prefer not in (None, "compiled", "pinocchio"):
        raise UnsupportedModelError(f"backend must be 'compiled', 'pinocchio' or None: {prefer!r}")
    if prefer == "pinocchio":
        return _chosen(PinocchioBackend(model), "chosen by the caller")
    try:
        backend = CompiledBackend(model)
    except ValueError as exc:
        if prefer == "compiled":
            raise UnsupportedModelError(f"the compiled back end cannot take {exc}") from None
        return _chosen(PinocchioBackend(model), f"unsupported {exc}")
    kinds = sorted({("revolute", "prismatic", "continuous", "free-flyer")[k] for k in backend.kind})
    if any(model.joints[j].shortname() == "JointModelMimic" for j in range(1, model.njoints)):
        kinds.append("mimic")
    return _chosen(backend, "joints: " + ", ".join(kinds))


def _chosen(backend: PinocchioBackend | CompiledBackend, why: str) -> tuple[Backend, EngineChoice]:
    backend.engine = EngineChoice(backend.name, why)
    return backend, backend.engine
