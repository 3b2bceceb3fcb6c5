"""Inverse reachability: one structure per robot (and tool frame) that says, for any base
placed upright on a floor and any tool pose, whether the arm reaches it, by a lookup.

The structure uses the arm's symmetries, read from its model (never its name):

* **yaw**: the first moving joint is a revolute joint about the base's vertical axis (its
  axis parallel to z and through the base origin) that turns fully (a range of 2 pi or a
  continuous joint). Turning the base about z then changes only that joint's angle, so
  reach depends on where a pose is *relative to the azimuth*, not on the azimuth itself.
* **roll**: the last moving joint (the tool frame's parent) is revolute and turns fully.
  Rolling the tool about that joint's axis then changes only that angle, so a pose is
  reached exactly when the joint's axis line (a point on it, its direction) is.

With both, a pose reduces to four numbers (RM4D's observation, Rudorfer, ICRA 2025): the
angle ``theta`` of the last joint's axis from the vertical and the point where that axis
starts (the last joint's origin), turned about z so that the axis leans towards +x:
``(x*, y*, z)``. The structure is a voxel grid over ``(x*, y*, z)`` with ``angles`` bins of
``theta``; each cell is decided at its centre by the IK: from every analytic branch where
the arm has a compiled structure (``method="auto"``), else by the numeric budget (a lower
bound). ``position_only=True`` needs the yaw alone: a position is reduced to its distance
from the vertical axis and its height (a 2-D grid). The grid runs as a map (chunks, a Zarr
store with digests, resume, a Dask client), so its store has a map's integrity guarantees.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._version import __version__
from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..ik import IKOptions
from ..robot import Robot, as_robot
from .compute import InverseSettings, compiled_branches
from .grid import Grid, axis_frames, first_joint_origin
from .run import MapRun, run_chunks
from .store import robot_digest

__all__ = ["InverseReach", "Symmetry", "axis_frames", "inverse_reachability", "symmetries"]

FULL_TURN = 2 * math.pi - 1e-9
AXIS_TOL = 1e-9  # how far from vertical [rad] and from the base origin [m] an axis may be
MAX_CELLS = 50_000_000
"""The most cells (voxels x angle bins, each decided by IK) an inverse-reachability structure
may have, like a map's :data:`~toolkit.maps.grid.MAX_VOXELS`: voxel=0.04 m and 24 angles
give ~3 M for a 1 m arm; beyond the cap the call is refused before anything is allocated."""
INVERSE_OPTIONS = IKOptions(tol=1e-6, max_iter=80, restarts=8, seed=0)


@dataclass(frozen=True)
class Symmetry:
    """Which placement symmetries a robot's chain to a frame has (see the module doc).

    Attributes:
        yaw, roll: whether turning the base about z / rolling the tool about the last joint's
            axis changes nothing but one joint angle.
        yaw_reason, roll_reason: why (or why not), in one line each.
        roll_axis: the last joint's axis in that joint's frame.
        tool_in_joint: the tool frame's pose (4, 4) in the last joint's frame.
    """

    yaw: bool
    roll: bool
    yaw_reason: str
    roll_reason: str
    roll_axis: tuple[float, float, float]
    tool_in_joint: tuple[float, ...]

    def describe(self) -> str:
        return f"yaw: {self.yaw_reason}; roll: {self.roll_reason}"


def _revolute_axis(model: pin.Model, data: pin.Data, j: int) -> np.ndarray | None:
    """The joint's axis in its own frame, or None for a joint that is not 1-DoF revolute."""
    joint = model.joints[j]
    S = np.asarray(data.joints[j].S, dtype=float).reshape(6, -1)
    if joint.nv != 1 or joint.shortname() == "JointModelMimic" or np.linalg.norm(S[:3, 0]) > 1e-12:
        return None
    return S[3:, 0] / np.linalg.norm(S[3:, 0])


def _turns_fully(model: pin.Model, j: int) -> bool:
    joint = model.joints[j]
    if joint.nq == 2:  # a continuous joint (cos, sin)
        return True
    i = joint.idx_q
    return float(model.upperPositionLimit[i] - model.lowerPositionLimit[i]) >= FULL_TURN


def symmetries(robot: Robot, frame: str | None = None) -> Symmetry:
    """The yaw and roll symmetries of the chain from the base to ``frame`` (default: the
    tip), checked on the model at its neutral configuration."""
    robot = as_robot(robot)
    model = robot.model
    fid = robot.frames.id(frame)
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    path, j = [], int(model.frames[fid].parentJoint)
    while j > 0:
        if model.joints[j].nv > 0:
            path.append(j)
        j = int(model.parents[j])
    path.reverse()
    if len(path) < 2:
        reason = "fewer than two moving joints to the frame"
        return Symmetry(False, False, reason, reason, (0.0, 0.0, 1.0), tuple(np.eye(4).ravel()))
    first, last = path[0], path[-1]
    name1, name_n = model.names[first], model.names[last]
    yaw, yaw_reason = True, f"{name1} turns fully about the base's vertical axis"
    axis = _revolute_axis(model, data, first)
    if axis is None:
        yaw, yaw_reason = False, f"the first joint {name1} is not revolute"
    else:
        world = data.oMi[first].rotation @ axis
        origin = np.asarray(data.oMi[first].translation)
        if np.linalg.norm(np.cross(world, [0.0, 0.0, 1.0])) > AXIS_TOL:
            yaw, yaw_reason = False, f"the first joint {name1}'s axis is not vertical"
        elif np.linalg.norm(origin[:2]) > AXIS_TOL:
            yaw, yaw_reason = False, f"{name1}'s axis does not pass through the base origin"
        elif not _turns_fully(model, first):
            yaw, yaw_reason = False, f"the first joint {name1} does not turn fully"
    roll, roll_reason = True, f"{name_n} turns fully and carries the tool"
    u = _revolute_axis(model, data, last)
    if u is None:
        roll, roll_reason = False, f"the last joint {name_n} is not revolute"
        u = np.array([0.0, 0.0, 1.0])
    elif not _turns_fully(model, last):
        roll, roll_reason = False, f"the last joint {name_n} does not turn fully"
    tool = np.asarray(model.frames[fid].placement.homogeneous)
    return Symmetry(
        yaw, roll, yaw_reason, roll_reason, (float(u[0]), float(u[1]), float(u[2])),
        tuple(float(v) for v in tool.ravel()),
    )  # fmt: skip


@dataclass(frozen=True)
class InverseReach:
    """An inverse-reachability structure (:func:`inverse_reachability`).

    Attributes:
        reach: cells reached (nx, ny, nz, angles): over ``(x*, y*, z)`` (position-only:
            distance from the vertical axis, one cell, height) and the axis angle bins.
        grid: the voxel grid of ``(x*, y*, z)`` [m].
        angles: bins of the last joint axis's angle from the vertical over [0, pi].
        position_only: a structure of positions (yaw symmetry alone).
        symmetry: the symmetries it rests on.
        method: ``"analytic"`` (every branch, exact at the cell centres) or ``"numeric"``
            (the IK budget: a lower bound).
        frame: the tool frame.
        figures: chunks, IK solves and seconds of the build.
    """

    reach: np.ndarray
    grid: Grid
    angles: int
    position_only: bool
    symmetry: Symmetry
    method: str
    frame: str
    robot_name: str = ""
    figures: dict[str, float] = field(default_factory=dict)

    @property
    def cells(self) -> int:
        return int(self.reach.size)

    def keys(self, tasks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(points (N, 3), heading (N,) [rad], angle bins (N,)) of world task poses (N, 4, 4)
        (or positions (N, 3) for a position-only structure): the point the structure
        indexes, the azimuth that is turned away and the axis-angle bin."""
        if self.position_only:
            points = tasks if tasks.ndim == 2 else tasks[:, :3, 3]
            return points, np.zeros(len(points)), np.zeros(len(points), dtype=np.int64)
        tool = np.array(self.symmetry.tool_in_joint).reshape(4, 4)
        joint = tasks @ np.linalg.inv(tool)
        a = joint[:, :3, :3] @ np.array(self.symmetry.roll_axis)
        theta = np.arccos(np.clip(a[:, 2], -1.0, 1.0))
        bins = np.minimum((theta / (math.pi / self.angles)).astype(np.int64), self.angles - 1)
        return joint[:, :3, 3], np.arctan2(a[:, 1], a[:, 0]), bins

    def reaches(self, bases: ArrayLike, tasks: ArrayLike) -> np.ndarray:
        """(B, N) whether a base upright at each of ``bases`` (B, 3) [m] (any yaw: the
        structure is yaw-free) reaches each world task: poses (N, 4, 4), or positions
        (N, 3) for a position-only structure."""
        b = _validate.array(bases, "bases", shape=(-1, 3))
        t = _validate.array(tasks, "tasks")
        poses = t.ndim == 3 and t.shape[1:] == (4, 4)
        if not (poses or (self.position_only and t.ndim == 2 and t.shape[1] == 3)):
            want = "positions (N, 3) or poses (N, 4, 4)" if self.position_only else "(N, 4, 4)"
            raise InvalidParameterError(f"tasks must be {want}, got shape {t.shape}")
        points, heading, bins = self.keys(t)
        c, s = np.cos(heading), np.sin(heading)
        out = np.zeros((len(b), len(points)), dtype=bool)
        g = self.grid
        lower, shape = np.array(g.lower), np.array(g.shape)
        flat = self.reach.reshape(-1)
        for start in range(0, len(b), 1024):  # bounded memory: 1024 bases at a time
            d = points[None] - b[start : start + 1024, None]
            if self.position_only:
                u, v = np.hypot(d[..., 0], d[..., 1]), np.zeros(d.shape[:2])
            else:
                u, v = c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]
            idx = [np.floor((w - lower[k]) / g.voxel).astype(np.int64)
                   for k, w in enumerate((u, v, d[..., 2]))]  # fmt: skip
            inside = np.all([(i >= 0) & (i < shape[k]) for k, i in enumerate(idx)], axis=0)
            cell = ((idx[0] * shape[1] + idx[1]) * shape[2] + idx[2]) * self.angles + bins
            hit = np.zeros(inside.shape, dtype=bool)
            hit[inside] = flat[cell[inside]]
            out[start : start + 1024] = hit
        return out


def _structure_grid(robot: Robot, sym: Symmetry, voxel: float, position_only: bool,
                    frame: str | None, chunk: int, seed: int) -> Grid:  # fmt: skip
    """The (x*, y*, z) grid: around the first joint's origin, out to the farthest of 20,000
    sampled points (the last joint's origin; position-only: the tool point) plus 2 %."""
    q = robot.random_q(20_000, seed=np.random.default_rng(seed))
    tips = robot.fk(q, frame)
    if not position_only:
        tips = tips @ np.linalg.inv(np.array(sym.tool_in_joint).reshape(4, 4))
    points = tips[:, :3, 3]
    cz = float(first_joint_origin(robot)[2])
    radius = float(np.linalg.norm(points - [0.0, 0.0, cz], axis=1).max()) * 1.02 + voxel
    n = max(math.ceil(2 * radius / voxel), 1)
    if position_only:
        lower, shape = (0.0, -voxel / 2, cz - radius), (max(n // 2, 1), 1, n)
    else:
        lower, shape = (-radius, -radius, cz - radius), (n, n, n)
    return Grid(lower, voxel, shape, (chunk, chunk, chunk), (0.0, 0.0, cz), radius)


@renames.renamed(ik_method="method")
def inverse_reachability(
    robot: Robot,
    *,
    voxel: float = 0.04,
    angles: int = 24,
    position_only: bool = False,
    frame: str | None = None,
    collision_free: bool = True,
    method: str = "auto",
    options: IKOptions | None = None,
    seed: int = 0,
    run: MapRun | None = None,
    **run_settings: object,
) -> InverseReach:
    """The inverse-reachability structure of ``robot`` (module doc): ``voxel`` [m] the cell
    edge of ``(x*, y*, z)``, ``angles`` the bins of the last joint axis's angle from the
    vertical; ``collision_free`` (default True): a cell counts only with a solution free of
    self-collision. ``method`` (the IK method) as for :func:`toolkit.maps.reachability`.
    Runs as a map (``run=`` or the fields of :class:`MapRun` as keywords). Raises
    :class:`~toolkit.errors.InvalidParameterError` naming the reason when the arm lacks
    the symmetry the structure needs (:func:`toolkit.maps.placement` then solves the IK
    at every candidate instead)."""
    robot = as_robot(robot)
    how = MapRun.build(run, run_settings, "inverse_reachability")
    voxel = _validate.number(voxel, "voxel [m]", lower=1e-3, strict=True)
    angles = _validate.count(angles, "angles", minimum=1, maximum=720)
    position_only = _validate.flag(position_only, "position_only")
    collision_free = _validate.flag(collision_free, "collision_free")
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    method = _validate.one_of(method, "method", ("auto", "analytic", "numeric"))
    opts = INVERSE_OPTIONS if options is None else IKOptions.build(options)
    sym = _symmetry_needed(robot, frame, position_only)
    analytic = _analytic(robot, frame, method, position_only)
    if position_only:
        angles = 1
    robot.collision_checker(None, collision_free)  # builds (and checks) the checker once, here
    grid = _structure_grid(robot, sym, voxel, position_only, frame, how.chunk, seed)
    cells = math.prod(grid.shape) * angles
    if cells > MAX_CELLS:
        raise InvalidParameterError(
            f"inverse_reachability of {robot.name}: {grid.shape[0]} x {grid.shape[1]} x "
            f"{grid.shape[2]} voxels x {angles} angles = {cells:,} cells (more than "
            f"{MAX_CELLS:,}, each an IK problem): choose a larger voxel or fewer angles"
        )
    s = InverseSettings(
        frame, position_only, angles, np.array(sym.tool_in_joint).reshape(4, 4),
        np.array(sym.roll_axis), opts, seed, collision_free, analytic,
    )  # fmt: skip
    nx, ny, nz = grid.shape
    spec = {"reach": ((nx, ny, nz, angles), (*grid.chunk, angles), "bool")}
    meta = _meta(robot, grid, s, sym)
    arrays, figures = run_chunks("inverse_reachability", robot, grid, s, spec, meta, how)
    return InverseReach(
        arrays["reach"].astype(bool), grid, angles, position_only, sym,
        "analytic" if analytic else "numeric", frame or robot.tip, robot.name, figures,
    )  # fmt: skip


def _symmetry_needed(robot: Robot, frame: str | None, position_only: bool) -> Symmetry:
    sym = symmetries(robot, frame)
    if not sym.yaw or (not position_only and not sym.roll):
        why = sym.yaw_reason if not sym.yaw else sym.roll_reason
        raise InvalidParameterError(
            f"{robot.name}: no inverse-reachability structure for "
            f"{'positions' if position_only else 'poses'}: {why} (the structure needs the "
            f"yaw{'' if position_only else ' and roll'} symmetry; maps.placement solves the "
            "IK at every candidate base instead)"
        )
    return sym


def _analytic(robot: Robot, frame: str | None, method: str, position_only: bool) -> bool:
    """Whether the cells are decided from every analytic branch."""
    fits = compiled_branches(robot, frame)
    if method == "analytic" and (position_only or not fits):
        raise InvalidParameterError(
            "method='analytic' needs pose targets and an arm with a compiled analytic "
            f"structure: {robot.name}'s is {robot.structure_of(frame).family or 'none'}"
        )
    return method != "numeric" and fits and not position_only


def _meta(robot: Robot, grid: Grid, s: InverseSettings, sym: Symmetry) -> dict[str, Any]:
    """The structure's identity in its store."""
    return {
        "kind": "inverse_reachability",
        "robot": robot.name,
        "robot_digest": robot_digest(robot),
        "frame": s.frame or robot.tip,
        "grid": grid.as_dict(),
        "angles": s.angles,
        "position_only": s.position_only,
        "collision_free": s.collision_free,
        "symmetry": hashlib.sha256(repr(sym).encode()).hexdigest()[:16],
        "ik": {
            "tol": s.options.tol,
            "max_iter": s.options.max_iter,
            "restarts": s.options.restarts,
            "method": "analytic" if s.analytic else "numeric",
        },
        "seed": s.seed,
        "toolkit_version": __version__,
    }


def settings_of(structure: Any) -> InverseReach:
    """``structure`` checked to be an :class:`InverseReach`."""
    if not isinstance(structure, InverseReach):
        raise InvalidParameterError(
            f"structure must be a toolkit.maps.InverseReach, got {structure!r:.80}"
        )
    return structure
