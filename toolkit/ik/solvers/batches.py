"""Every IK branch of N targets at once (``Robot.ik_all_batch``, a part of
:class:`~toolkit.robot.Robot`): the compiled family's kernels over the cores, the other
families target by target."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...common import renames
from ...common import validate as _validate
from ...errors import InvalidParameterError, UnsupportedModelError
from ...kinematics import CompiledBackend, parallel
from .. import checks
from ..analytic import BranchDoor, Family, branches, door_kernels, nearest_turn_rows
from ..analytic import structure as arm
from ..numeric import IKOptions, batch_targets, check_poses
from ..targets import nearest_rotations
from .branches import ROUGH, BranchQueries
from .singular import NEAR_SINGULAR, SWEEP_ITER, closeness, sigma, sweep_starts, turn_gap

__all__ = ["AnalyticIK"]


class AnalyticIK(BranchQueries):
    """A robot's analytic IK with its batches (``robot.ik_all_batch``): the part of
    :class:`~toolkit.robot.Robot` that answers by branches."""

    @renames.renamed(q_rest="q0")
    def ik_all_batch(
        self, targets: ArrayLike, *, frame: str | None = None, tol: float = 1e-10,
        q0: ArrayLike | None = None, lock: object = None,
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """Every branch of N target poses (N, 4, 4) at once (N positions (N, 3) for a
        3-joint arm; see :class:`toolkit.ik.IKAllBatchResult`): compiled and spread over the
        cores (every family is compiled: :data:`toolkit.ik.analytic.structure.COMPILED`),
        the branches of an arm only near its family polished on the real model in one
        compiled batch (branches that merge listed once); on the Pinocchio reference back
        end, a locked or 3-joint arm only near its family, or a search target of more than
        16 branches, target by target through :meth:`ik_all`, one row per branch. Each row
        is the one :meth:`ik_all` gives (each revolute joint at its turn within the limits
        nearest ``q0``'s angle);
        ``lock`` as for :meth:`ik_all` (a locked arm only near its family: target by
        target)."""
        fid = self.frames.id(frame)
        tol = _validate.number(tol, "tol", lower=0.0, strict=True, upper=0.01)
        poses, position_only = batch_targets(targets, rotations=False)  # the door checks them
        locked = () if lock is None else self._locked(lock)
        chain, found = self._solvable(fid, locked, "ik_batch()")
        places = found.places_point
        if places != position_only:
            raise InvalidParameterError(
                f"ik_all_batch of {self.name} ({found.family}) needs "
                f"{'(N, 3) target positions' if places else '(N, 4, 4) target poses'}"
            )
        door = self._door(fid, locked) if found.compiled else None
        if door is None or ((locked or places) and not door.exact(tol)):
            if found.compiled:
                self._compiled_chain(fid)  # says why: the kinematics are not compiled
            check_poses(poses)
            moved = np.zeros(len(poses))
            if not position_only:  # float32 or rounded rotations: solved at the nearest ones
                poses, moved = nearest_rotations(poses)
            return self._looped(poses, fid, (chain, found), tol, (q0, lock), moved)
        return self._through_door(door, poses, fid, tol, (q0, lock, locked))

    def _through_door(
        self, door: BranchDoor, poses: np.ndarray, fid: int, tol: float,
        rest_lock: tuple[ArrayLike | None, object, tuple[tuple[int, float], ...]],
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """:meth:`ik_all_batch` of a compiled family through its door (``rest_lock``:
        q_rest, lock as given, lock as (joint id, angle)); the targets the door flags as
        not orthonormal (float32, rounded) moved to the nearest rotations and solved again."""
        q_rest, lock, locked = rest_lock
        chain, found = door.chain, door.found
        # the door's middle holds the locked angles already
        rest = door.mid if q_rest is None else self._rest(q_rest, locked)
        pref = door.mid_pref if q_rest is None else door.pref_of(rest)
        exact = door.exact(tol)
        poses = np.ascontiguousarray(poses, dtype=float)
        spread = parallel(8 * len(poses))
        Q, E, K, S, C = door.rows(poses, tol, rest, pref, near=not exact, spread=spread)
        refused = (C[:, 1] & door_kernels.NOT_POSE) != 0  # finite (checked), not a pose
        if refused.any():  # says why
            check_poses(poses[refused])
            raise InvalidParameterError("targets: a pose is not a rigid transform")
        moved = np.zeros(len(poses))
        mv = np.flatnonzero(C[:, 1] == door_kernels.MOVE)
        if len(mv):
            poses = poses.copy()
            poses[mv], moved[mv] = nearest_rotations(poses[mv])
            again = door.rows(poses[mv], tol, rest, pref, near=not exact, spread=spread)
            for whole, part in zip((Q, E, K, S, C), again, strict=True):
                whole[mv] = part
        # views of the door's own arrays (nothing else holds them): no copies
        pos, rot, roots, free = E[..., 0], E[..., 1], K[..., :3], K[..., 3]
        counts, flags, ok, inside = C[:, 0], C[:, 1], S[..., 1], S[..., 0]
        live = np.arange(Q.shape[1])[None, :] < counts[:, None]
        if not exact:
            Q, pos, rot, roots, free, counts, live = self._near_family(
                (Q, roots, free, counts, live), poses, fid, tol, (chain, pref)
            )
        elif flags.any() and (locked or found.places_point or (flags & door_kernels.MANY).any()):
            # ik_all's: the polish holding locked joints or a point's position alone, or a
            # search with more branches than the door's rows
            return self._looped(poses, fid, (chain, found), tol, (q_rest, lock), moved)
        elif flags.any():  # rounding at a singular pose or a tangent: those rows polished
            self._polish_rough(Q, pos, rot, live, poses, fid, tol, (chain, pref))
        if not exact or flags.any():  # rows the door did not verify: verified here
            ok, inside = self._verified(Q, pos, rot, live, tol)
        free[~live] = 0
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not exact, free,
                                         moved, inside)  # fmt: skip

    def _verified(
        self, Q: np.ndarray, pos: np.ndarray, rot: np.ndarray, live: np.ndarray, tol: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(verified and within the limits, within the limits) (N, B) of the ``live`` rows."""
        ok, inside = np.zeros(live.shape, dtype=bool), np.zeros(live.shape, dtype=bool)
        inside[live] = np.asarray(self.numeric.ik_state.valid_rows(Q[live]), dtype=bool)
        ok[live] = (pos[live] <= tol) & (rot[live] <= tol) & inside[live]
        return ok, inside

    def _near_family(
        self, arrays: tuple[np.ndarray, ...], poses: np.ndarray, fid: int, tol: float,
        turning: tuple[arm.Chain, np.ndarray],
    ) -> tuple[np.ndarray, ...]:  # fmt: skip
        """(Q, pos, rot, roots, free, counts, live) of an arm only near its family: the
        exact geometry's branches ``arrays`` (Q, roots, free, counts, live) polished on the
        real model, the branches the polish misses near a singularity added, each row at
        its joints' turns within the limits nearest the rest angles (``turning``: the chain
        and those angles)."""
        chain = turning[0]
        Q, roots, free, counts, live = arrays
        Q, counts, roots, live, free, failed, (pos, rot) = self._polished(
            Q, counts, roots, live, free, poses, fid, tol
        )
        found_more = self._near_singular_rows(Q, live, failed, poses, fid, tol, chain)
        if found_more:  # the batch's width grows where a target gained branches
            Q, pos, rot, roots, free, counts, live = self._appended(
                found_more, (Q, pos, rot, roots, free, counts, live)
            )
        Q[live] = self._nearest_turns(Q[live], turning)
        return Q, pos, rot, roots, free, counts, live

    def _near_singular_rows(
        self, Q: np.ndarray, live: np.ndarray, failed: tuple[np.ndarray, np.ndarray],
        poses: np.ndarray, fid: int, tol: float, chain: arm.Chain,
    ) -> dict[int, list[tuple[np.ndarray, float, float]]]:  # fmt: skip
        """The branches the polish misses near a singularity, as ``ik_all`` finds them
        (:func:`toolkit.ik.solvers.singular.missed_branches`: seeded from the polished rows and
        the starts that did not converge, ``failed`` (targets, rows)), for every target at
        once: {target: [(q, position error, orientation error), ...]}."""
        at = np.argwhere(live)
        if not len(at) and not len(failed[0]):
            return {}
        cols = list(chain.columns)
        A = self.joints.angles(np.concatenate([Q[live], failed[1]]))
        where = np.concatenate([at[:, 0], failed[0]]).astype(np.int64)
        small, direction = sigma(self, A, fid, cols, 6, below=NEAR_SINGULAR)  # inf: far
        seeds = np.flatnonzero(small < NEAR_SINGULAR)
        if not len(seeds):
            return {}
        starts, owner = sweep_starts(A, seeds, direction, cols)
        target = where[owner]
        opts = IKOptions(tol=tol, max_iter=SWEEP_ITER, restarts=0)
        numeric = self.numeric
        Q0 = self.joints.q_from_angles(starts)
        done, _ = numeric.ik_loop.solve_poses(fid, poses, np.ones(6), Q0, numeric.ik_state, opts,
                                              0, owner=target)  # fmt: skip
        pos, rot = self._errors(done, poses, fid, target)
        good = np.flatnonzero((pos <= tol) & (rot <= tol))
        if not len(good):
            return {}
        B = self.joints.angles(done[good])
        # each candidate against its target's own branches at once (NaN past them): most
        # fall back onto the branch they started from
        W = np.full((*live.shape, len(cols)), np.nan)
        W[live] = A[: len(at), cols]
        t = target[good]
        exact = np.flatnonzero(np.isinf(small[: len(at)]) & np.isin(at[:, 0], t))
        if len(exact) and closeness(tol, NEAR_SINGULAR) > closeness(tol, np.inf):
            # the rows a candidate is compared with: their own sigma (not needed where the
            # bound they were proved to keep, NEAR_SINGULAR, already gives the floor 1e-6)
            small[exact] = sigma(self, A[exact], fid, cols, 6)[0]
        close = np.full(live.shape, np.nan)
        close[live] = closeness(tol, small[: len(at)])
        d = B[:, None, cols] - W[t]
        d = np.where(chain.sliding, d, np.remainder(d + np.pi, 2 * np.pi) - np.pi)
        with np.errstate(invalid="ignore"):
            old = (np.abs(d).max(axis=2) < close[t]).any(axis=1)
        out: dict[int, list[tuple[np.ndarray, float, float]]] = {}
        kept: dict[int, list[tuple[np.ndarray, float]]] = {}
        fresh = np.flatnonzero(~old)  # the few new ones: against each other, by their sigma
        near = sigma(self, B[fresh], fid, cols, 6)[0] if len(fresh) else np.zeros(0)
        for n, k in enumerate(fresh.tolist()):
            i, a = int(t[k]), B[k]
            if any(turn_gap(a[cols], b[cols], chain.sliding) < c for b, c in kept.get(i, [])):
                continue
            kept.setdefault(i, []).append((a, float(closeness(tol, near[n]))))
            j = good[k]
            out.setdefault(i, []).append((done[j], float(pos[j]), float(rot[j])))
        return out

    def _appended(
        self, more: dict[int, list[tuple[np.ndarray, float, float]]],
        arrays: tuple[np.ndarray, ...],
    ) -> tuple[np.ndarray, ...]:  # fmt: skip
        """``arrays`` (Q, pos, rot, roots, free, counts, live) with the rows ``more`` after
        each target's own (the width grows to the longest)."""
        Q, pos, rot, roots, free, counts, live = arrays
        width = max(Q.shape[1], *(int(counts[i]) + len(r) for i, r in more.items()))
        if width > Q.shape[1]:
            grow = width - Q.shape[1]
            Q = np.concatenate([Q, np.full((len(Q), grow, Q.shape[2]), np.nan)], axis=1)
            pos, rot = (np.concatenate([x, np.full((len(x), grow), np.nan)], axis=1)
                        for x in (pos, rot))  # fmt: skip
            roots = np.concatenate([roots, np.full((len(roots), grow, 3), -1, np.int64)], axis=1)
            free = np.concatenate([free, np.zeros((len(free), grow), np.int64)], axis=1)
            live = np.concatenate([live, np.zeros((len(live), grow), dtype=bool)], axis=1)
        for i, rows in more.items():
            for q, p, r in rows:
                k = int(counts[i])
                Q[i, k], pos[i, k], rot[i, k], live[i, k] = q, p, r, True
                counts[i] = k + 1
        return Q, pos, rot, roots, free, counts, live

    def _branch_rows(self, r: branches.IKAllResult, chain: arm.Chain) -> tuple[np.ndarray, ...]:
        """(q, position errors, orientation errors, roots, free bits) of each branch of an
        :meth:`ik_all` answer: its first row within the limits, else its first row."""
        first: dict[int, int] = {}
        for i, (b, inside) in enumerate(zip(r.branch.tolist(), r.within_limits.tolist(),
                                            strict=True)):  # fmt: skip
            if b not in first or (inside and not r.within_limits[first[b]]):
                first[b] = i
        ix = list(first.values())
        family = Family(r.structure.family)
        bits = [sum(1 << chain.names.index(j) for j in r.free[i]) for i in ix]
        return (r.q[ix], r.position_error[ix], r.orientation_error[ix],
                np.array([family.roots_of(r.labels[i]) for i in ix], np.int64).reshape(-1, 3),
                np.array(bits, np.int64))  # fmt: skip

    def _nearest_turns(self, Q: np.ndarray, turning: tuple[arm.Chain, np.ndarray]) -> np.ndarray:
        """Rows Q (M, nq) with each revolute chain joint at its turn within its limits
        nearest the rest angle (``turning``: the chain and those angles; wrapped to
        [-pi, pi) where none fits): the row ``ik_all`` gives."""
        if not len(Q):
            return Q
        chain, pref = turning
        A = self.joints.angles(Q)
        lo, hi = self._chain_limits(chain)
        cols = list(chain.columns)
        A[:, cols] = nearest_turn_rows(np.ascontiguousarray(A[:, cols]), lo, hi, pref,
                                       ~chain.sliding)  # fmt: skip
        return self.joints.q_from_angles(A)

    def _polish_rough(
        self, Q: np.ndarray, pos: np.ndarray, rot: np.ndarray, live: np.ndarray,
        poses: np.ndarray, fid: int, tol: float, turning: tuple[arm.Chain, np.ndarray],
    ) -> None:  # fmt: skip
        """Rows of an exact arm that miss ``tol`` by rounding only (no more than
        :data:`~toolkit.ik.solvers.branches.ROUGH`) polished on the real model in place."""
        with np.errstate(invalid="ignore"):
            rough = live & ((pos > tol) | (rot > tol)) & (pos <= ROUGH) & (rot <= ROUGH)
        if not rough.any():
            return
        at = np.argwhere(rough)
        opts = IKOptions(tol=tol, max_iter=50, restarts=0)
        rows = np.ascontiguousarray(poses[at[:, 0]])
        done, _ = self.numeric.ik_loop.solve_poses(
            fid, rows, np.ones(6), Q[rough], self.numeric.ik_state, opts, 0
        )
        Q[rough] = self._nearest_turns(done, turning)
        pos[rough], rot[rough] = self._errors(Q[rough], rows, fid)

    def _compiled_chain(self, fid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        backend = self.kinematics
        if not isinstance(backend, CompiledBackend):
            raise UnsupportedModelError(
                f"{self.name}: ik_all_batch needs the compiled kinematics back end "
                f"({self.kinematics.engine.reason})"
            )
        return backend.chain(fid)

    def _errors(
        self, Q: np.ndarray, poses: np.ndarray, fid: int, owner: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Position [m] and orientation [rad] errors of rows Q (M, nq) against poses (M, 4, 4),
        or against poses[owner] (C-contiguous float64 poses, ``owner`` (M,) int64: no pose
        copied per row on the compiled kinematics), by the kinematics back end's forward
        kinematics (the angle from the chord, exact near 0)."""
        backend = self.kinematics
        if owner is not None and isinstance(backend, CompiledBackend):
            Q = np.ascontiguousarray(Q, dtype=float)
            pos, rot = checks.owned_errors(parallel(len(Q)), Q, *backend.chain(fid), poses, owner)
            return np.asarray(pos), np.asarray(rot)
        if owner is not None:
            poses = poses[owner]
        F = self.kinematics.fk(Q, fid) if len(Q) else np.zeros((0, 4, 4))
        pos, rot = checks.pair_errors(np.ascontiguousarray(F),
                                              np.ascontiguousarray(poses, dtype=float))  # fmt: skip
        return np.asarray(pos), np.asarray(rot)

    def _polished(
        self, Q: np.ndarray, counts: np.ndarray, roots: np.ndarray, live: np.ndarray,
        free: np.ndarray, poses: np.ndarray, fid: int, tol: float,
    ) -> tuple[Any, ...]:  # fmt: skip
        """The branches of an arm near its family polished on the real model in one compiled
        batch; a branch that did not converge, or became another, is dropped: (Q, counts,
        roots, live, free, (targets, start rows) of those that did not converge, (position,
        orientation errors) (N, B), NaN past each target's branches)."""
        at = np.argwhere(live)
        if not len(at):
            none = np.full(live.shape, np.nan)
            return (Q, counts, roots, live, free, (np.zeros(0, np.int64), Q[live]),
                    (none, none.copy()))  # fmt: skip
        opts = IKOptions(tol=tol, max_iter=50, restarts=0)
        Q = Q.copy()
        owner = np.ascontiguousarray(at[:, 0], dtype=np.int64)  # each row's target
        state = self.numeric.ik_state
        starts = Q[live]
        Q[live], _ = self.numeric.ik_loop.solve_poses(fid, poses, np.ones(6), starts, state, opts,
                                                      0, owner=owner)  # fmt: skip
        errors = [np.full(live.shape, np.nan) for _ in range(2)]
        pos, rot = self._errors(Q[live], poses, fid, owner)
        errors[0][live], errors[1][live] = pos, rot
        converged = (pos <= tol) & (rot <= tol)
        failed = (at[~converged, 0], starts[~converged])
        keep = live.copy()
        keep[live] = converged
        N, B = live.shape
        A = np.full((N, B, self.model.nv), np.nan)
        A[live] = self.joints.angles(Q[live])
        keep &= branches.distinct_each(A, np.zeros(self.model.nv, dtype=bool))
        order = np.argsort(~keep, axis=1, kind="stable")  # the kept first, in order
        Q = np.take_along_axis(Q, order[:, :, None], axis=1)
        roots = np.take_along_axis(roots, order[:, :, None], axis=1)
        free = np.take_along_axis(free, order, axis=1)
        keep = np.take_along_axis(keep, order, axis=1)
        pos, rot = (np.take_along_axis(e, order, axis=1) for e in errors)
        Q[~keep] = np.nan
        roots[~keep] = -1
        free[~keep] = 0
        pos[~keep] = rot[~keep] = np.nan
        return Q, keep.sum(axis=1), roots, keep, free, failed, (pos, rot)

    def _looped(
        self, poses: np.ndarray, fid: int, structure: tuple[arm.Chain, arm.Structure],
        tol: float, rest_lock: tuple[ArrayLike | None, object], moved: np.ndarray,
    ) -> branches.IKAllBatchResult:  # fmt: skip
        """:meth:`ik_all_batch` of a family without a batch kernel: :meth:`ik_all` per
        target, one row per branch: its first row within the limits (each revolute joint
        at its lowest turn there), else its first row."""
        chain, found = structure
        frame = self.model.frames[fid].name
        places = found.places_point
        answers = [self._branch_rows(self.ik_all(T[:3, 3] if places else T, frame=frame,
                                                 tol=tol, q0=rest_lock[0],
                                                 lock=rest_lock[1]), chain)
                   for T in poses]  # fmt: skip
        N, B = len(poses), max([len(a[0]) for a in answers], default=0)
        Q = np.full((N, B, self.model.nq), np.nan)
        pos, rot = np.full((N, B), np.nan), np.full((N, B), np.nan)
        roots = np.full((N, B, 3), -1, np.int64)
        free = np.zeros((N, B), np.int64)
        counts = np.array([len(a[0]) for a in answers], np.int64)
        for n, (q, p, r, rt, fr) in enumerate(answers):
            k = len(q)
            Q[n, :k], pos[n, :k], rot[n, :k], roots[n, :k], free[n, :k] = q, p, r, rt, fr
        ok, inside = self._verified(Q, pos, rot, ~np.isnan(pos), tol)
        return branches.IKAllBatchResult(Q, counts, ok, pos, rot, roots, found, not found.exact,
                                         free, moved, inside)  # fmt: skip
