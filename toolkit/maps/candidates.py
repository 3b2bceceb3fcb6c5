"""Base placement's candidates: every (x, y) over the yaws by IK where no structure serves
(:func:`brute_force`), the grid cells worth verifying (:func:`choose`), and each verified
again at its base with the scene as the base sees it (:func:`ranked`): reached tasks, their
configurations and the secondary score."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..collision import Scene
from ..errors import InvalidParameterError
from ..robot import Robot, checker_for
from .bases import base_pose, scene_from_base
from .compute import backlash_deviation, compiled_branches, first_usable, manipulability
from .layers import OffsetLayer
from .run import Progress

__all__ = ["MAX_PAIR_SOLVES", "ROUNDS", "Verified", "brute_force", "choose", "ranked"]

MAX_PAIR_SOLVES = 2_000_000  # IK at every candidate: beyond this, ask for a coarser grid
ROUNDS = 10  # at most this many groups of ``verify`` candidates are verified


class Verified(NamedTuple):
    """One verified candidate: the base (x, y, z, yaw), which tasks it reaches (N,), the
    configuration reaching each (N, nq), the secondary score and the estimate it had."""

    base: np.ndarray
    reached: np.ndarray
    q: np.ndarray
    score: float
    estimate: float


def _in_base(tasks: np.ndarray, base: np.ndarray) -> np.ndarray:
    return np.linalg.inv(base_pose(base)) @ tasks


def _solve(
    robot: Robot, targets: np.ndarray, position_only: bool, frame: str | None,
    scene: Scene | None, collision_free: bool, seed: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(success (N,), q (N, nq)) of tool targets in the base frame: from every analytic
    branch where the arm has a compiled structure, else by the numeric batch IK."""
    if not position_only and compiled_branches(robot, frame):
        found = robot.ik_all_batch(targets, frame=frame)
        return first_usable(robot, found.success, found.q, scene if collision_free else False)
    res = robot.ik_batch(
        targets[:, :3, 3] if position_only else targets, frame=frame, scene=scene,
        collision_free=collision_free, seed=seed, restarts=20, method="numeric",
    )  # fmt: skip
    return res.success, res.q


def brute_force(
    robot: Robot, tasks: np.ndarray, xy: np.ndarray, z: float, yaws: np.ndarray,
    position_only: bool, frame: str | None, collision_free: bool, seed: int, progress: bool,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(fraction (C,), best yaw (C,)) of every (x, y) candidate over the yaws, by IK."""
    solves = len(xy) * len(yaws) * len(tasks)
    if solves > MAX_PAIR_SOLVES:
        raise InvalidParameterError(
            f"{robot.name} has no inverse-reachability structure here, so every (base, task) "
            f"pair is solved by IK: {solves:,} solves (more than {MAX_PAIR_SOLVES:,}); choose a "
            "larger step, fewer yaws or a smaller region"
        )
    frac = np.zeros((len(xy), len(yaws)))
    bar = Progress(len(yaws), progress, "place (IK at every candidate)", "yaws")
    try:
        for j, yaw in enumerate(yaws):
            bases = np.column_stack([xy, np.full(len(xy), z), np.full(len(xy), yaw)])
            targets = np.concatenate([_in_base(tasks, b) for b in bases])
            ok, _ = _solve(robot, targets, position_only, frame, None, collision_free, seed + j)
            frac[:, j] = ok.reshape(len(xy), len(tasks)).mean(axis=1)
            bar.step(len(targets))
    finally:
        bar.close()
    best = np.argmax(frac, axis=1)
    return frac[np.arange(len(xy)), best], yaws[best]


def choose(heat: np.ndarray, count: int, spacing: int, blur: int) -> list[tuple[int, int]]:
    """Up to ``count`` grid cells, best estimate first (ties: the better neighbourhood,
    ``blur`` passes of a 3x3 mean, which keeps away from the reach's edge), each
    ``spacing`` cells from the ones before."""
    around = heat
    for _ in range(blur):
        pad = np.pad(around, 1, mode="edge")
        around = np.mean([pad[1 + dx : pad.shape[0] - 1 + dx, 1 + dy : pad.shape[1] - 1 + dy]
                          for dx in (-1, 0, 1) for dy in (-1, 0, 1)], axis=0)  # fmt: skip
    order = np.lexsort((-around.ravel(), -heat.ravel()))
    chosen: list[tuple[int, int]] = []
    for flat in order:
        i, j = divmod(int(flat), heat.shape[1])
        if all(max(abs(i - a), abs(j - b)) >= spacing for a, b in chosen):
            chosen.append((i, j))
            if len(chosen) == count:
                break
    return chosen


def _secondary(
    robot: Robot, layer: OffsetLayer | None, score: str, q: np.ndarray, ok: np.ndarray,
    payload: float, frame: str | None,
) -> float:  # fmt: skip
    if score == "reach" or not ok.any():
        return float(ok.mean())
    if score == "manipulability":
        return float(manipulability(robot, q[ok], frame).mean())
    assert layer is not None  # the backlash score needs a layer (checked by placement)
    each = layer.with_payload(payload)
    err, _ = backlash_deviation(each, q[ok], robot.fk(q[ok], frame), frame)
    converged = err[np.isfinite(err)]  # a fixed point that did not converge is left out
    return float(converged.mean()) if len(converged) else math.inf


def _verify(
    robot: Robot, layer: OffsetLayer | None, poses: np.ndarray, base: np.ndarray,
    scene: Scene | None, position_only: bool, frame: str | None, collision_free: bool,
    score: str, payload: float, seed: int,
) -> tuple[np.ndarray, np.ndarray, float]:  # fmt: skip
    """(reached (N,), q (N, nq), secondary score) of the tasks from one base, solved again
    there with the scene as the base sees it."""
    seen = scene_from_base(scene, base_pose(base))
    if collision_free and seen is not None and checker_for(robot, seen).base_hits:
        # the base's own shapes hit an obstacle (not a support): nothing is reached there
        none = np.zeros(len(poses), dtype=bool)
        q = np.full((len(poses), robot.nq), np.nan)
        return none, q, _secondary(robot, layer, score, q, none, payload, frame)
    ok, q = _solve(robot, _in_base(poses, base), position_only, frame, seen, collision_free, seed)
    return ok, q, _secondary(robot, layer, score, q, ok, payload, frame)


def ranked(
    robot: Robot, layer: OffsetLayer | None, poses: np.ndarray, heat: np.ndarray, xs: np.ndarray,
    ys: np.ndarray, z: float, best_yaw: np.ndarray, verify: int, step: float,
    scene: Scene | None, position_only: bool, frame: str | None, collision_free: bool,
    score: str, payload: float, seed: int,
) -> list[Verified]:  # fmt: skip
    """The verified candidates, best first. They
    are verified ``verify`` at a time, in the order of their estimates, until the best
    verified reach is at least the next estimate (the scene's obstacles, which the
    estimate ignores, can only lower a reach) or ``ROUNDS`` groups were verified (always,
    for a secondary score)."""
    chosen = choose(heat, verify * ROUNDS, spacing=2, blur=max(1, round(0.1 / step)))
    rows: list[Verified] = []
    for k, (i, j) in enumerate(chosen):
        if score == "reach" and k and k % verify == 0:  # other scores use every round
            if max(r.reached.mean() for r in rows) >= heat[i, j]:
                break  # no later candidate is estimated to reach more
        base = np.array([xs[i], ys[j], z, best_yaw[i * len(ys) + j]])
        reached, q, secondary = _verify(robot, layer, poses, base, scene, position_only, frame,
                                        collision_free, score, payload, seed)  # fmt: skip
        rows.append(Verified(base, reached, q, secondary, float(heat[i, j])))
    sign = -1.0 if score == "backlash" else 1.0  # the smallest error first
    rows.sort(key=lambda r: (-float(r.reached.mean()), -sign * r.score))
    return rows[:verify]
