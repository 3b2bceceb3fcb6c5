"""What one chunk of a map computes: a pure function of (robot or layer, chunk, settings),
so that a chunk gives the same arrays wherever and whenever it runs."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..ik import IKOptions
from ..robot import Robot
from .grid import Grid, axis_frames
from .layers import OffsetLayer

SOLVES = "_solves"  # a chunk's count of the IK solves it ran (toolkit.maps.run pops it)

__all__ = [
    "AccuracySettings",
    "InverseSettings",
    "ReachSettings",
    "accuracy_chunk",
    "backlash_deviation",
    "chunk_seed",
    "compiled_branches",
    "first_usable",
    "inverse_chunk",
    "manipulability",
    "reach_chunk",
]


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


@dataclass(frozen=True)
class InverseSettings:
    """The inputs of an inverse-reachability structure besides the robot and the grid."""

    frame: str | None
    position_only: bool
    angles: int  # bins of the last joint axis's angle from the vertical, over [0, pi]
    tool_in_joint: np.ndarray  # (4, 4) the tool frame in the last joint's frame
    roll_axis: np.ndarray  # (3,) the last joint's axis in its frame
    options: IKOptions
    seed: int
    collision_free: bool
    analytic: bool


def compiled_branches(robot: Robot, frame: str | None) -> bool:
    """Whether every analytic branch of ``frame``'s poses comes from a compiled kernel: a
    family of poses (not one placing a point) with one
    (:attr:`toolkit.ik.analytic.structure.Structure.compiled`) on the compiled kinematics back
    end."""
    found = robot.structure_of(frame)
    return found.compiled and not found.places_point and robot.kinematics.engine.name == "compiled"


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
        "collision_free": s.collision_free, "method": "numeric",  # branches: _every_branch
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
    hit, q = first_usable(robot, found.success, found.q, s.scene if s.collision_free else False)
    return hit.reshape(-1, K), q.reshape(len(centres), K, robot.nq)


def first_usable(
    robot: Robot, valid: np.ndarray, Q: np.ndarray, scene: Any
) -> tuple[np.ndarray, np.ndarray]:
    """(hit (N,), q (N, nq)) of N targets' branches (``valid`` (N, B), ``Q`` (N, B, nq)):
    the first valid branch free of collision (with ``scene``; ``False``: any valid branch),
    NaN where none. Branch k is checked only for the targets whose earlier branches all
    collide, so a target costs one check or two, not one per branch."""
    n = len(valid)
    q = np.full((n, Q.shape[2]), np.nan)
    hit = np.zeros(n, dtype=bool)
    checker = None if scene is False else robot.collision_checker(scene, True)
    for k in range(valid.shape[1]):
        rows = np.flatnonzero(valid[:, k] & ~hit)
        if not len(rows):
            continue
        if checker is not None:
            rows = rows[~checker.in_collision_many(Q[rows, k])]
        hit[rows] = True
        q[rows] = Q[rows, k]
    return hit, q


def manipulability(robot: Robot, q: np.ndarray, frame: str | None) -> np.ndarray:
    J = robot.jacobian(q, frame) if len(q) else np.zeros((0, 6, robot.joints.nv))
    small = J @ np.swapaxes(J, 1, 2) if robot.joints.nv >= 6 else np.swapaxes(J, 1, 2) @ J
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
        score = manipulability(robot, q, s.frame)
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


def backlash_deviation(
    layer: Any, q: np.ndarray, nominal: np.ndarray, frame: str | None
) -> tuple[np.ndarray, np.ndarray]:
    """(position [m], orientation [rad]) errors (M,) of the frame that backlash (``layer``,
    at its payload) causes at commands q (M, nq) whose nominal poses are ``nominal``
    (M, 4, 4); NaN where the backlash fixed point did not converge."""
    out = layer.solve(q)
    actual = layer.robot.fk(out.theta, frame)
    ok = np.atleast_1d(out.converged)
    dp = np.where(ok, np.linalg.norm(actual[:, :3, 3] - nominal[:, :3, 3], axis=1), np.nan)
    dr = np.where(ok, _rotation_angle(actual[:, :3, :3], nominal[:, :3, :3]), np.nan)
    return dp, dr


def accuracy_chunk(
    layer: OffsetLayer,
    grid: Grid,
    idx: tuple[int, int, int],
    s: AccuracySettings,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """Per payload and k_H (axes 0 and 1), the tool position [m] and orientation [rad]
    errors caused by backlash over the solved orientations of each voxel of chunk ``idx``:
    ``position`` and ``rotation`` of shape (P, H, 3, cx, cy, cz) holding mean, p95, max;
    with compensation, ``compensated`` the same for the position after compensation."""
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
            each = layer.with_payload(payload).with_parameters(layer.delta, np.array(k_h))
            dp, dr = backlash_deviation(each, q, nominal, s.reach.frame)
            position[a, b] = _stats(dp, voxel_of, m)
            rotation[a, b] = _stats(dr, voxel_of, m)
            if s.compensate:
                command = each.command_for(q)
                back = each.solve(command, start=q)
                reached = robot.fk(back.theta, s.reach.frame)[:, :3, 3]
                valid = np.atleast_1d(back.converged) & np.array(
                    [robot.joints.within_limits(c) for c in command]
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


def _cell_poses(centres: np.ndarray, s: InverseSettings) -> np.ndarray:
    """Tool poses (m * angles, 4, 4) of the cells at ``centres``: the last joint's origin
    at the centre, its axis leaning towards +x by each bin's middle angle."""
    theta = (np.arange(s.angles) + 0.5) * np.pi / s.angles
    a = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    u = axis_frames(s.roll_axis[None])[0]
    R = axis_frames(a) @ u.T  # R @ roll_axis = a
    joint = np.tile(np.eye(4), (len(centres), s.angles, 1, 1))
    joint[:, :, :3, :3] = R[None]
    joint[:, :, :3, 3] = centres[:, None]
    return (joint @ s.tool_in_joint).reshape(-1, 4, 4)


def inverse_chunk(
    robot: Robot,
    grid: Grid,
    idx: tuple[int, int, int],
    s: InverseSettings,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """``reach`` (cx, cy, cz, angles) of the cells of chunk ``idx`` of an
    inverse-reachability structure (:mod:`toolkit.maps.inverse`)."""
    _threads(threads)
    centres = grid.chunk_centers(idx)
    shape = centres.shape[:3]
    centres = centres.reshape(-1, 3)
    reach = np.zeros((len(centres), s.angles), dtype=bool)
    near = grid.in_reach(centres)
    solves = 0
    if near.any() and s.position_only:  # (r, 0, z): the distance from the axis and height
        res = robot.ik_batch(
            centres[near], frame=s.frame, options=s.options, collision_free=s.collision_free,
            seed=chunk_seed(s.seed, idx, 0), method="numeric",
        )  # fmt: skip
        reach[near, 0], solves = res.success, int(near.sum())
    elif near.any():
        poses = _cell_poses(centres[near], s)
        if s.analytic:
            found = robot.ik_all_batch(poses, frame=s.frame, tol=s.options.tol)
            scene = None if s.collision_free else False  # None: self-collision alone
            hit, _ = first_usable(robot, found.success, found.q, scene)
        else:
            hit = robot.ik_batch(
                poses, frame=s.frame, options=s.options, collision_free=s.collision_free,
                seed=chunk_seed(s.seed, idx, 1), method="numeric",  # s.analytic: above
            ).success  # fmt: skip
        reach[near] = hit.reshape(-1, s.angles)
        solves = len(poses)
    return {"reach": reach.reshape(*shape, s.angles), SOLVES: np.array(solves)}
