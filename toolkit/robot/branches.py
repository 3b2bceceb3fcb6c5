"""A robot's analytic IK (mixed into :class:`~toolkit.robot.Robot`): its structure, every
branch of a target (``ik_all``), and the branch ``ik(..., method="analytic")`` answers."""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..ik import (
    IKOptions,
    IKResult,
    PoseTask,
    SolverState,
    analytic,
    branches,
    loops,
    solver,
)
from ..ik import structure as arm

__all__ = ["BranchQueries"]

_LOCK = threading.Lock()


def _same_turns(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two angle vectors are equal up to whole turns (to 1e-9 rad)."""
    return bool(np.all(np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi) < 1e-9))


class BranchQueries:
    """The analytic IK of :class:`~toolkit.robot.Robot` (mixed into it)."""

    if TYPE_CHECKING:  # Robot's, declared for the type checker
        import pinocchio as pin

        model: pin.Model
        name: str
        tip: str

        @property
        def lower(self) -> np.ndarray: ...

        @property
        def upper(self) -> np.ndarray: ...

        def frame_id(self, frame: str | None) -> int: ...

        def check_q(self, q: ArrayLike, *, batch: bool = False) -> np.ndarray: ...

        def angles(self, q: ArrayLike) -> np.ndarray: ...

        def q_from_angles(self, values: ArrayLike) -> np.ndarray: ...

        @property
        def ik_state(self) -> SolverState: ...

        @property
        def ik_loop(self) -> loops.IKLoop: ...

    def _chain_structure(self, fid: int) -> tuple[arm.Chain | None, arm.Structure]:
        cache: dict[int, tuple[arm.Chain | None, arm.Structure]]
        cache = self.__dict__.setdefault("_structures", {})
        with _LOCK:
            found = cache.get(fid)
            if found is None:
                try:
                    chain = arm.chain_of(self.model, fid)
                    found = (chain, arm.find_structure(chain))
                except UnsupportedModelError as exc:
                    names = (self.model.frames[fid].name,)
                    found = (None, arm.Structure(None, names, str(exc)))
                cache[fid] = found
        return found

    @property
    def structure(self) -> arm.Structure:
        """What makes the IK to the tip solvable in closed form: the family, its joints and
        why (or why none fits); see :func:`toolkit.ik.structure.find_structure`."""
        return self._chain_structure(self.frame_id(None))[1]

    def structure_of(self, frame: str | None = None) -> arm.Structure:
        """:attr:`structure` for another frame."""
        return self._chain_structure(self.frame_id(frame))[1]

    def ik_all(
        self, target: object, *, frame: str | None = None, tol: float = 1e-10,
        q_rest: ArrayLike | None = None,
    ) -> branches.IKAllResult:  # fmt: skip
        """Every IK branch of a 4x4 target pose, by subproblem decomposition
        (:mod:`toolkit.ik.analytic`), each verified by an independent forward kinematics to
        ``tol`` [m and rad] and repeated for every equivalent angle (q + 2 pi k) within the
        joint limits. Joints outside the chain keep their value in ``q_rest`` (default:
        the middle of their range). An arm only near its family (a calibrated arm) has
        every branch polished on the real model (``polished``). An
        :class:`~toolkit.errors.UnsupportedModelError` says why when the arm has no
        structure (then use :meth:`ik`)."""
        fid = self.frame_id(frame)
        tol = _validate.number(tol, "tol", lower=0.0, strict=True, upper=0.01)
        task = PoseTask.from_target(fid, target, None)
        if not task.weights[3:].any():
            raise InvalidParameterError("ik_all needs a 4x4 target pose, not a position")
        chain, found = self._chain_structure(fid)
        if chain is None or found.family is None or found.points is None:
            raise UnsupportedModelError(
                f"{self.name}: no analytic IK to {self.model.frames[fid].name}: {found.reason}; "
                "use ik() (numeric)"
            )
        state = self.ik_state
        rest = self.angles(state.mid if q_rest is None else self.check_q(q_rest))
        ok = analytic.EXACT_ONLY if found.exact else analytic.NEAR_OK
        raw = analytic.FAMILIES[found.family](chain, found.points, task.pose, ok)
        cols = list(chain.columns)
        kept: list[tuple[np.ndarray, str]] = []
        lost = 0
        for angles, label in raw:
            values = rest.copy()
            values[cols] = np.remainder(angles + np.pi, 2 * np.pi) - np.pi  # in (-pi, pi]
            q = self.q_from_angles(values)
            if not found.exact:  # near the family only: polish on the real model
                opts = IKOptions(tol=tol, max_iter=50, restarts=0)
                res = loops.solve_ik(self.ik_loop, state, task, q, opts)
                if not (res.position_error <= tol and res.orientation_error <= tol):
                    lost += 1
                    continue
                q = res.q
            angles = self.angles(q)
            if any(_same_turns(angles[cols], a[cols]) for a, _ in kept):
                lost += not found.exact  # two polished branches that became one
                continue
            kept.append((angles, label))
        return self._verified_branches(
            kept, cols, self._chain_limits(chain), task, tol, found, lost
        )

    def _chain_limits(self, chain: arm.Chain) -> tuple[np.ndarray, np.ndarray]:
        """Per chain joint, its angle limits (unlimited for a continuous joint)."""
        lo, hi = [], []
        for j in chain.joints:
            joint = self.model.joints[j]
            one = joint.nq == 1
            lo.append(float(self.lower[joint.idx_q]) if one else -np.inf)
            hi.append(float(self.upper[joint.idx_q]) if one else np.inf)
        return np.array(lo), np.array(hi)

    def _verified_branches(
        self, kept: list[tuple[np.ndarray, str]], cols: list[int],
        limits: tuple[np.ndarray, np.ndarray], task: PoseTask, tol: float,
        found: arm.Structure, lost: int,
    ) -> branches.IKAllResult:  # fmt: skip
        """Each branch verified once (turns of a joint do not move the frame), then
        repeated for every equivalent angle within the limits."""
        state = self.ik_state
        rows, labels, ok, pos, rot = [], [], [], [], []
        for angles, label in kept:
            check = solver.verify(state, task, self.q_from_angles(angles), tol)
            reached = check.position_error <= tol and check.orientation_error <= tol
            chosen = branches.turns(angles[cols], *limits)
            values = np.repeat(angles[None], len(chosen), axis=0)
            values[:, cols] = chosen
            rows.append(values)
            labels += [label] * len(chosen)
            ok += [reached] * len(chosen)
            pos += [check.position_error] * len(chosen)
            rot += [check.orientation_error] * len(chosen)
        Q = self.q_from_angles(np.concatenate(rows)) if rows else np.zeros((0, self.model.nq))
        inside = np.asarray(state.valid_rows(Q), dtype=bool).reshape(-1)
        return branches.IKAllResult(
            Q, np.array(ok, dtype=bool) & inside, inside, labels, np.array(pos),
            np.array(rot), found, not found.exact, lost,
        )  # fmt: skip

    def _analytic_ik(
        self, task: PoseTask, q0: np.ndarray | None, tol: float, checker: object = None
    ) -> IKResult | None:
        """The verified branch nearest q0 (default: mid-range), collision-free when a
        checker is given; None when no branch succeeds."""
        state = self.ik_state
        start = state.mid if q0 is None else q0
        found = self.ik_all(task.pose, frame=self.model.frames[task.frame_id].name, tol=tol,
                            q_rest=start)  # fmt: skip
        order = np.argsort([np.abs(self.angles(q) - self.angles(start)).sum() for q in found.q])
        for i in order.tolist():
            if not found.success[i]:
                continue
            q = found.q[i]
            if checker is not None and checker.first_collision(q) is not None:  # type: ignore[attr-defined]
                continue
            return solver.verify(state, task, q, tol)
        return None
