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
from .bases import base_pose, candidate_grid, task_poses, yaw_angles
from .candidates import Verified, brute_force, ranked
from .inverse import InverseReach, inverse_reachability, settings_of, symmetries
from .layers import OffsetLayer, layer_of

__all__ = ["Placement", "placement"]

SCORES = ("reach", "manipulability", "backlash")


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

    @classmethod
    def from_rows(cls, rows: list[Verified], **fields: Any) -> Placement:
        """The answer of the verified candidates ``rows`` (best first), the other fields by
        keyword."""
        reached = np.array([r.reached for r in rows])
        return cls(
            bases=np.array([r.base for r in rows]), reach=reached.mean(axis=1),
            estimate=np.array([r.estimate for r in rows]), reached=reached,
            q=np.array([r.q for r in rows]), score=np.array([r.score for r in rows]),
            **fields,
        )  # fmt: skip

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


@renames.renamed(structure="reach_map")
def placement(
    robot: Robot | OffsetLayer,
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
    """Where to put ``robot`` (or a joint-offset layer, :class:`~toolkit.maps.OffsetLayer`,
    such as a :class:`~toolkit.papers.backlash.Backlash`) so that ``frame`` reaches ``tasks``,
    world tool poses (N, 4, 4) or positions (N, 3); the
    base stands upright in ``region`` [[x_min, y_min], [x_max, y_max]] [m] on a ``step`` [m]
    grid at ``height`` [m], turned by ``yaws`` angles over ``yaw_range`` [rad]. ``scene``:
    obstacles in the world; ``collision_free``: a task counts only free of collision.
    ``score``: ``"reach"`` (the fraction of tasks), or among bases reaching as many, the
    largest mean ``"manipulability"`` or smallest mean ``"backlash"`` tool error (a layer, at
    ``payload`` [kg]). ``verify`` candidates are solved again and returned. ``reach_map``
    (was ``structure=``): an :class:`InverseReach` to reuse, None to build one (``voxel``,
    ``angles``) where the symmetries allow, False for IK at every candidate, or a folder (a
    ``Path``: a Zarr store built once, then read back verified). ``progress``: progress."""
    layer = layer_of(robot)
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
    rows = ranked(robot, layer, poses, heat, xs, ys, z, best_yaw, verify, step, scene,
                   position_only, frame, collision_free, score, payload, seed)  # fmt: skip
    figures["verify_s"] = time.perf_counter() - start
    _warn_if_nothing(robot, rows, len(poses))
    return Placement.from_rows(
        rows, score_name=score, xs=xs, ys=ys, heat=heat, tasks=poses,
        position_only=position_only, method=method, robot_name=robot.name, figures=figures,
    )  # fmt: skip


def _warn_if_nothing(robot: Robot, rows: list[Verified], tasks: int) -> None:
    if rows and rows[0].reached.mean() == 0:
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
    robot.frames.id(frame)
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


def _options(
    score: str,
    layer: OffsetLayer | None,
    payload: float,
    verify: int,
    collision_free: bool,
    scene: Any,
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
        fraction, best_yaw = brute_force(
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
