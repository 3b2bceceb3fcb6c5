"""A robot's analytic IK (a part of :class:`~toolkit.robot.Robot`): its structure, every
branch of a target (``ik_all``), and the branch ``ik(..., method="analytic")`` answers."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ...common import renames
from ...common import validate as _validate
from ...errors import InvalidParameterError, UnsupportedModelError
from ...kinematics import Backend, CompiledBackend, Frames, JointLayout
from ..analytic import (
    BranchDoor,
    branches,
    chain_angles,
    door_kernels,
    families,
    nearest_turn_rows,
    registry,
)
from ..analytic import structure as arm
from ..numeric import IKOptions, IKResult, NumericIK, PoseTask, loops, solver
from ..targets import nearest_rotations
from . import doors, singular
from .kept import BranchCaches
from .reasons import why_none

__all__ = ["ROUGH", "BranchQueries"]

ROUGH = door_kernels.ROUGH


class BranchQueries:
    """A robot's analytic IK (a part of :class:`~toolkit.robot.Robot`; ``robot.ik_all``,
    ``structure`` and ``structure_of`` are its methods): its structures and doors, kept in
    its own caches (:class:`BranchCaches`), and every branch of a target."""

    def __init__(
        self, model: pin.Model, name: str, joints: JointLayout, frames: Frames,
        kinematics: Backend, caches: BranchCaches, numeric: NumericIK,
    ) -> None:  # fmt: skip
        self.model, self.name, self.joints, self.frames = model, name, joints, frames
        self.kinematics, self.caches, self.numeric = kinematics, caches, numeric

    def _chain_structure(
        self, fid: int, lock: tuple[tuple[int, float], ...] = ()
    ) -> tuple[arm.Chain | None, arm.Structure]:
        caches = self.caches
        key: object = fid if not lock else (fid, lock)
        found: tuple[arm.Chain | None, arm.Structure] | None = caches.structures.get(key)
        if found is None:
            found = doors.relocked(self, fid, lock)  # a tail lock at a new angle: re-tipped
        if found is None:
            hint = (fid, tuple(j for j, _ in lock))  # the family of these locked joints
            try:
                chain = arm.chain_of(self.model, fid, dict(lock))
                found = (chain, arm.find_structure(chain, caches.families.get(hint)))
                if lock and found[1].family is not None:
                    caches.keep(caches.families, hint, (found[1].family, found[1].reversed))
            except UnsupportedModelError as exc:
                names = (self.model.frames[fid].name,)
                found = (None, arm.Structure(family=None, joints=names, reason=str(exc)))
            doors.keep_template(self, fid, lock, found)
        caches.keep(caches.structures, key, found)
        return found

    def _solvable(
        self, fid: int, locked: tuple[tuple[int, float], ...], numeric: str
    ) -> tuple[arm.Chain, arm.Structure]:
        """The chain to ``fid`` and its structure, or an :class:`UnsupportedModelError`
        saying why it has none and pointing to the ``numeric`` call."""
        chain, found = self._chain_structure(fid, locked)
        if chain is None or found.family is None or found.points is None:
            raise UnsupportedModelError(
                f"{self.name}: no analytic IK to {self.model.frames[fid].name}: {found.reason}; "
                f"use {numeric} (numeric)"
            )
        return chain, found

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
        why (or why none fits); see :func:`toolkit.ik.analytic.structure.find_structure`."""
        return self._chain_structure(self.frames.id(None))[1]

    def structure_of(self, frame: str | None = None, *, lock: object = None) -> arm.Structure:
        """:attr:`structure` for another frame, or with joints locked (``lock``: {joint
        name: angle [rad]}, e.g. the seventh joint of a 7-joint arm)."""
        return self._chain_structure(self.frames.id(frame), self._locked(lock))[1]

    @renames.renamed(q_rest="q0")
    def ik_all(
        self, target: object, *, frame: str | None = None, tol: float = 1e-10,
        q0: ArrayLike | None = None, lock: object = None, turns: bool = False,
    ) -> branches.IKAllResult:  # fmt: skip
        """Every IK branch of a 4x4 target pose (a position for a 3-joint arm), by subproblem
        decomposition (:mod:`toolkit.ik.analytic.families`), each verified by an independent forward
        kinematics to ``tol`` [m and rad]. One row per branch, each revolute joint at its
        turn (q + 2 pi k) within the limits nearest ``q0``'s angle (the wrapped angle in
        [-pi, pi) where no turn fits, and the row is then outside the limits); ``turns=True``
        lists every turn of every branch within the limits instead (rows that share
        ``branch``). Joints outside the chain keep their value in ``q0`` (default: the
        middle of their range). An arm only near its family (a calibrated arm) has every
        branch polished on the real model (``polished``). An
        :class:`~toolkit.errors.UnsupportedModelError` says why when the arm has no
        structure (then use :meth:`ik`). ``lock`` ({joint name: angle [rad]}) holds joints
        at those angles and solves the others (a 7-joint arm with one joint locked); a sweep
        of a locked joint's angle gives branches along the self-motion. The compiled
        families answer in :meth:`ik_all_batch`'s compiled call."""
        fid = self.frames.id(frame)
        if type(tol) is not float or not 0.0 < tol <= 0.01:
            tol = _validate.number(tol, "tol", lower=0.0, strict=True, upper=0.01)
        locked = () if lock is None else self._locked(lock)
        if type(turns) is not bool:
            turns = _validate.flag(turns, "turns")
        door, answer = self._door(fid, locked), None
        pose = None if door is None else doors.door_pose(door, target)
        if pose is not None and door is not None and door.exact(tol):
            answer = doors.door_answer(self, door, pose, tol, q0, locked, turns)
        if answer is None:
            answer = self._ik_all_general(fid, target, tol, q0, locked, turns)
        if not np.count_nonzero(answer.success):  # say why (never on a target with a branch)
            answer = answer._replace(reason=why_none(self, frame, target, answer, tol, locked))
        return answer

    def _door(self, fid: int, locked: tuple[tuple[int, float], ...] = ()) -> BranchDoor | None:
        """The compiled family's door to ``fid`` (joints ``locked``), None where the chain has
        no compiled family or the kinematics are not compiled; kept per chain."""
        kept = self.caches.doors
        key: object = fid if not locked else (fid, locked)
        if key in kept:
            answer: BranchDoor | None = kept[key]
            return answer
        chain, found = self._chain_structure(fid, locked)
        backend = self.kinematics
        door = None
        if chain is not None and found.compiled and isinstance(backend, CompiledBackend):
            state = self.numeric.ik_state
            lo, hi, _, _ = self._chain_layout(chain)
            qcol = np.array([self.model.joints[j].idx_q for j in chain.joints], np.int64)
            circle = np.array([self.model.joints[j].nq == 2 for j in chain.joints])
            layout = (qcol, circle, lo, hi, np.ascontiguousarray(state.limit_lower, dtype=float),
                      np.ascontiguousarray(state.limit_upper, dtype=float),
                      np.asarray(chain.sliding, dtype=bool))  # fmt: skip
            mid = self._rest(None, locked)
            door = BranchDoor(chain, found, layout, backend.chain(fid), mid,
                              chain_angles(layout, mid))  # fmt: skip
        self.caches.keep(kept, key, door)
        return door

    def _rest(self, q_rest: ArrayLike | None, locked: tuple[tuple[int, float], ...]) -> np.ndarray:
        """The rest configuration q (nq,): ``q_rest`` checked (default: mid-range), the
        locked joints at their angles."""
        rest = np.array(
            self.numeric.ik_state.mid if q_rest is None else self.joints.check(q_rest), dtype=float
        )
        if locked:
            values = self.joints.angles(rest)
            for j, angle in locked:
                values[self.model.joints[j].idx_v] = angle
            rest = np.ascontiguousarray(self.joints.q_from_angles(values), dtype=float)
        return rest

    def _ik_all_general(
        self, fid: int, target: object, tol: float, q_rest: ArrayLike | None,
        locked: tuple[tuple[int, float], ...], turns: bool,
    ) -> branches.IKAllResult:  # fmt: skip
        """:meth:`ik_all` of any family: the Python forms, the polish of an arm near its
        family, the branches near a singularity."""
        task = PoseTask.from_target(fid, target, None)
        chain, found = self._solvable(fid, locked, "ik()")
        places = found.places_point
        if places == bool(task.weights[3:].any()):
            raise InvalidParameterError(
                f"ik_all of {self.name} ({found.family}) needs a target "
                f"{'position (3,): a 3-joint arm places a point' if places else 'pose (4, 4)'}"
            )
        moved = 0.0
        if not places:  # a float32 or rounded rotation: solved at the nearest rotation
            projected, shift = nearest_rotations(task.pose[None])
            task.pose[:3, :3], moved = projected[0, :3, :3], float(shift[0])
        rest = self.joints.angles(self._rest(q_rest, locked))
        cols = list(chain.columns)
        exact = arm.exact_for(found, tol)
        structure = (chain, found, self._door(fid, locked))
        A, labels, free = self._raw_branches(structure, task.pose, rest, exact)
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
        result = self._verified_branches(kept, chain, task, tol, (found, lost, exact, moved),
                                         rest[cols])  # fmt: skip
        return doors.every_turn(self, result, chain, tol) if turns else result

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
            polished = [loops.solve_ik(self.numeric.ik_loop, self.numeric.ik_state, task, q, opts)
                        for q in self.joints.q_from_angles(values)]  # fmt: skip
        reached = [r.position_error <= tol and r.orientation_error <= tol for r in polished]
        kept = np.array([r.q for r, ok in zip(polished, reached, strict=True) if ok])
        failed = [(v, label) for v, label, ok in zip(values, labels, reached, strict=True)
                  if not ok]  # fmt: skip
        return (
            self.joints.angles(kept.reshape(-1, self.model.nq)),
            [label for label, ok in zip(labels, reached, strict=True) if ok],
            free[np.asarray(reached, dtype=bool)],
            len(polished) - sum(reached),
            failed,
        )

    def _newton(self, values: np.ndarray, task: PoseTask, cols: list[int]) -> IKResult:
        """Gauss-Newton on the joints ``cols`` alone (the Jacobian's columns of the chain)
        from one value per joint: quadratic near a branch, so 20 steps reach round-off."""
        v = values.copy()
        fid, kin = task.frame_id, self.kinematics  # the back end: v is the toolkit's own
        target = task.pose
        rows = 6 if task.weights[3:].any() else 3  # a position target: its 3 rows
        for _ in range(20):
            q = self.joints.raw_q(v, self.name)[None]
            T = kin.fk(q, fid)[0]
            dp = target[:3, 3] - T[:3, 3]
            dw = pin.log3(target[:3, :3] @ T[:3, :3].T) if rows == 6 else np.zeros(3)
            if max(np.linalg.norm(dp), np.linalg.norm(dw)) < 1e-14:
                break
            J = kin.jacobian(q, fid)[0][:rows, cols]
            v[cols] += np.linalg.lstsq(J, np.concatenate([dp, dw])[:rows], rcond=None)[0]
        q = self.joints.q_from_angles(v)
        return solver.verify(self.numeric.ik_state, task, q, 1e-10, 20, 0)

    def _raw_branches(
        self, structure: tuple[arm.Chain, arm.Structure, BranchDoor | None], pose: np.ndarray,
        rest: np.ndarray, exact: bool,
    ) -> tuple[np.ndarray, list[str], np.ndarray]:  # fmt: skip
        """The family's branches (angles (B, n) of the chain's joints, labels, free joints
        (B,): bit j the chain's joint j) at rest angles ``rest`` (nv,): compiled through the
        door where there is one (equal rows dropped), else the Python form. ``structure``:
        (chain, its structure, its door or None)."""
        chain, found, door = structure
        assert found.family is not None and found.points is not None
        cols = list(chain.columns)
        if door is not None:
            Q, _, K, _, C = door.rows(
                np.ascontiguousarray(pose, dtype=float)[None], 0.01,
                self.joints.q_from_angles(rest),
                np.ascontiguousarray(rest[cols]), near=not exact,
            )  # fmt: skip
            if not C[0, 1] & door_kernels.MANY:  # more branches than its rows: Python's
                k = int(C[0, 0])
                return (
                    self.joints.angles(Q[0, :k])[:, cols],
                    door.labels(K[0, :k, :3]),
                    K[0, :k, 3].copy(),
                )
        ok = families.EXACT_ONLY if exact else families.NEAR_OK
        raw = registry.solve(chain, found, pose, ok)
        A = np.array([a for a, _ in raw], dtype=float).reshape(-1, len(cols))
        return A, [label for _, label in raw], np.zeros(len(raw), np.int64)

    def _chain_limits(self, chain: arm.Chain) -> tuple[np.ndarray, np.ndarray]:
        """Per chain joint, its angle limits (unlimited for a continuous joint)."""
        return self._chain_layout(chain)[:2]

    def _chain_layout(
        self, chain: arm.Chain
    ) -> tuple[np.ndarray, np.ndarray, list[int], list[int]]:
        """(lower, upper limits per chain joint (unlimited for a continuous joint), the
        chain joints with one coordinate, those coordinates' places in q); kept per chain
        (the limits are read-only)."""
        cache = self.caches.chain_layouts
        found: tuple[np.ndarray, np.ndarray, list[int], list[int]] | None = cache.get(chain.joints)
        if found is None:
            lo, hi, one, at = [], [], [], []
            for k, j in enumerate(chain.joints):
                joint = self.model.joints[j]
                single = joint.nq == 1
                lo.append(float(self.joints.lower[joint.idx_q]) if single else -np.inf)
                hi.append(float(self.joints.upper[joint.idx_q]) if single else np.inf)
                if single:
                    one.append(k)
                    at.append(int(joint.idx_q))
            found = cache[chain.joints] = (np.array(lo), np.array(hi), one, at)
        return found

    def _verified_branches(
        self, kept: list[tuple[np.ndarray, str, int]], chain: arm.Chain, task: PoseTask,
        tol: float, about: tuple[arm.Structure, int, bool, float], pref: np.ndarray,
    ) -> branches.IKAllResult:  # fmt: skip
        """Each branch verified by the kinematics back end's forward kinematics (which shares
        no code with the subproblems; turns of a joint do not move the frame), each revolute
        joint at its turn within the limits nearest ``pref`` (the chain's rest angles).
        ``about``: (structure, branches lost, exact, how far the target moved). A branch of
        an exact arm that misses ``tol`` by rounding only (a singular pose's representative,
        a target at a tangent) is polished on the real model first."""
        found, lost, exact, moved = about
        cols = list(chain.columns)
        A = np.array([a for a, _, _ in kept]).reshape(-1, self.model.nv)
        lo, hi = self._chain_limits(chain)
        A[:, cols] = nearest_turn_rows(np.ascontiguousarray(A[:, cols]), lo, hi, pref,
                                       ~chain.sliding)  # fmt: skip
        Q = self.joints.raw_q(A, self.name)
        F = self.kinematics.fk(Q, task.frame_id)
        pos, rot = branches.errors(F, task.pose, task.use_rot)
        rough = np.flatnonzero(((pos > tol) | (rot > tol)) & (pos <= ROUGH) & (rot <= ROUGH))
        if len(rough):  # Gauss-Newton on the chain's joints (a singular one: least norm)
            for i in rough.tolist():
                r = self._newton(A[i], task, cols)
                A[i], pos[i], rot[i] = (
                    self.joints.angles(r.q),
                    r.position_error,
                    r.orientation_error,
                )
            A[:, cols] = nearest_turn_rows(np.ascontiguousarray(A[:, cols]), lo, hi, pref,
                                           ~chain.sliding)  # fmt: skip
            Q = self.joints.raw_q(A, self.name)
        inside = np.asarray(self.numeric.ik_state.valid_rows(Q), dtype=bool).reshape(-1)
        reached = (pos <= tol) & (rot <= tol)
        return branches.IKAllResult(
            q=Q,
            success=reached & inside,
            within_limits=inside,
            labels=[label for _, label, _ in kept],
            position_error=pos,
            orientation_error=rot,
            structure=found,
            polished=not exact,
            lost=lost,
            branch=np.arange(len(kept), dtype=np.int64),
            free=tuple(branches.free_joints(bits, chain.names) for _, _, bits in kept),
            target_moved=moved,
        )

    def _analytic_ik(
        self, task: PoseTask, q0: np.ndarray | None, tol: float, checker: object = None
    ) -> IKResult | None:
        """The verified branch nearest q0 (default: mid-range; each branch at its turns
        nearest q0), collision-free when a checker is given; None when no branch succeeds:
        every branch of :meth:`ik_all` (the general path; ``Robot.ik`` tries an exact
        compiled family's door before this)."""
        state = self.numeric.ik_state
        start = state.mid if q0 is None else q0
        target = task.pose if task.weights[3:].any() else task.pose[:3, 3]  # a 3R: a point
        found = self.ik_all(target, frame=self.model.frames[task.frame_id].name, tol=tol,
                            q0=start)  # fmt: skip
        far = (
            np.abs(self.joints.angles(found.q) - self.joints.angles(start)).sum(axis=1)
            if len(found.q)
            else []
        )
        for i in np.argsort(far, kind="stable").tolist():
            if not found.success[i]:
                continue
            q = found.q[i]
            if checker is not None and checker.first_collision(q) is not None:  # type: ignore[attr-defined]
                continue
            answer = solver.verify(state, task, q, tol)  # the target as given: a projected
            if answer.success:  # one's rows may miss it (a float32 pose), then numeric
                return answer._replace(method="analytic")
        return None
