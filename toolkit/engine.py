"""The kinematics engine: one interface, two back ends.

* **compiled** (:class:`ChainEngine`): for every model whose moving joints are 1-DoF
  revolute or prismatic joints (aligned or not), or mimic joints driven by them: all the
  catalogue models (the ``bending`` model's mimic joints included) and arms such as UR,
  Panda, Z1, SO-101. Joint placements, axes, mimic ratios and inertias are read from the
  Pinocchio model once; forward kinematics, frame Jacobians, generalized gravity and the
  IK loop then run as numba kernels (:mod:`toolkit._kernels`), batches over all cores.
* **pinocchio**: everything else (continuous joints stored as cos/sin, free-flyer,
  spherical or planar joints), with identical results and API.

:func:`select` chooses; ``Robot.engine`` says which one a robot uses and why. Pinocchio
stays the reference: the tests compare the compiled FK, Jacobian and gravity with it to
1e-12 on every catalogue model and example robot. The kernels are compiled on first use
and cached on disk (numba's ``cache=True``): the first run in a fresh installation costs
a few seconds per kernel, later processes load them in well under a second.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from .ik import DAMPING, LAMBDA_MIN, STALL, IKOptions, PoseTask, SolverState

__all__ = ["EngineChoice"]  # select() and ChainEngine are the core's (Robot uses them)

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


class EngineChoice(NamedTuple):
    """The back end a robot uses, and why."""

    name: str  # "compiled" or "pinocchio"
    reason: str


def _numeric_motion(model: pin.Model, j: int, scale: float) -> tuple[int, np.ndarray]:
    """(kind, axis) of a joint read off Pinocchio's own kinematics (used for mimic joints,
    whose inner joint type the Python API does not expose)."""
    data = model.createData()
    q = pin.neutral(model)
    placement = model.jointPlacements[j]
    pin.forwardKinematics(model, data, q)
    m0 = placement.actInv(data.liMi[j])
    q = q.copy()
    step = 0.5
    q[model.joints[j].idx_q] += step
    pin.forwardKinematics(model, data, q)
    m1 = placement.actInv(data.liMi[j])
    delta = m0.actInv(m1)
    turn = np.asarray(pin.log3(delta.rotation))
    if np.linalg.norm(turn) > 1e-9:
        return 0, turn / (step * scale)
    return 1, np.asarray(delta.translation) / (step * scale)


def _joint(model: pin.Model, j: int) -> tuple[int, np.ndarray, float, float] | None:
    """(kind, unit axis, scale, offset) of a supported joint, None otherwise."""
    joint = model.joints[j]
    short = joint.shortname()
    if short == "JointModelMimic":
        mimic = joint.extract()
        scale, offset = float(mimic.scaling), float(mimic.offset)
        if scale == 0.0:
            return None
        kind, axis = _numeric_motion(model, j, scale)
        return kind, axis / np.linalg.norm(axis), scale, offset
    if joint.nq != 1 or joint.nv != 1:
        return None
    for prefix, kind in (("JointModelR", 0), ("JointModelP", 1)):
        if short.startswith(prefix):
            tail = short[len(prefix) :]
            if tail in _AXES:
                return kind, np.array(_AXES[tail]), 1.0, 0.0
            if tail in ("evoluteUnaligned", "rismaticUnaligned"):
                axis = np.asarray(joint.extract().axis, dtype=float)
                return kind, axis / np.linalg.norm(axis), 1.0, 0.0
    return None


class ChainEngine:
    """Compiled kinematics of one Pinocchio model (see the module doc for the scope)."""

    name = "compiled"

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.nq, self.nv = int(model.nq), int(model.nv)
        joints = list(range(1, model.njoints))
        index = {j: k for k, j in enumerate(joints)}
        rows = []
        for j in joints:
            spec = _joint(model, j)
            if spec is None:
                raise ValueError(f"joint {model.names[j]!r} ({model.joints[j].shortname()})")
            rows.append(spec)
        n = len(joints)
        self._joints = joints
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
        self.mass = np.array([model.inertias[j].mass for j in joints])
        self.lever = np.array([model.inertias[j].lever for j in joints]).reshape(n, 3)
        self.gravity_vector = np.array(model.gravity.linear, dtype=float)
        self._chains: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._tree = self._pack(np.arange(n, dtype=np.int64), self.parent)
        self._body = np.column_stack([self.mass, self.lever])

    def _pack(self, rows: np.ndarray, parents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(ints, flts) of :mod:`toolkit._kernels` for the joint rows ``rows``."""
        n = len(rows)
        ints = np.empty((n, 4), np.int64)
        ints[:, 0] = np.where(parents < 0, n, parents)
        ints[:, 1], ints[:, 2], ints[:, 3] = self.kind[rows], self.qi[rows], self.vi[rows]
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

    # ------------------------------------------------------------------ inverse kinematics
    def solve(
        self, task: PoseTask, q_start: np.ndarray, state: SolverState, opts: IKOptions
    ) -> tuple[np.ndarray, int, int]:
        """The IK loop of :mod:`toolkit.ik`, compiled: (best q, iterations, last attempt).

        With a ``timeout`` the attempts run in growing chunks and the clock is read between
        chunks; seeding by (seed, attempt) keeps the answer independent of the chunking.
        """
        from . import _ik_kernels

        chain = self.chain(task.frame_id)
        bounds = (state.clip_lower, state.clip_upper, state.sample_lower, state.sample_upper)
        settings = (DAMPING, LAMBDA_MIN, STALL)
        head = (task.rotation, task.position, task.weights, task.use_rot, q_start, bounds)
        seed, last = _seed(opts.seed), opts.restarts + 1
        if opts.timeout is None:
            q, _, iters, attempt, _ = _ik_kernels.solve(
                *head, opts.tol, opts.max_iter, (0, last), seed, settings, chain
            )
            return q, int(iters), int(attempt)
        deadline = time.perf_counter() + opts.timeout
        best_q, best_cost, total, start, chunk = q_start, np.inf, 0, 0, 2
        attempt = 0
        while start < last:
            stop = min(last, start + chunk)
            q, cost, iters, attempt, ok = _ik_kernels.solve(
                *head, opts.tol, opts.max_iter, (start, stop), seed, settings, chain
            )
            total += int(iters)
            if cost < best_cost:
                best_q, best_cost = q, cost
            if ok or time.perf_counter() > deadline:
                break
            start, chunk = stop, min(chunk * 2, 64)
        return best_q, total, int(attempt)

    # ------------------------------------------------------------------ batches
    def fk(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        """Poses (N, 4, 4) of a frame at configurations Q (N, nq), checked by the caller."""
        from . import _kernels

        return np.asarray(_kernels.fk_batch(np.ascontiguousarray(Q), *self.chain(frame_id)))

    def jacobian(self, Q: np.ndarray, frame_id: int) -> np.ndarray:
        """Frame Jacobians (N, 6, nv), LOCAL_WORLD_ALIGNED."""
        from . import _kernels

        Q = np.ascontiguousarray(Q)
        return np.asarray(_kernels.jacobian_batch(Q, *self.chain(frame_id), self.nv))

    def gravity(self, Q: np.ndarray) -> np.ndarray:
        """Generalized gravity g(q) (N, nv)."""
        from . import _kernels

        ints, flts = self._tree
        Q = np.ascontiguousarray(Q)
        return np.asarray(
            _kernels.gravity_batch(Q, ints, flts, self._body, self.gravity_vector, self.nv)
        )

    def backlash(
        self,
        Q: np.ndarray,
        start: np.ndarray,
        law: np.ndarray,
        tol: float,
        max_iter: int,
        torque_tol: float,
    ) -> tuple[np.ndarray, ...]:
        """[P1]'s fixed point for commands Q (N, n): see :func:`toolkit._kernels.backlash_batch`."""
        from . import _kernels

        tree = (*self._tree, self._body, self.gravity_vector)
        kernel = _kernels.backlash_batch if len(Q) >= 64 else _kernels.backlash_serial
        Q, start = np.ascontiguousarray(Q), np.ascontiguousarray(start)
        return tuple(kernel(Q, start, law, tol, max_iter, torque_tol, tree))


def _seed(seed: int | None) -> int:
    """A 31-bit kernel seed (None: a fresh one from the operating system)."""
    if seed is None:
        return int(np.random.SeedSequence().entropy % (2**31))  # type: ignore[operator]
    return int(seed % (2**31))


def select(model: pin.Model) -> tuple[ChainEngine | None, EngineChoice]:
    """The compiled engine for ``model`` when it can take it, else None; and the choice."""
    if model.nq != model.nv:
        return None, EngineChoice(
            "pinocchio", "continuous, free-flyer or spherical joints (nq != nv)"
        )
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - numba is a dependency
        return None, EngineChoice("pinocchio", "numba is not installed")
    try:
        engine = ChainEngine(model)
    except ValueError as exc:
        return None, EngineChoice("pinocchio", f"unsupported joint {exc}")
    return engine, EngineChoice("compiled", "1-DoF revolute/prismatic (and mimic) joints")
