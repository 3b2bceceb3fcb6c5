"""A robot's analytic IK (mixed into :class:`~toolkit.robot.Robot`): its structure, every
branch of a target (``ik_all``), and the branch ``ik(..., method="analytic")`` answers."""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..ik import (
    IKOptions,
    IKResult,
    PoseTask,
    SolverState,
    analytic,
    analytic_kernels,
    branches,
    loops,
    nearest_rotations,
    solver,
)
from ..ik import structure as arm
from ..kinematics import Backend, EngineChoice, JointLayout
from . import singular

__all__ = ["ROUGH", "BranchQueries", "packed_family"]

ROUGH = 1e-6
"""[m, rad] A branch of an exact arm that misses ``tol`` by no more than this (rounding at
a singular pose or a tangent) is polished on the real model instead of dropped."""

_LOCK = threading.Lock()
_LOCKED_KEPT = 64
"""How many structures with locked joints (one per lock value) a robot keeps."""


def packed_family(
    chain: arm.Chain, found: arm.Structure
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The compiled family's fixed arrays: axes, points, the frame's rotation and position
    at zero."""
    assert found.points is not None
    tip = chain.tip
    return (
        np.ascontiguousarray(chain.axes),
        np.ascontiguousarray(found.points),
        np.ascontiguousarray(tip[:3, :3]),
        np.ascontiguousarray(tip[:3, 3]),
    )


def _label(roots: np.ndarray, wrist: bool = True) -> str:
    """ "shoulder +, elbow -, wrist +" of a branch's roots (blank where one root; no wrist
    for a 5R arm)."""
    key = (*roots.tolist(), wrist)
    label = _LABELS.get(key)
    if label is None:
        signs = ["" if r < 0 else ("+" if r == 0 else "-") for r in key[:3]]
        label = f"shoulder {signs[0]}, elbow {signs[1]}" + (f", wrist {signs[2]}" if wrist else "")
        _LABELS[key] = label
    return label


_LABELS: dict[tuple[int | bool, ...], str] = {}


class BranchQueries:
    """The analytic IK of :class:`~toolkit.robot.Robot` (mixed into it)."""

    if TYPE_CHECKING:  # Robot's, declared for the type checker
        import pinocchio as pin

        model: pin.Model
        name: str
        tip: str
        joints: JointLayout

        @property
        def lower(self) -> np.ndarray: ...

        @property
        def upper(self) -> np.ndarray: ...

        def frame_id(self, frame: str | None) -> int: ...

        def check_q(self, q: ArrayLike, *, batch: bool = False) -> np.ndarray: ...

        def angles(self, q: ArrayLike) -> np.ndarray: ...

        def q_from_angles(self, values: ArrayLike) -> np.ndarray: ...

        def fk(self, q: ArrayLike, frame: str | None = None) -> np.ndarray: ...

        def jacobian(self, q: ArrayLike, frame: str | None = None) -> np.ndarray: ...

        @property
        def ik_state(self) -> SolverState: ...

        @property
        def ik_loop(self) -> loops.IKLoop: ...

        @property
        def kinematics(self) -> Backend: ...

        engine: EngineChoice

    def _chain_structure(
        self, fid: int, lock: tuple[tuple[int, float], ...] = ()
    ) -> tuple[arm.Chain | None, arm.Structure]:
        cache: dict[object, tuple[arm.Chain | None, arm.Structure]]
        cache = self.__dict__.setdefault("_structures", {})
        key: object = fid if not lock else (fid, lock)
        with _LOCK:
            found = cache.get(key)
            if found is None:
                try:
                    chain = arm.chain_of(self.model, fid, dict(lock))
                    found = (chain, arm.find_structure(chain))
                except UnsupportedModelError as exc:
                    names = (self.model.frames[fid].name,)
                    found = (None, arm.Structure(None, names, str(exc)))
                locked = [k for k in cache if isinstance(k, tuple)]
                for old in locked[: max(0, len(locked) + 1 - _LOCKED_KEPT)]:
                    del cache[old]  # a sweep of a locked angle keeps the latest ones only
                cache[key] = found
        return found

    def _locked(self, lock: object) -> tuple[tuple[int, float], ...]:
        """``lock`` ({joint name: angle [rad]}) as sorted (Pinocchio joint id, angle)."""
        if lock is None:
            return ()
        if not isinstance(lock, dict) or not lock:
            raise InvalidParameterError(
                f"lock must be a dict of joint name -> angle [rad], got {lock!r:.80}"
            )
        out = []
        for name, value in lock.items():
            if not isinstance(name, str) or not self.model.existJointName(name):
                raise InvalidParameterError(f"lock: no joint named {name!r} in {self.name}")
            j = int(self.model.getJointId(name))
            angle = _validate.number(value, f"lock[{name!r}] [rad]")
            out.append((j, angle))
        return tuple(sorted(out))

    @property
    def structure(self) -> arm.Structure:
        """What makes the IK to the tip solvable in closed form: the family, its joints and
        why (or why none fits); see :func:`toolkit.ik.structure.find_structure`."""
        return self._chain_structure(self.frame_id(None))[1]

    def structure_of(self, frame: str | None = None, *, lock: object = None) -> arm.Structure:
        """:attr:`structure` for another frame, or with joints locked (``lock``: {joint
        name: angle [rad]}, e.g. the seventh joint of a 7-joint arm)."""
        return self._chain_structure(self.frame_id(frame), self._locked(lock))[1]

    def ik_all(
        self, target: object, *, frame: str | None = None, tol: float = 1e-10,
        q_rest: ArrayLike | None = None, lock: object = None,
    ) -> branches.IKAllResult:  # fmt: skip
        """Every IK branch of a 4x4 target pose (a position for a 3-joint arm), by subproblem
        decomposition
        (:mod:`toolkit.ik.analytic`), each verified by an independent forward kinematics to
        ``tol`` [m and rad] and repeated for every equivalent angle (q + 2 pi k) within the
        joint limits. Joints outside the chain keep their value in ``q_rest`` (default:
        the middle of their range). An arm only near its family (a calibrated arm) has
        every branch polished on the real model (``polished``). An
        :class:`~toolkit.errors.UnsupportedModelError` says why when the arm has no
        structure (then use :meth:`ik`). ``lock`` ({joint name: angle [rad]}) holds joints
        at those angles and solves the others (a 7-joint arm with one joint locked); a sweep
        of a locked joint's angle gives branches along the self-motion."""
        fid = self.frame_id(frame)
        tol = _validate.number(tol, "tol", lower=0.0, strict=True, upper=0.01)
        task = PoseTask.from_target(fid, target, None)
        locked = self._locked(lock)
        chain, found = self._chain_structure(fid, locked)
        if chain is None or found.family is None or found.points is None:
            raise UnsupportedModelError(
                f"{self.name}: no analytic IK to {self.model.frames[fid].name}: {found.reason}; "
                "use ik() (numeric)"
            )
        places = found.family in analytic.POSITION_FAMILIES
        if places == bool(task.weights[3:].any()):
            raise InvalidParameterError(
                f"ik_all of {self.name} ({found.family}) needs a target "
                f"{'position (3,): a 3-joint arm places a point' if places else 'pose (4, 4)'}"
            )
        moved = 0.0
        if not places:  # a float32 or rounded rotation: solved at the nearest rotation
            projected, shift = nearest_rotations(task.pose[None])
            task.pose[:3, :3], moved = projected[0, :3, :3], float(shift[0])
        state = self.ik_state
        rest = self.joints.angles(state.mid if q_rest is None else self.check_q(q_rest), self.name)
        for j, angle in locked:
            rest[self.model.joints[j].idx_v] = angle
        cols = list(chain.columns)
        exact = arm.exact_for(found, tol)
        A, labels, free = self._raw_branches(chain, found, task.pose, rest[cols], exact)
        values = np.repeat(rest[None], len(A), axis=0)
        turn = ~chain.sliding
        if len(A):
            A[:, turn] = np.remainder(A[:, turn] + np.pi, 2 * np.pi) - np.pi  # in [-pi, pi)
            values[:, cols] = A
        lost = 0
        if not exact and len(A):  # near the family only: polish on the real model
            values, labels, free, lost, failed = self._polish_branches(
                values, labels, free, task, tol, chain, locked
            )
        keep = branches.distinct(values[:, cols], chain.sliding)
        lost += int((~keep).sum()) if not exact else 0
        rows = np.flatnonzero(keep)
        kept = [(values[i], labels[i], int(free[i])) for i in rows.tolist()]
        if not exact and len(A):  # near a singularity: the real arm's branches lie apart
            kept += singular.missed_branches(self, kept, failed, task, tol, chain)
        return self._verified_branches(kept, chain, task, tol, found, lost, exact, moved)

    def _polish_branches(
        self, values: np.ndarray, labels: list[str], free: np.ndarray, task: PoseTask,
        tol: float, chain: arm.Chain, locked: tuple[tuple[int, float], ...],
    ) -> tuple[np.ndarray, list[str], np.ndarray, int, list[tuple[np.ndarray, str]]]:  # fmt: skip
        """The branches of the nearest exact geometry polished on the real model from the
        turn of each angle within its limits, locked joints held (clipped) at their value:
        (values, labels, free joints, how many did not converge, (start, label) of those)."""
        lo, hi = self._chain_limits(chain)
        cols = list(chain.columns)
        for row in values:  # the turn within the limits nearest the branch's angle
            choices = branches.turns_of(row[cols], lo, hi, chain.sliding)
            row[cols] = choices[np.argmin(np.abs(choices - row[cols]).sum(axis=1))]
        if locked or not task.weights[3:].any():
            # Gauss-Newton on the chain's own joints: the locked ones never move, and a
            # branch outside the limits is polished too (then listed as outside)
            polished = [self._newton(v, task, cols) for v in values]
        else:
            opts = IKOptions(tol=tol, max_iter=50, restarts=0)
            polished = [loops.solve_ik(self.ik_loop, self.ik_state, task, q, opts)
                        for q in self.q_from_angles(values)]  # fmt: skip
        reached = [r.position_error <= tol and r.orientation_error <= tol for r in polished]
        kept = np.array([r.q for r, ok in zip(polished, reached, strict=True) if ok])
        failed = [(v, label) for v, label, ok in zip(values, labels, reached, strict=True)
                  if not ok]  # fmt: skip
        return (
            self.angles(kept.reshape(-1, self.model.nq)),
            [label for label, ok in zip(labels, reached, strict=True) if ok],
            free[np.asarray(reached, dtype=bool)],
            len(polished) - sum(reached),
            failed,
        )

    def _newton(self, values: np.ndarray, task: PoseTask, cols: list[int]) -> IKResult:
        """Gauss-Newton on the joints ``cols`` alone (the Jacobian's columns of the chain)
        from one value per joint: quadratic near a branch, so 20 steps reach round-off."""
        v = values.copy()
        frame = self.model.frames[task.frame_id].name
        target = task.pose
        rows = 6 if task.weights[3:].any() else 3  # a position target: its 3 rows
        for _ in range(20):
            T = self.fk(self.q_from_angles(v), frame)
            dp = target[:3, 3] - T[:3, 3]
            dw = pin.log3(target[:3, :3] @ T[:3, :3].T) if rows == 6 else np.zeros(3)
            if max(np.linalg.norm(dp), np.linalg.norm(dw)) < 1e-14:
                break
            J = self.jacobian(self.q_from_angles(v), frame)[:rows, cols]
            v[cols] += np.linalg.lstsq(J, np.concatenate([dp, dw])[:rows], rcond=None)[0]
        q = self.q_from_angles(v)
        return solver.verify(self.ik_state, task, q, 1e-10, 20, 0)

    def _raw_branches(
        self, chain: arm.Chain, found: arm.Structure, pose: np.ndarray, pref: np.ndarray,
        exact: bool,
    ) -> tuple[np.ndarray, list[str], np.ndarray]:  # fmt: skip
        """The family's branches (angles (B, n), labels, free joints (B,): bit j the chain's
        joint j): compiled where a kernel exists, else the Python form. ``pref``: the chain
        joints' angles a singular pose's free joints take."""
        assert found.family is not None and found.points is not None
        joints = len(chain.joints)
        if not found.compiled:
            ok = analytic.EXACT_ONLY if exact else analytic.NEAR_OK
            raw = analytic.solve(chain, found, pose, ok)
            A = np.array([a for a, _ in raw], dtype=float).reshape(-1, joints)
            return A, [label for _, label in raw], np.zeros(len(raw), np.int64)
        out = np.zeros((8, joints))
        roots = np.full((8, 3), -1, np.int64)
        free = np.zeros(8, np.int64)
        solve = analytic_kernels.KERNELS[found.family][0]
        pref = np.ascontiguousarray(pref, dtype=float)
        if not found.reversed:
            n = solve(*packed_family(chain, found), pose, not exact, pref, out, roots, free)
            return out[:n].copy(), [_label(roots[k], joints == 6) for k in range(n)], free[:n]
        # solved on the chain seen from its frame, at T^-1, and turned back (analytic.solve)
        packed = packed_family(arm.reverse(chain), found)
        n = solve(*packed, np.linalg.inv(pose), not exact, np.ascontiguousarray(-pref[::-1]),
                  out, roots, free)  # fmt: skip
        labels = ["reversed: " + _label(roots[k], joints == 6) for k in range(n)]
        return -out[:n, ::-1], labels, branches.reverse_bits(free[:n], joints)

    def _chain_limits(self, chain: arm.Chain) -> tuple[np.ndarray, np.ndarray]:
        """Per chain joint, its angle limits (unlimited for a continuous joint)."""
        return self._chain_layout(chain)[:2]

    def _chain_layout(
        self, chain: arm.Chain
    ) -> tuple[np.ndarray, np.ndarray, list[int], list[int]]:
        """(lower, upper limits per chain joint (unlimited for a continuous joint), the
        chain joints with one coordinate, those coordinates' places in q); kept per chain
        (the limits are read-only)."""
        cache: dict[tuple[int, ...], tuple[np.ndarray, np.ndarray, list[int], list[int]]]
        cache = self.__dict__.setdefault("_chain_layouts", {})
        found = cache.get(chain.joints)
        if found is None:
            lo, hi, one, at = [], [], [], []
            for k, j in enumerate(chain.joints):
                joint = self.model.joints[j]
                single = joint.nq == 1
                lo.append(float(self.lower[joint.idx_q]) if single else -np.inf)
                hi.append(float(self.upper[joint.idx_q]) if single else np.inf)
                if single:
                    one.append(k)
                    at.append(int(joint.idx_q))
            found = cache[chain.joints] = (np.array(lo), np.array(hi), one, at)
        return found

    def _verified_branches(
        self, kept: list[tuple[np.ndarray, str, int]], chain: arm.Chain, task: PoseTask,
        tol: float, found: arm.Structure, lost: int, exact: bool, moved: float,
    ) -> branches.IKAllResult:  # fmt: skip
        """Each branch verified once by the kinematics back end's forward kinematics (which
        shares no code with the subproblems; turns of a joint do not move the frame), then
        repeated for every equivalent angle within the limits. A branch of an exact arm that
        misses ``tol`` by rounding only (a singular pose's representative, a target at a
        tangent) is polished on the real model first."""
        state = self.ik_state
        cols = list(chain.columns)
        A = np.array([a for a, _, _ in kept]).reshape(-1, self.model.nv)
        Qb = self.joints.q_from_angles(A, self.name)
        F = self.kinematics.fk(Qb, task.frame_id)
        pos, rot = branches.errors(F, task.pose, task.use_rot)
        rough = np.flatnonzero(((pos > tol) | (rot > tol)) & (pos <= ROUGH) & (rot <= ROUGH))
        if len(rough):  # Gauss-Newton on the chain's joints (a singular one: least norm)
            for i in rough.tolist():
                r = self._newton(A[i], task, cols)
                A[i], pos[i], rot[i] = self.angles(r.q), r.position_error, r.orientation_error
            Qb = self.joints.q_from_angles(A, self.name)
        lo, hi, one, at = self._chain_layout(chain)
        chosen, owner = branches.turns_many(A[:, cols], lo, hi, chain.sliding)
        Q = Qb[owner]  # each turn in the coordinate of its joint (a (cos, sin) pair has none)
        Q[:, at] = chosen[:, one]
        inside = np.asarray(state.valid_rows(Q), dtype=bool).reshape(-1)
        reached = (pos <= tol) & (rot <= tol)
        names = [label for _, label, _ in kept]
        free_names = [branches.free_joints(bits, chain.names) for _, _, bits in kept]
        return branches.IKAllResult(
            Q, reached[owner] & inside, inside, [names[i] for i in owner.tolist()], pos[owner],
            rot[owner], found, not exact, lost, owner.astype(np.int64),
            tuple(free_names[i] for i in owner.tolist()), moved,
        )  # fmt: skip

    def _analytic_ik(
        self, task: PoseTask, q0: np.ndarray | None, tol: float, checker: object = None
    ) -> IKResult | None:
        """The verified branch nearest q0 (default: mid-range), collision-free when a
        checker is given; None when no branch succeeds."""
        state = self.ik_state
        start = state.mid if q0 is None else q0
        target = task.pose if task.weights[3:].any() else task.pose[:3, 3]  # a 3R: a point
        found = self.ik_all(target, frame=self.model.frames[task.frame_id].name, tol=tol,
                            q_rest=start)  # fmt: skip
        far = np.abs(self.angles(found.q) - self.angles(start)).sum(axis=1) if len(found.q) else []
        for i in np.argsort(far, kind="stable").tolist():
            if not found.success[i]:
                continue
            q = found.q[i]
            if checker is not None and checker.first_collision(q) is not None:  # type: ignore[attr-defined]
                continue
            return solver.verify(state, task, q, tol)
        return None
