"""Base placement: where to put a robot so that its tool reaches given poses.

:func:`placement` scores every candidate base of a floor region (a grid of x, y at one
height, and yaw angles) by the fraction of the tasks it reaches, ranks them, and
**verifies** the best: each task is solved again by IK at that base (every analytic branch
where the arm has a compiled structure, else the numeric IK), free of collision with the
robot itself and with the ``scene`` (obstacles fixed in the world: the base moves, the scene
does not), so a returned placement never claims a task it cannot reach.

The estimate comes from an inverse-reachability structure (:mod:`toolkit.maps.inverse`)
where the arm's symmetries allow one: a lookup per (base, task), and the same for every
yaw. Otherwise every (candidate, task) pair is solved by IK without the scene (said in
``method``); the verification is the same either way. Estimates ignore the scene's
obstacles; the verified answers include them.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Scene
from ..common import caller_level, renames
from ..common import validate as _validate
from ..errors import InvalidParameterError, UnreachableTargetsWarning
from ..robot import Robot, as_robot
from .bases import base_pose, candidate_grid, scene_from_base, task_poses, yaw_angles
from .compute import backlash_deviation, compiled_branches, first_usable, manipulability
from .inverse import InverseReach, inverse_reachability, settings_of, symmetries
from .run import Progress

__all__ = ["Placement", "placement"]

MAX_PAIR_SOLVES = 2_000_000  # IK at every candidate: beyond this, ask for a coarser grid
SCORES = ("reach", "manipulability", "backlash")
ROUNDS = 10  # at most this many groups of ``verify`` candidates are verified


@dataclass(frozen=True)
class Placement:
    """The answer of :func:`placement`.

    Attributes:
        bases: the verified candidates (K, 4): x, y, z [m] and yaw [rad], best first.
        reach: the fraction of the tasks each reaches, verified (K,).
        estimate: the fraction the estimate gave them (K,).
        reached: which tasks each reaches, verified (K, N).
        q: the joint configuration reaching each task (K, N, nq); NaN where none.
        score: the secondary criterion of each (K,): mean manipulability of the reached
            tasks (``score="manipulability"``), mean backlash tool position error [m]
            over the tasks whose backlash fixed point converged, inf if none
            (``"backlash"``), or the reach again (``"reach"``).
        xs, ys: the candidate grid [m]; heat: the estimated fraction reached at each
            (x, y) (nx, ny), the best over the yaws.
        tasks: the task poses (N, 4, 4) in the world.
        method: how the estimate was made.
        figures: seconds of the structure's build, the estimate and the verification.
    """

    bases: np.ndarray
    reach: np.ndarray
    estimate: np.ndarray
    reached: np.ndarray
    q: np.ndarray
    score: np.ndarray
    score_name: str
    xs: np.ndarray
    ys: np.ndarray
    heat: np.ndarray
    tasks: np.ndarray
    position_only: bool
    method: str
    robot_name: str = ""
    figures: dict[str, float] = field(default_factory=dict)

    @property
    def best(self) -> np.ndarray:
        """The best base (x, y, z, yaw)."""
        return self.bases[0]

    def best_pose(self) -> np.ndarray:
        """The best base as a 4x4 pose in the world."""
        return base_pose(self.bases[0])

    def draw(self, path: Any = None, ax: Any = None) -> Any:
        """The region as a heat map of the estimated fraction reached, the tasks (x, y) and
        the verified candidates (the best as a star); saved to ``path`` when given."""
        from .draw import draw_placement

        return draw_placement(self, path, ax)


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
        collision_free=collision_free, seed=seed, restarts=20,
    )  # fmt: skip
    return res.success, res.q


def _brute_force(
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


def _choose(heat: np.ndarray, count: int, spacing: int, blur: int) -> list[tuple[int, int]]:
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
    robot: Robot, layer: Any, score: str, q: np.ndarray, ok: np.ndarray, payload: float,
    frame: str | None,
) -> float:  # fmt: skip
    if score == "reach" or not ok.any():
        return float(ok.mean())
    if score == "manipulability":
        return float(manipulability(robot, q[ok], frame).mean())
    from ..papers.backlash import Backlash

    each = Backlash(robot, layer.delta, layer.k_h, layer.nominal_torque, payload)
    err, _ = backlash_deviation(each, q[ok], robot.fk(q[ok], frame), frame)
    converged = err[np.isfinite(err)]  # a fixed point that did not converge is left out
    return float(converged.mean()) if len(converged) else math.inf


@renames.renamed(structure="reach_map")
def placement(
    robot: Any,
    tasks: ArrayLike,
    region: ArrayLike,
    *,
    height: float = 0.0,
    step: float = 0.02,
    yaws: int = 36,
    yaw_range: ArrayLike = (-math.pi, math.pi),
    scene: Scene | None = None,
    collision_free: bool = True,
    score: str = "reach",
    payload: float = 0.0,
    verify: int = 10,
    frame: str | None = None,
    reach_map: InverseReach | bool | os.PathLike[str] | None = None,
    voxel: float = 0.03,
    angles: int = 30,
    seed: int = 0,
    progress: bool = False,
) -> Placement:
    """Where to put ``robot`` (or a :class:`~toolkit.papers.backlash.Backlash` layer) so
    that ``frame`` reaches ``tasks``, world tool poses (N, 4, 4) or positions (N, 3); the
    base stands upright in ``region`` [[x_min, y_min], [x_max, y_max]] [m] on a ``step`` [m]
    grid at ``height`` [m], turned by ``yaws`` angles over ``yaw_range`` [rad]. ``scene``:
    obstacles in the world; ``collision_free``: a task counts only free of collision.
    ``score``: ``"reach"`` (the fraction of tasks), or among bases reaching as many, the
    largest mean ``"manipulability"`` or smallest mean ``"backlash"`` tool error (a layer, at
    ``payload`` [kg]). ``verify`` candidates are solved again and returned. ``reach_map``
    (was ``structure=``): an :class:`InverseReach` to reuse, None to build one (``voxel``,
    ``angles``) where the symmetries allow, False for IK at every candidate, or a folder (a
    ``Path``: a Zarr store built once, then read back verified). ``progress``: progress."""
    layer = _layer(robot)
    robot = as_robot(layer.robot if layer is not None else robot)
    poses, position_only = task_poses(tasks)
    step = _validate.number(step, "step [m]", lower=1e-3, strict=True)
    z = _validate.number(height, "height [m]")
    xs, ys = candidate_grid(region, step)
    yaw_set = yaw_angles(yaws, yaw_range)
    score, payload, verify, collision_free = _options(score, layer, payload, verify,
                                                      collision_free, scene)  # fmt: skip
    reach = _checked(robot, frame, voxel, angles, seed, progress, reach_map)
    start = time.perf_counter()
    built = _structure(robot, reach, position_only, frame, collision_free, voxel, angles,
                       seed, progress)  # fmt: skip
    figures = {"structure_s": time.perf_counter() - start}
    start = time.perf_counter()
    heat, best_yaw, method = _estimate(robot, built, poses, xs, ys, z, yaw_set, position_only,
                                       frame, collision_free, seed, progress)  # fmt: skip
    figures["estimate_s"] = time.perf_counter() - start
    start = time.perf_counter()
    rows = _ranked(robot, layer, poses, heat, xs, ys, z, best_yaw, verify, step, scene,
                   position_only, frame, collision_free, score, payload, seed)  # fmt: skip
    figures["verify_s"] = time.perf_counter() - start
    _warn_if_nothing(robot, rows, len(poses))
    columns = [np.array([r[k] for r in rows]) for k in range(5)]  # base, ok, q, score, est
    return Placement(
        columns[0], columns[1].mean(axis=1), columns[4], columns[1], columns[2], columns[3],
        score, xs, ys, heat, poses, position_only, method, robot.name, figures,
    )  # fmt: skip


def _warn_if_nothing(robot: Robot, rows: list[tuple[Any, ...]], tasks: int) -> None:
    if rows and rows[0][1].mean() == 0:
        warnings.warn(
            f"{robot.name}: no candidate base of the region reaches any of the {tasks} "
            "tasks (verified); widen the region, change the height, or check the tasks' frame",
            UnreachableTargetsWarning,
            stacklevel=caller_level(),
        )


def _checked(
    robot: Robot, frame: str | None, voxel: float, angles: int, seed: int, progress: bool,
    structure: object,
) -> object:  # fmt: skip
    """The frame and the structure's settings, checked before any work (even where no
    structure is built); a store folder comes back as a str."""
    robot.frame_id(frame)
    _validate.number(voxel, "voxel [m]", lower=1e-3, strict=True)
    _validate.count(angles, "angles", minimum=1, maximum=720)
    _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    _validate.flag(progress, "progress")
    if isinstance(structure, str):  # a typo must not become a folder and minutes of work
        raise InvalidParameterError(
            f"reach_map={structure!r:.60}: an InverseReach, None, False, or the store's folder "
            "as a pathlib.Path (text is not taken for a folder)"
        )
    if isinstance(structure, os.PathLike):
        folder = os.fspath(structure)
        if not str(folder).strip():
            raise InvalidParameterError("reach_map: an empty folder name; give the store's folder")
        return str(folder)
    if structure is not None and structure is not False:
        settings_of(structure)
    return structure


def _layer(value: Any) -> Any:
    """A Backlash layer given in place of the robot, or None."""
    from ..papers.backlash import Backlash

    return value if isinstance(value, Backlash) else None


def _options(
    score: str, layer: Any, payload: float, verify: int, collision_free: bool, scene: Any
) -> tuple[str, float, int, bool]:
    score = _validate.one_of(score, "score", SCORES)
    if score == "backlash" and layer is None:
        raise InvalidParameterError("score='backlash' needs a Backlash layer in place of the robot")
    if scene is not None and not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a toolkit Scene, got {scene!r:.80}")
    return (
        score,
        _validate.number(payload, "payload [kg]", lower=0.0),
        _validate.count(verify, "verify", minimum=1, maximum=1000),
        _validate.flag(collision_free, "collision_free"),
    )


def _structure(
    robot: Robot, structure: Any, position_only: bool, frame: str | None,
    collision_free: bool, voxel: float, angles: int, seed: int, progress: bool,
) -> InverseReach | None:  # fmt: skip
    """The structure to estimate with: the one given, a new one where the arm's symmetries
    allow, or None (IK at every candidate)."""
    if structure is False:
        return None
    if structure is None or isinstance(structure, str):
        stored = isinstance(structure, str)  # a store folder: the symmetries must allow it
        sym = symmetries(robot, frame)
        if not stored and not (sym.yaw and (position_only or sym.roll)):
            return None
        return inverse_reachability(
            robot, voxel=voxel, angles=angles, position_only=position_only, frame=frame,
            collision_free=collision_free, seed=seed, progress=progress,
            store=structure, resume=stored,
        )  # fmt: skip
    built = settings_of(structure)
    if built.position_only != position_only or built.frame != (frame or robot.tip):
        raise InvalidParameterError(
            f"the structure is for {'positions' if built.position_only else 'poses'} of "
            f"{built.frame}; the tasks are {'positions' if position_only else 'poses'} of "
            f"{frame or robot.tip}"
        )
    return built


def _verify(
    robot: Robot, layer: Any, poses: np.ndarray, base: np.ndarray, scene: Scene | None,
    position_only: bool, frame: str | None, collision_free: bool, score: str,
    payload: float, seed: int,
) -> tuple[np.ndarray, np.ndarray, float]:  # fmt: skip
    """(reached (N,), q (N, nq), secondary score) of the tasks from one base, solved again
    there with the scene as the base sees it."""
    seen = scene_from_base(scene, base_pose(base))
    if collision_free and seen is not None and robot.base_collisions(seen):
        # the base's own shapes hit an obstacle (not a support): nothing is reached there
        none = np.zeros(len(poses), dtype=bool)
        q = np.full((len(poses), robot.nq), np.nan)
        return none, q, _secondary(robot, layer, score, q, none, payload, frame)
    ok, q = _solve(robot, _in_base(poses, base), position_only, frame, seen, collision_free, seed)
    return ok, q, _secondary(robot, layer, score, q, ok, payload, frame)


def _estimate(
    robot: Robot, built: InverseReach | None, poses: np.ndarray, xs: np.ndarray,
    ys: np.ndarray, z: float, yaw_set: np.ndarray, position_only: bool, frame: str | None,
    collision_free: bool, seed: int, progress: bool,
) -> tuple[np.ndarray, np.ndarray, str]:  # fmt: skip
    """(heat (nx, ny): the estimated fraction reached, the yaw of each (x, y), method)."""
    grid_xy = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1).reshape(-1, 2)
    if built is not None:
        lookup = poses[:, :3, 3] if position_only else poses
        where = np.column_stack([grid_xy, np.full(len(grid_xy), z)])
        fraction = built.reaches(where, lookup).mean(axis=1)
        best_yaw = np.full(len(grid_xy), yaw_set[len(yaw_set) // 2])  # yaw-free: any
        method = (f"inverse reachability ({'2' if position_only else '4'}-D, "
                  f"{built.method}; the estimate holds for every yaw)")  # fmt: skip
    else:
        fraction, best_yaw = _brute_force(
            robot,
            poses,
            grid_xy,
            z,
            yaw_set,
            position_only,
            frame,
            collision_free,
            seed,
            progress,
        )
        sym = symmetries(robot, frame)
        why = sym.yaw_reason if not sym.yaw else sym.roll_reason
        method = f"IK at every candidate (no inverse-reachability structure: {why})"
    return fraction.reshape(len(xs), len(ys)), best_yaw, method


def _ranked(
    robot: Robot, layer: Any, poses: np.ndarray, heat: np.ndarray, xs: np.ndarray,
    ys: np.ndarray, z: float, best_yaw: np.ndarray, verify: int, step: float,
    scene: Scene | None, position_only: bool, frame: str | None, collision_free: bool,
    score: str, payload: float, seed: int,
) -> list[tuple[Any, ...]]:  # fmt: skip
    """The verified candidates, best first: (base, reached, q, secondary, estimate). They
    are verified ``verify`` at a time, in the order of their estimates, until the best
    verified reach is at least the next estimate (the scene's obstacles, which the
    estimate ignores, can only lower a reach) or ``ROUNDS`` groups were verified (always,
    for a secondary score)."""
    chosen = _choose(heat, verify * ROUNDS, spacing=2, blur=max(1, round(0.1 / step)))
    rows: list[tuple[Any, ...]] = []
    for k, (i, j) in enumerate(chosen):
        if score == "reach" and k and k % verify == 0:  # other scores use every round
            if max(r[1].mean() for r in rows) >= heat[i, j]:
                break  # no later candidate is estimated to reach more
        base = np.array([xs[i], ys[j], z, best_yaw[i * len(ys) + j]])
        found = _verify(robot, layer, poses, base, scene, position_only, frame, collision_free,
                        score, payload, seed)  # fmt: skip
        rows.append((base, *found, float(heat[i, j])))
    sign = -1.0 if score == "backlash" else 1.0  # the smallest error first
    rows.sort(key=lambda r: (-float(r[1].mean()), -sign * r[3]))
    return rows[:verify]
