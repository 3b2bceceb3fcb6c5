"""Workspace maps: where an arm reaches a point in enough orientations, and how large the
backlash error is there; chunked, resumable, from one machine to a Dask cluster.

* :func:`reachability` puts a voxel grid around the base (bounds from the sampled reach,
  or given) and tries K tool orientations (:func:`spread_orientations`) at every voxel
  centre with the batch IK. Per voxel: the reachability index (fraction of orientations
  solved), and the solved q and target orientation of the best one (largest
  manipulability). ``position_only=True`` maps positions alone.
* :func:`inverse_reachability` and :func:`placement` answer the inverse question, where to
  put the base so that the tool reaches given poses (:mod:`toolkit.maps.placement`).
* :func:`backlash_accuracy` maps, for a :class:`~toolkit.papers.backlash.Backlash` layer,
  the tool position and orientation errors backlash causes over the solved orientations
  of each voxel (mean, 95th percentile, max), for several payloads and k_H values; with
  ``compensate=True`` also after compensation (``Backlash.command_for``).

The grid is cut into chunks of ``chunk``**3 voxels, one task each. Without ``client``,
the chunks run on this machine with no set-up and no Dask: in ``workers`` threads of
this process (default: one per core), each chunk's compiled kernels on one core without
the GIL, so a script without a main guard, stdin or a notebook works; or with
``workers=1`` in this thread, each chunk spread over every core by the compiled engine.
A damaged store (a chunk deleted, copied or corrupted) is never read as data: ``resume``
recomputes it, otherwise a ``MapStoreError`` names it. With ``client`` (a
``dask.distributed.Client``), each chunk is a task on the cluster; the robot (or layer)
goes to the workers by pickling, once each, never as a path on this machine. Every
finished chunk is written to the Zarr ``store`` at once; ``resume=True`` finishes a
killed run from it. Each chunk's IK seeds are fixed by (``seed``, chunk), so a map is
the same whether it ran here, on a cluster, or in pieces.

IK budget: a voxel is first solved position-only (at least 8 restarts); its orientations
start from that solution, with ``options`` (default: 3 restarts, 60 iterations). The
index is therefore what this budget finds: a lower bound of the true fraction.
"""

from __future__ import annotations

import hashlib
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._version import __version__
from ..common import caller_level, renames
from ..common import validate as _validate
from ..errors import InvalidParameterError, UnreachableTargetsWarning
from ..ik import IKOptions, parse_mask
from ..robot import Robot, as_robot
from .bases import base_pose, scene_from_base
from .compute import AccuracySettings, ReachSettings, compiled_branches
from .draw import draw_placement, draw_slices, map_values, show_voxels
from .grid import Grid, make_grid, spread_orientations
from .inverse import InverseReach, Symmetry, inverse_reachability, symmetries
from .layers import OffsetLayer
from .placement import Placement, placement
from .results import AccuracyMap, ReachabilityMap
from .run import MapRun, run_chunks
from .store import robot_digest, zarr_available

__all__ = [
    "AccuracyMap",
    "Grid",
    "InverseReach",
    "MapRun",
    "OffsetLayer",
    "Placement",
    "ReachabilityMap",
    "Symmetry",
    "backlash_accuracy",
    "base_pose",
    "draw_placement",
    "draw_slices",
    "inverse_reachability",
    "make_grid",
    "map_values",
    "placement",
    "reachability",
    "scene_from_base",
    "show_voxels",
    "spread_orientations",
    "symmetries",
    "zarr_available",
]

MAP_OPTIONS = IKOptions(tol=1e-6, max_iter=60, restarts=3, seed=0)


def _settings(
    robot: Robot,
    orientations: int,
    position_only: bool,
    mask: ArrayLike | None,
    frame: str | None,
    options: IKOptions | None,
    seed: int,
    spread_starts: bool = False,
    scene: Any = None,
    collision_free: bool = True,
    method: str = "auto",
) -> ReachSettings:
    """The checked inputs; with ``spread_starts``, a position-only map counts
    ``orientations`` IK solutions per voxel from random starts."""
    position_only = _validate.flag(position_only, "position_only")
    _validate.count(orientations, "orientations", minimum=1, maximum=10_000)
    starts = 1
    if position_only and spread_starts:
        starts = _validate.count(orientations, "orientations", maximum=10_000)
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    robot.frames.id(frame)  # validates
    opts = MAP_OPTIONS if options is None else IKOptions.build(options)
    if opts.time_limit is not None:
        raise InvalidParameterError("map IK options take no time_limit: restarts bound each solve")
    rotations = np.eye(3)[None] if position_only else spread_orientations(orientations)
    weights = None
    if mask is not None:
        weights = tuple(float(w) for w in parse_mask(mask, position_only))
    collision_free = _validate.flag(collision_free, "collision_free")
    free = robot.collision_checker(scene, collision_free) is not None  # checked (and built) here
    method = _validate.one_of(method, "method", ("auto", "analytic", "numeric"))
    fits = compiled_branches(robot, frame) and weights is None and not position_only
    if method == "analytic" and not fits:
        raise InvalidParameterError(
            f"method='analytic' needs full-pose targets (no mask, not position_only) and "
            f"an arm with a compiled analytic structure: {robot.name}'s is "
            f"{robot.structure_of(frame).family or robot.structure_of(frame).reason}"
        )
    analytic = method != "numeric" and fits
    return ReachSettings(
        rotations, position_only, weights, frame, opts, seed, starts, scene, free, analytic
    )


def _check_reach(robot: Robot, s: ReachSettings) -> None:
    """Refuse a map whose every voxel would be unreachable: targets constraining more
    directions than the joints move the frame in (a 5-joint arm asked for full poses)."""
    constrained = 3 if s.position_only else 6
    if s.mask is not None:
        constrained = sum(1 for w in s.mask if w > 0)
    rank = robot.frames.rank(s.frame)
    if rank < constrained:
        raise InvalidParameterError(
            f"{robot.name}'s joints move {s.frame or robot.tip} in {rank} independent "
            f"directions, fewer than the {constrained} the map's targets fix, so no voxel "
            "could be reached in the orientations tried: pass position_only=True (the arm's "
            f"reach), or a mask that frees {constrained - rank} direction(s) its joints "
            "do not control"
        )


def _warn_if_empty(robot: Robot, reached: np.ndarray, s: ReachSettings) -> None:
    """Warn when no voxel was reached: the user asked for something the arm cannot do."""
    if reached.size and not np.any(reached):
        what = "position" if s.position_only else f"{len(s.orientations)} orientations"
        warnings.warn(
            f"{robot.name}: no voxel of the map was reached ({reached.size} voxels, "
            f"{what} each); with fewer than six joints, or a mask that fixes directions the "
            "joints do not control, try position_only=True",
            UnreachableTargetsWarning,
            stacklevel=caller_level(),
        )


def _meta(kind: str, robot: Robot, grid: Grid, s: ReachSettings, **more: object) -> dict[str, Any]:
    return {
        "kind": kind,
        "robot": robot.name,
        "robot_digest": robot_digest(robot),
        "frame": s.frame or robot.tip,
        "grid": grid.as_dict(),
        "orientations_digest": hashlib.sha256(np.round(s.orientations, 12).tobytes()).hexdigest(),
        "orientations": len(s.orientations),
        "position_only": s.position_only,
        "mask": None if s.mask is None else list(s.mask),
        "starts": s.starts,
        "collision_free": s.collision_free,
        "scene": None if s.scene is None else s.scene.digest(),
        "ik": {
            "tol": s.options.tol,
            "max_iter": s.options.max_iter,
            "restarts": s.options.restarts,
            **({"method": "analytic"} if s.analytic else {}),  # numeric stores as before
        },
        "seed": s.seed,
        "toolkit_version": __version__,
        **more,
    }


@renames.renamed(ik_method="method")
def reachability(
    robot: Robot,
    *,
    voxel: float,
    orientations: int = 50,
    bounds: ArrayLike | None = None,
    position_only: bool = False,
    seed: int = 0,
    mask: ArrayLike | None = None,
    frame: str | None = None,
    options: IKOptions | None = None,
    scene: Any = None,
    collision_free: bool = True,
    method: str = "auto",
    run: MapRun | None = None,
    **run_settings: object,
) -> ReachabilityMap:
    """The reachability map of ``robot`` (module doc). ``voxel`` [m]; ``bounds`` (2, 3)
    [m]; ``mask`` as for :meth:`toolkit.Robot.ik` (e.g. free the roll of a 5-DOF arm);
    ``scene``: objects the solutions must not hit; ``collision_free`` (default True): a
    voxel orientation counts only with a solution free of self-collision (and of the
    scene); both are part of the store's identity. ``collision_free=False`` maps the arm
    alone in empty space. ``method`` (the IK method): ``"auto"`` (default) decides each
    orientation from every analytic branch where the arm has a compiled structure (exact; see
    :meth:`toolkit.Robot.ik_all_batch`) and by the numeric budget elsewhere (a lower
    bound); ``"analytic"`` insists on the former, ``"numeric"`` on the latter. The method
    used is part of the store's identity (``ik.method``, for analytic maps).

    How it runs is a :class:`MapRun` (``run=``) or its fields as keywords: ``store`` (a
    Zarr folder or store object), ``client`` (a ``dask.distributed.Client``), ``resume``,
    ``progress``, ``workers``, ``chunk``."""
    robot = as_robot(robot)
    how = MapRun.build(run, run_settings, "reachability")
    s = _settings(
        robot, orientations, position_only, mask, frame, options, seed, False, scene,
        collision_free, method,
    )  # fmt: skip
    _check_reach(robot, s)
    grid = make_grid(robot, voxel, bounds, frame=frame, chunk=how.chunk)  # not the IK seed
    nx, ny, nz = grid.shape
    c = grid.chunk
    spec = {
        "index": ((nx, ny, nz), c, "float64"),
        "best_q": ((nx, ny, nz, robot.nq), (*c, robot.nq), "float64"),
        "best_rotation": ((nx, ny, nz, 3, 3), (*c, 3, 3), "float64"),
    }
    meta = _meta("reachability", robot, grid, s)
    arrays, figures = run_chunks("reachability", robot, grid, s, spec, meta, how)
    _warn_if_empty(robot, np.nan_to_num(arrays["index"]) > 0, s)
    return ReachabilityMap(
        grid.centers(), arrays["index"], arrays["best_q"], arrays["best_rotation"],
        s.orientations, grid, s.position_only, figures, robot.name,
    )  # fmt: skip


def _k_h_list(layer: Any, k_h: object) -> tuple[tuple[float, ...], ...]:
    n = layer.robot.nq
    values = [layer.k_h] if k_h is None else list(k_h) if isinstance(k_h, list | tuple) else [k_h]
    if not values:
        raise InvalidParameterError("k_h must list at least one value")
    return tuple(
        tuple(float(v) for v in _validate.per_joint(k, "k_h", n, lower=0.0)) for k in values
    )


def _accuracy_spec(grid: Grid, s: AccuracySettings) -> dict[str, Any]:
    nx, ny, nz = grid.shape
    P, H = len(s.payloads), len(s.k_h)
    stats = ((P, H, 3, nx, ny, nz), (P, H, 3, *grid.chunk), "float64")
    spec = {"position": stats, "rotation": stats, "reachable": ((nx, ny, nz), grid.chunk, "bool")}
    if s.compensate:
        spec["compensated"] = stats
    return spec


def _layer_meta(layer: Any, s: AccuracySettings) -> dict[str, Any]:
    return {
        "delta": [float(v) for v in layer.delta],
        "nominal_torque": [float(v) for v in layer.nominal_torque],
        "payloads": list(s.payloads),
        "k_h": [list(k) for k in s.k_h],
        "compensate": s.compensate,
    }


@renames.renamed(ik_method="method")
def backlash_accuracy(
    layer: Any,
    *,
    voxel: float,
    orientations: int = 20,
    payloads: ArrayLike = (0.0, 0.5),
    k_h: object = None,
    compensate: bool = False,
    seed: int = 0,
    bounds: ArrayLike | None = None,
    position_only: bool = False,
    mask: ArrayLike | None = None,
    options: IKOptions | None = None,
    scene: Any = None,
    collision_free: bool = True,
    method: str = "auto",
    run: MapRun | None = None,
    **run_settings: object,
) -> AccuracyMap:
    """The backlash-accuracy map of ``layer`` (module doc): ``payloads`` [kg]; ``k_h``
    None (the layer's), one value (scalar or per joint) or a list of them. With
    ``position_only`` (arms with fewer than 6 joints), ``orientations`` counts the IK
    solutions per voxel, each from its own random start. How it runs: ``run=`` or the
    fields of :class:`MapRun` as keywords, as for :func:`reachability`."""
    if not isinstance(layer, OffsetLayer):
        raise InvalidParameterError(f"layer must be a toolkit Backlash layer, got {layer!r:.80}")
    robot = layer.robot
    how = MapRun.build(run, run_settings, "backlash_accuracy")
    masses = _validate.array(payloads, "payloads")
    loads = tuple(float(p) for p in masses.ravel())
    if masses.ndim > 1 or not loads or not all(0 <= p < 1e6 for p in loads):
        raise InvalidParameterError(
            f"payloads must be one or more masses >= 0 kg, got {payloads!r}"
        )
    compensate = _validate.flag(compensate, "compensate")
    reach = _settings(
        robot, orientations, position_only, mask, None, options, seed, True, scene,
        collision_free, method,
    )  # fmt: skip
    s = AccuracySettings(reach, loads, _k_h_list(layer, k_h), compensate)
    _check_reach(robot, reach)
    grid = make_grid(robot, voxel, bounds, chunk=how.chunk)
    spec = _accuracy_spec(grid, s)
    meta = _meta("backlash_accuracy", robot, grid, reach, layer=_layer_meta(layer, s))
    arrays, figures = run_chunks("backlash_accuracy", layer, grid, s, spec, meta, how)
    _warn_if_empty(robot, arrays["reachable"].astype(bool), reach)
    pos, rot = arrays["position"], arrays["rotation"]
    comp = arrays.get("compensated")
    return AccuracyMap(
        grid.centers(), loads, s.k_h, pos[:, :, 0], pos[:, :, 1], pos[:, :, 2],
        rot[:, :, 0], rot[:, :, 1], rot[:, :, 2], arrays["reachable"].astype(bool), grid,
        None if comp is None else comp[:, :, 0], None if comp is None else comp[:, :, 1],
        None if comp is None else comp[:, :, 2], figures, robot.name,
    )  # fmt: skip
