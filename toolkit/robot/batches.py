"""Every IK branch of N targets at once (``Robot.ik_all_batch``, mixed into
:class:`~toolkit.robot.Robot`): the compiled family's kernels over the cores, the other
families target by target."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..ik import (
    IKOptions,
    SolverState,
    analytic,
    analytic_kernels,
    batch_targets,
    branches,
    loops,
)
from ..ik import structure as arm
from ..kinematics import Backend, CompiledBackend, EngineChoice, parallel
from .branches import packed_family

__all__ = ["BranchBatches"]

_ROOTS = ("shoulder", "elbow", "wrist")


def _roots_of(label: str) -> list[int]:
    """(shoulder, elbow, wrist) roots of a branch label: 0 for +, 1 for -, -1 for none."""
    out = []
    for name in _ROOTS:
        at = label.find(name + " ")
        sign = label[at + len(name) + 1 : at + len(name) + 2] if at >= 0 else ""
        out.append(0 if sign == "+" else 1 if sign == "-" else -1)
    return out


class BranchBatches:
    """The batch analytic IK of :class:`~toolkit.robot.Robot` (mixed into it)."""

    if TYPE_CHECKING:  # Robot's and BranchQueries', declared for the type checker
        import pinocchio as pin

        model: pin.Model
        name: str

        def frame_id(self, frame: str | None) -> int: ...

        def check_q(self, q: ArrayLike, *, batch: bool = False) -> np.ndarray: ...

        def angles(self, q: ArrayLike) -> np.ndarray: ...

        def q_from_angles(self, values: ArrayLike) -> np.ndarray: ...

        def ik_all(
            self, target: object, *, frame: str | None = None, tol: float = 1e-10,
            q_rest: ArrayLike | None = None, lock: object = None,
        ) -> branches.IKAllResult: ...  # fmt: skip

        def _chain_structure(
            self, fid: int, lock: tuple[tuple[int, float], ...] = ()
        ) -> tuple[arm.Chain | None, arm.Structure]: ...

        @property
        def ik_state(self) -> SolverState: ...

        @property
        def ik_loop(self) -> loops.IKLoop: ...

        @property
        def kinematics(self) -> Backend: ...

        engine: EngineChoice

    def ik_all_batch(
        self, targets: ArrayLike, *, frame: str | None = None, tol: float = 1e-10,
        q_rest: ArrayLike | None = None,
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """Every branch of N target poses (N, 4, 4) at once (N positions (N, 3) for a
        3-joint arm; see :class:`toolkit.ik.IKAllBatchResult`): compiled and spread over the
        cores for the compiled families (:data:`toolkit.ik.structure.COMPILED`), whose
        branches of an arm only near one are polished on the real model in one compiled
        batch (branches that merge listed once); the other families target by target
        through :meth:`ik_all`, one row per branch."""
        fid = self.frame_id(frame)
        tol = _validate.number(tol, "tol", lower=0.0, strict=True, upper=0.01)
        poses, position_only = batch_targets(targets)
        chain, found = self._chain_structure(fid)
        if chain is None or found.family is None or found.points is None:
            raise UnsupportedModelError(
                f"{self.name}: no analytic IK to {self.model.frames[fid].name}: {found.reason}; "
                "use ik_batch() (numeric)"
            )
        places = found.family in analytic.POSITION_FAMILIES
        if places != position_only:
            raise InvalidParameterError(
                f"ik_all_batch of {self.name} ({found.family}) needs "
                f"{'(N, 3) target positions' if places else '(N, 4, 4) target poses'}"
            )
        if not found.compiled:
            return self._looped(poses, fid, (chain, found), tol, q_rest)
        spread = parallel(8 * len(poses))
        Ts = np.ascontiguousarray(poses)
        solve = analytic_kernels.KERNELS[found.family][1]
        if not found.reversed:
            A, roots, counts = solve(spread, *packed_family(chain, found), Ts, not found.exact)
        else:  # solved on the chain seen from its frame, at T^-1, and turned back
            packed = packed_family(arm.reverse(chain), found)
            A, roots, counts = solve(spread, *packed, np.linalg.inv(Ts), not found.exact)
            A = np.ascontiguousarray(-A[:, :, ::-1])
        rest = self.ik_state.mid if q_rest is None else self.check_q(q_rest)
        qcol = np.array([self.model.joints[j].idx_q for j in chain.joints], np.int64)
        circle = np.array([self.model.joints[j].nq == 2 for j in chain.joints])
        ints, flts, tip_pl = self._compiled_chain(fid)
        Q, pos, rot = analytic_kernels.verify_batch(
            spread, A, counts, np.ascontiguousarray(rest, dtype=float), qcol, circle, ints,
            flts, tip_pl, Ts,
        )  # fmt: skip
        live = np.arange(8)[None, :] < counts[:, None]
        if not found.exact:
            Q, counts, roots, live = self._polished(Q, counts, roots, live, poses, fid, tol)
            at = np.argwhere(live)
            pos, rot = (np.full(live.shape, np.nan) for _ in range(2))
            pos[live], rot[live] = self._errors(Q[live], poses[at[:, 0]], fid)
        ok = np.zeros(live.shape, dtype=bool)
        ok[live] = (pos[live] <= tol) & (rot[live] <= tol)
        ok[live] &= np.asarray(self.ik_state.valid_rows(Q[live]), dtype=bool)
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not found.exact)

    def _compiled_chain(self, fid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        backend = self.kinematics
        if not isinstance(backend, CompiledBackend):
            raise UnsupportedModelError(
                f"{self.name}: ik_all_batch needs the compiled kinematics back end "
                f"({self.engine.reason})"
            )
        return backend.chain(fid)

    def _errors(self, Q: np.ndarray, poses: np.ndarray, fid: int) -> tuple[np.ndarray, np.ndarray]:
        """Position [m] and orientation [rad] errors of rows Q (M, nq) against poses (M, 4, 4),
        by the kinematics back end's forward kinematics (the angle from the chord, exact
        near 0)."""
        F = self.kinematics.fk(Q, fid) if len(Q) else np.zeros((0, 4, 4))
        pos = np.linalg.norm(F[:, :3, 3] - poses[:, :3, 3], axis=1)
        chord = np.linalg.norm(F[:, :3, :3] - poses[:, :3, :3], axis=(1, 2))
        rot = 2.0 * np.arcsin(np.minimum(1.0, chord / (2.0 * np.sqrt(2.0))))
        return pos, rot

    def _polished(
        self, Q: np.ndarray, counts: np.ndarray, roots: np.ndarray, live: np.ndarray,
        poses: np.ndarray, fid: int, tol: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """The branches of an arm near its family polished on the real model in one compiled
        batch; a branch that did not converge, or became another, is dropped."""
        at = np.argwhere(live)
        if not len(at):
            return Q, counts, roots, live
        opts = IKOptions(tol=tol, max_iter=50, restarts=0)
        Q = Q.copy()
        rows = np.ascontiguousarray(poses[at[:, 0]])
        state = self.ik_state
        Q[live], _ = self.ik_loop.solve_poses(fid, rows, np.ones(6), Q[live], state, opts, 0)
        pos, rot = self._errors(Q[live], poses[at[:, 0]], fid)
        keep = live.copy()
        keep[live] = (pos <= tol) & (rot <= tol)
        N, B = live.shape
        A = np.full((N, B, self.model.nv), np.nan)
        A[live] = self.angles(Q[live])
        keep &= branches.distinct_each(A, np.zeros(self.model.nv, dtype=bool))
        order = np.argsort(~keep, axis=1, kind="stable")  # the kept first, in order
        Q = np.take_along_axis(Q, order[:, :, None], axis=1)
        roots = np.take_along_axis(roots, order[:, :, None], axis=1)
        keep = np.take_along_axis(keep, order, axis=1)
        Q[~keep] = np.nan
        roots[~keep] = -1
        return Q, keep.sum(axis=1), roots, keep

    def _looped(
        self, poses: np.ndarray, fid: int, structure: tuple[arm.Chain, arm.Structure],
        tol: float, q_rest: ArrayLike | None,
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """:meth:`ik_all_batch` of a family without a batch kernel: :meth:`ik_all` per
        target, one row per branch label, each revolute joint's angle in [-pi, pi)."""
        chain, found = structure
        frame = self.model.frames[fid].name
        places = found.family in analytic.POSITION_FAMILIES
        answers = []
        for T in poses:
            r = self.ik_all(T[:3, 3] if places else T, frame=frame, tol=tol, q_rest=q_rest)
            first: dict[str, int] = {}
            for i, label in enumerate(r.labels):
                first.setdefault(label, i)
            answers.append((r, list(first.values())))
        N, B = len(poses), max([len(ix) for _, ix in answers], default=0)
        Q = np.full((N, B, self.model.nq), np.nan)
        pos, rot = np.full((N, B), np.nan), np.full((N, B), np.nan)
        roots = np.full((N, B, 3), -1, np.int64)
        counts = np.array([len(ix) for _, ix in answers], np.int64)
        turn = [c for c, s in zip(chain.columns, chain.sliding, strict=True) if not s]
        for n, (r, ix) in enumerate(answers):
            if ix:
                A = self.angles(r.q[ix])
                A[:, turn] = np.remainder(A[:, turn] + np.pi, 2 * np.pi) - np.pi
                Q[n, : len(ix)] = self.q_from_angles(A)
                pos[n, : len(ix)] = r.position_error[ix]
                rot[n, : len(ix)] = r.orientation_error[ix]
                roots[n, : len(ix)] = [_roots_of(r.labels[i]) for i in ix]
        live = ~np.isnan(pos)
        ok = np.zeros((N, B), dtype=bool)
        ok[live] = (pos[live] <= tol) & (rot[live] <= tol)
        ok[live] &= np.asarray(self.ik_state.valid_rows(Q[live]), dtype=bool)
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not found.exact)
