"""What one chunk of a map computes: a pure function of (robot or layer, chunk, settings),
so that a chunk gives the same arrays wherever and whenever it runs."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..ik import IKOptions
from ..robot import Robot
from .grid import Grid

SOLVES = "_solves"  # a chunk's count of the IK solves it ran (toolkit.maps.run pops it)

__all__ = ["AccuracySettings", "ReachSettings", "accuracy_chunk", "chunk_seed", "reach_chunk"]


@dataclass(frozen=True)
class ReachSettings:
    """The inputs of a reachability map besides the robot and the grid."""

    orientations: np.ndarray  # (K, 3, 3)
    position_only: bool
    mask: tuple[float, ...] | None
    frame: str | None
    options: IKOptions
    seed: int
    starts: int = 1  # position-only: solves per voxel, from random starts (accuracy maps)
    scene: Any = None  # a toolkit Scene whose objects the solutions must not hit
    collision_free: bool = False  # only collision-free solutions count
    analytic: bool = False  # orientations decided from every analytic branch (exact)


@dataclass(frozen=True)
class AccuracySettings:
    """The inputs of a backlash-accuracy map besides the layer and the grid."""

    reach: ReachSettings
    payloads: tuple[float, ...]
    k_h: tuple[tuple[float, ...], ...]  # one per-joint k_H per map layer
    compensate: bool


def chunk_seed(seed: int, idx: tuple[int, int, int], stage: int) -> int:
    """The IK seed of one stage of one chunk: fixed by (seed, chunk, stage) alone."""
    state = np.random.SeedSequence([int(seed), *map(int, idx), int(stage)]).generate_state(1)
    return int(state[0] % (2**31 - 1))


def _threads(threads: int | None) -> None:
    if threads is not None:
        import numba

        most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
        numba.set_num_threads(max(1, min(int(threads), most)))


def _solutions(
    robot: Robot, grid: Grid, idx: tuple[int, int, int], s: ReachSettings
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """(centres (m, 3), in-reach flags (m,), success (m, K), solved q (m, K, nq), IK solves
    run) of a chunk: a position-only solve per voxel, then each orientation from that
    solution."""
    centres = grid.chunk_centers(idx).reshape(-1, 3)
    m, K = len(centres), (s.starts if s.position_only else len(s.orientations))
    success = np.zeros((m, K), dtype=bool)
    qs = np.full((m, K, robot.nq), np.nan)
    near = grid.in_reach(centres)
    if not near.any():
        return centres, near, success, qs, 0
    # a position-only map solves with its mask; the position stage of an oriented map
    # solves the full position (its mask applies to the orientations)
    position_mask = list(s.mask) if s.position_only and s.mask is not None else None
    common: dict[str, Any] = {
        "frame": s.frame, "options": s.options, "scene": s.scene,
        "collision_free": s.collision_free,
    }  # fmt: skip
    if s.position_only and K > 1:  # K solutions per voxel, from K random starts
        rng = np.random.default_rng(chunk_seed(s.seed, idx, 2))
        spread = robot.ik_batch(
            np.repeat(centres[near], K, axis=0),
            robot.random_q(int(near.sum()) * K, seed=rng),
            mask=position_mask,
            seed=chunk_seed(s.seed, idx, 0),
            **common,
        )
        success[near] = spread.success.reshape(-1, K)
        qs[near] = spread.q.reshape(-1, K, robot.nq)
        return centres, near, success, qs, len(spread.success)
    if s.analytic and not s.position_only:
        success[near], qs[near] = _every_branch(robot, centres[near], s)
        return centres, near, success, qs, int(near.sum()) * K
    first = robot.ik_batch(
        centres[near],
        mask=position_mask,
        seed=chunk_seed(s.seed, idx, 0),
        restarts=max(s.options.restarts, 8),
        **common,
    )
    if s.position_only:
        success[near, 0] = first.success
        qs[near, 0] = first.q
        return centres, near, success, qs, len(first.success)
    rows = np.flatnonzero(near)[first.success]
    if len(rows):
        success[rows], qs[rows] = _orientations(robot, centres[rows], first.q[first.success],
                                                s, idx, common)  # fmt: skip
    return centres, near, success, qs, len(first.success) + len(rows) * K


def _orientations(
    robot: Robot, centres: np.ndarray, q0: np.ndarray, s: ReachSettings,
    idx: tuple[int, int, int], common: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(success (m, K), q (m, K, nq)) of each orientation at each centre, by the batch IK
    from that centre's position solution ``q0``."""
    K = len(s.orientations)
    targets = np.tile(np.eye(4), (len(centres), K, 1, 1))
    targets[:, :, :3, :3] = s.orientations[None]
    targets[:, :, :3, 3] = centres[:, None, :]
    res = robot.ik_batch(
        targets.reshape(-1, 4, 4),
        np.repeat(q0, K, axis=0),
        mask=None if s.mask is None else list(s.mask),
        seed=chunk_seed(s.seed, idx, 1),
        **common,
    )
    return res.success.reshape(len(centres), K), res.q.reshape(len(centres), K, robot.nq)


def _every_branch(
    robot: Robot, centres: np.ndarray, s: ReachSettings
) -> tuple[np.ndarray, np.ndarray]:
    """(success (m, K), q (m, K, nq)) of every orientation at every centre, decided from
    all the analytic branches (``Robot.ik_all_batch``): an orientation counts when some
    branch is verified, within the limits and (with ``collision_free``) free of
    collision; its q is the first such branch."""
    K = len(s.orientations)
    targets = np.tile(np.eye(4), (len(centres), K, 1, 1))
    targets[:, :, :3, :3] = s.orientations[None]
    targets[:, :, :3, 3] = centres[:, None, :]
    found = robot.ik_all_batch(targets.reshape(-1, 4, 4), frame=s.frame, tol=s.options.tol)
    ok = found.success.copy()
    if s.collision_free and ok.any():
        checker = robot._checker(s.scene, True)
        assert checker is not None
        ok[ok] = ~checker.in_collision_many(found.q[ok])
    first = np.argmax(ok, axis=1)  # the first usable branch (0 when none: masked below)
    q = found.q[np.arange(len(ok)), first]
    hit = ok.any(axis=1)
    q[~hit] = np.nan
    return hit.reshape(-1, K), q.reshape(len(centres), K, robot.nq)


def _manipulability(robot: Robot, q: np.ndarray, frame: str | None) -> np.ndarray:
    J = robot.jacobian(q, frame) if len(q) else np.zeros((0, 6, robot.nv))
    small = J @ np.swapaxes(J, 1, 2) if robot.nv >= 6 else np.swapaxes(J, 1, 2) @ J
    return np.sqrt(np.clip(np.linalg.det(small), 0.0, None))


def reach_chunk(
    robot: Robot,
    grid: Grid,
    idx: tuple[int, int, int],
    s: ReachSettings,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """index, best_q, best_rotation of the voxels of chunk ``idx`` (chunk-shaped arrays)."""
    _threads(threads)
    _, _, success, qs, solves = _solutions(robot, grid, idx, s)
    m = len(success)
    best_q = np.full((m, robot.nq), np.nan)
    best_rotation = np.full((m, 3, 3), np.nan)
    solved = np.argwhere(success)
    if len(solved):
        q = qs[solved[:, 0], solved[:, 1]]
        score = _manipulability(robot, q, s.frame)
        order = np.lexsort((-score, solved[:, 0]))  # per voxel, best first
        first = order[np.r_[True, np.diff(solved[order, 0]) != 0]]
        voxels = solved[first, 0]
        best_q[voxels] = q[first]
        if s.position_only:
            best_rotation[voxels] = robot.fk(q[first], s.frame)[:, :3, :3]
        else:
            best_rotation[voxels] = s.orientations[solved[first, 1]]
    shape = grid.chunk_centers(idx).shape[:3]
    return {
        "index": success.mean(axis=1).reshape(shape),
        "best_q": best_q.reshape(*shape, robot.nq),
        "best_rotation": best_rotation.reshape(*shape, 3, 3),
        SOLVES: np.array(solves),
    }


def _stats(errors: np.ndarray, voxel_of: np.ndarray, m: int) -> np.ndarray:
    """(3, m): mean, 95th percentile and max of ``errors`` per voxel (NaN where none)."""
    out = np.full((3, m), np.nan)
    for v in np.unique(voxel_of):
        e = errors[voxel_of == v]
        e = e[np.isfinite(e)]
        if len(e):
            out[:, v] = (e.mean(), np.percentile(e, 95), e.max())
    return out


def _rotation_angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    cos = (np.einsum("nij,nij->n", Ra, Rb) - 1) / 2
    return np.arccos(np.clip(cos, -1.0, 1.0))


def accuracy_chunk(
    layer: Any,
    grid: Grid,
    idx: tuple[int, int, int],
    s: AccuracySettings,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """Per payload and k_H (axes 0 and 1), the tool position [m] and orientation [rad]
    errors caused by backlash over the solved orientations of each voxel of chunk ``idx``:
    ``position`` and ``rotation`` of shape (P, H, 3, cx, cy, cz) holding mean, p95, max;
    with compensation, ``compensated`` the same for the position after compensation."""
    from ..papers.backlash import Backlash

    robot: Robot = layer.robot
    shape = grid.chunk_centers(idx).shape[:3]
    _threads(threads)
    _, _, success, qs, solves = _solutions(robot, grid, idx, s.reach)
    m = success.shape[0]
    solved = np.argwhere(success)
    q = qs[solved[:, 0], solved[:, 1]]
    voxel_of = solved[:, 0]
    nominal = robot.fk(q, s.reach.frame) if len(q) else np.zeros((0, 4, 4))
    P, H = len(s.payloads), len(s.k_h)
    position = np.full((P, H, 3, m), np.nan)
    rotation = np.full((P, H, 3, m), np.nan)
    compensated = np.full((P, H, 3, m), np.nan)
    for a, payload in enumerate(s.payloads):
        for b, k_h in enumerate(s.k_h):
            if not len(q):
                continue
            each = Backlash(robot, layer.delta, np.array(k_h), layer.nominal_torque, payload)
            out = each.solve(q)
            actual = robot.fk(out.theta, s.reach.frame)
            ok = np.atleast_1d(out.converged)
            dp = np.where(ok, np.linalg.norm(actual[:, :3, 3] - nominal[:, :3, 3], axis=1), np.nan)
            dr = np.where(ok, _rotation_angle(actual[:, :3, :3], nominal[:, :3, :3]), np.nan)
            position[a, b] = _stats(dp, voxel_of, m)
            rotation[a, b] = _stats(dr, voxel_of, m)
            if s.compensate:
                command = each.command_for(q)
                back = each.solve(command, start=q)
                reached = robot.fk(back.theta, s.reach.frame)[:, :3, 3]
                valid = np.atleast_1d(back.converged) & np.array(
                    [robot.within_limits(c) for c in command]
                )
                dc = np.where(valid, np.linalg.norm(reached - nominal[:, :3, 3], axis=1), np.nan)
                compensated[a, b] = _stats(dc, voxel_of, m)
    result = {
        "position": position.reshape(P, H, 3, *shape),
        "rotation": rotation.reshape(P, H, 3, *shape),
        "reachable": (success.mean(axis=1) > 0).reshape(shape),
        SOLVES: np.array(solves),
    }
    if s.compensate:
        result["compensated"] = compensated.reshape(P, H, 3, *shape)
    return result
