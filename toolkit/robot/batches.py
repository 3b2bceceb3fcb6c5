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
    branch_kernels,
    branches,
    loops,
    nearest_rotations,
)
from ..ik import structure as arm
from ..kinematics import Backend, CompiledBackend, EngineChoice, parallel
from .branches import ROUGH, packed_family

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

        def _chain_limits(self, chain: arm.Chain) -> tuple[np.ndarray, np.ndarray]: ...

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
        moved = np.zeros(len(poses))
        if not position_only:  # float32 or rounded rotations: solved at the nearest ones
            poses, moved = nearest_rotations(poses)
        if not found.compiled:
            return self._looped(poses, fid, (chain, found), tol, q_rest, moved)
        spread = parallel(8 * len(poses))
        Ts = np.ascontiguousarray(poses)
        solve = analytic_kernels.KERNELS[found.family][1]
        rest = self.ik_state.mid if q_rest is None else self.check_q(q_rest)
        cols = list(chain.columns)
        pref = np.ascontiguousarray(self.angles(rest)[cols], dtype=float)
        exact = arm.exact_for(found, tol)
        if not found.reversed:
            A, roots, counts, free = solve(spread, *packed_family(chain, found), Ts, not exact,
                                           pref)  # fmt: skip
        else:  # solved on the chain seen from its frame, at T^-1, and turned back
            packed = packed_family(arm.reverse(chain), found)
            A, roots, counts, free = solve(spread, *packed, np.linalg.inv(Ts), not exact,
                                           np.ascontiguousarray(-pref[::-1]))  # fmt: skip
            A = np.ascontiguousarray(-A[:, :, ::-1])
            free = branches.reverse_bits(free, len(chain.joints))
        qcol = np.array([self.model.joints[j].idx_q for j in chain.joints], np.int64)
        circle = np.array([self.model.joints[j].nq == 2 for j in chain.joints])
        lo, hi = self._chain_limits(chain)
        ints, flts, tip_pl = self._compiled_chain(fid)
        wide = np.full(len(lo), np.inf)  # polished from the wrapped angles, as ik_all
        Q, pos, rot = analytic_kernels.verify_batch(
            spread, A, counts, np.ascontiguousarray(rest, dtype=float), qcol, circle,
            -wide if not exact else lo, wide if not exact else hi, ints, flts, tip_pl, Ts,
        )  # fmt: skip
        live = np.arange(8)[None, :] < counts[:, None]
        if not exact:
            Q, counts, roots, live, free = self._polished(Q, counts, roots, live, free, poses,
                                                          fid, tol)  # fmt: skip
            at = np.argwhere(live)
            pos, rot = (np.full(live.shape, np.nan) for _ in range(2))
            pos[live], rot[live] = self._errors(Q[live], poses[at[:, 0]], fid)
        else:  # rounding at a singular pose or a tangent: those rows polished
            self._polish_rough(Q, pos, rot, live, poses, fid, tol, chain)
        if not exact:
            Q[live] = self._lowest_turns(Q[live], chain)
        ok = np.zeros(live.shape, dtype=bool)
        ok[live] = (pos[live] <= tol) & (rot[live] <= tol)
        ok[live] &= np.asarray(self.ik_state.valid_rows(Q[live]), dtype=bool)
        free[~live] = 0
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not exact, free,
                                         moved)  # fmt: skip

    def _lowest_turns(self, Q: np.ndarray, chain: arm.Chain) -> np.ndarray:
        """Rows Q (M, nq) with each revolute chain joint at the lowest of its turns within its
        limits (wrapped to [-pi, pi) where none fits): one of the rows ``ik_all`` lists."""
        if not len(Q):
            return Q
        A = self.angles(Q)
        lo, hi = self._chain_limits(chain)
        cols = np.array(chain.columns)
        turn = ~chain.sliding
        x = A[:, cols[turn]]
        x = (x + np.pi) % branch_kernels.TWO_PI - np.pi
        lo, hi = lo[turn], hi[turn]
        bounded = np.isfinite(lo) & np.isfinite(hi)
        with np.errstate(invalid="ignore"):
            first = np.ceil((lo - branch_kernels.EDGE - x) / branch_kernels.TWO_PI)
            fits = bounded & (np.floor((hi + branch_kernels.EDGE - x) / branch_kernels.TWO_PI)
                              >= first)  # fmt: skip
        A[:, cols[turn]] = np.where(fits, x + branch_kernels.TWO_PI * first, x)
        return self.q_from_angles(A)

    def _polish_rough(
        self, Q: np.ndarray, pos: np.ndarray, rot: np.ndarray, live: np.ndarray,
        poses: np.ndarray, fid: int, tol: float, chain: arm.Chain,
    ) -> None:  # fmt: skip
        """Rows of an exact arm that miss ``tol`` by rounding only (no more than
        :data:`~toolkit.robot.branches.ROUGH`) polished on the real model in place."""
        with np.errstate(invalid="ignore"):
            rough = live & ((pos > tol) | (rot > tol)) & (pos <= ROUGH) & (rot <= ROUGH)
        if not rough.any():
            return
        at = np.argwhere(rough)
        opts = IKOptions(tol=tol, max_iter=50, restarts=0)
        rows = np.ascontiguousarray(poses[at[:, 0]])
        done, _ = self.ik_loop.solve_poses(fid, rows, np.ones(6), Q[rough], self.ik_state, opts, 0)
        Q[rough] = self._lowest_turns(done, chain)
        pos[rough], rot[rough] = self._errors(Q[rough], rows, fid)

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
        free: np.ndarray, poses: np.ndarray, fid: int, tol: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """The branches of an arm near its family polished on the real model in one compiled
        batch; a branch that did not converge, or became another, is dropped."""
        at = np.argwhere(live)
        if not len(at):
            return Q, counts, roots, live, free
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
        free = np.take_along_axis(free, order, axis=1)
        keep = np.take_along_axis(keep, order, axis=1)
        Q[~keep] = np.nan
        roots[~keep] = -1
        free[~keep] = 0
        return Q, keep.sum(axis=1), roots, keep, free

    def _looped(
        self, poses: np.ndarray, fid: int, structure: tuple[arm.Chain, arm.Structure],
        tol: float, q_rest: ArrayLike | None, moved: np.ndarray,
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """:meth:`ik_all_batch` of a family without a batch kernel: :meth:`ik_all` per
        target, one row per branch: its first row within the limits (each revolute joint
        at its lowest turn there), else its first row."""
        chain, found = structure
        frame = self.model.frames[fid].name
        places = found.family in analytic.POSITION_FAMILIES
        answers = []
        for T in poses:
            r = self.ik_all(T[:3, 3] if places else T, frame=frame, tol=tol, q_rest=q_rest)
            first: dict[int, int] = {}
            for i, (b, inside) in enumerate(zip(r.branch.tolist(), r.within_limits.tolist(),
                                                strict=True)):  # fmt: skip
                if b not in first or (inside and not r.within_limits[first[b]]):
                    first[b] = i
            answers.append((r, list(first.values())))
        N, B = len(poses), max([len(ix) for _, ix in answers], default=0)
        Q = np.full((N, B, self.model.nq), np.nan)
        pos, rot = np.full((N, B), np.nan), np.full((N, B), np.nan)
        roots = np.full((N, B, 3), -1, np.int64)
        free = np.zeros((N, B), np.int64)
        counts = np.array([len(ix) for _, ix in answers], np.int64)
        for n, (r, ix) in enumerate(answers):
            if ix:
                Q[n, : len(ix)] = r.q[ix]
                pos[n, : len(ix)] = r.position_error[ix]
                rot[n, : len(ix)] = r.orientation_error[ix]
                roots[n, : len(ix)] = [_roots_of(r.labels[i]) for i in ix]
                free[n, : len(ix)] = [sum(1 << chain.names.index(j) for j in r.free[i])
                                      for i in ix]  # fmt: skip
        live = ~np.isnan(pos)
        ok = np.zeros((N, B), dtype=bool)
        ok[live] = (pos[live] <= tol) & (rot[live] <= tol)
        ok[live] &= np.asarray(self.ik_state.valid_rows(Q[live]), dtype=bool)
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not found.exact,
                                         free, moved)  # fmt: skip
