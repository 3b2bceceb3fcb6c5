"""Collision-free motion planning in joint space: bidirectional RRT-Connect from a start
to any of several goals (:mod:`~toolkit.planning.trees`), every edge checked at
configurations at most ``resolution`` apart (:mod:`~toolkit.planning.edges`), the path
shortened by straight cuts that pass the same check, then checked again whole.

The package plans on arrays and a collision test; :meth:`toolkit.Robot.plan` gives it a
robot's joint values, limits and exact collision checker (coal, on the description's
meshes), and goals as configurations or tool poses.

MoveIt's formats (:mod:`~toolkit.planning.moveit`, :mod:`~toolkit.planning.requests`):
:func:`read_scene` reads a planning scene's obstacles into a Scene, :func:`read_request` a
motion plan request into a :class:`MotionRequest` (its ``plan(robot, scene)`` plans it),
:func:`write_joint_trajectory` and :func:`read_joint_trajectory` a joint trajectory.
:func:`plan_many` plans a dataset of problems on a pool of threads.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable

import numpy as np

from .edges import RESOLUTION, EdgeChecker, shortcut
from .many import plan_many
from .moveit import fixed_frames, read_scene
from .requests import (
    JointTrajectory,
    MotionRequest,
    read_joint_trajectory,
    read_request,
    write_joint_trajectory,
)
from .results import PlanResult
from .trees import rrt_connect

__all__ = [
    "RESOLUTION",
    "STEP",
    "JointTrajectory",
    "MotionRequest",
    "PlanResult",
    "fixed_frames",
    "plan_many",
    "plan_values",
    "read_joint_trajectory",
    "read_request",
    "read_scene",
    "write_joint_trajectory",
]

STEP = 0.5
"""[rad] The longest edge a tree grows by (in the Euclidean norm of the joint values)."""


def plan_values(
    collides: Callable[[np.ndarray], np.ndarray], start: np.ndarray, goals: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray], *, time_limit: float, seed: int,
    resolution: float = RESOLUTION, step: float = STEP, simplify: bool = True,
) -> tuple[np.ndarray | None, int, dict[str, float]]:  # fmt: skip
    """(path (K, n) of joint values or None, the goal reached (-1), figures: seconds,
    checks, nodes, whether the final path was verified) from ``start`` (n,) to any of
    ``goals`` (G, n), free by ``collides`` ((N, n) -> (N,) flags); inputs checked."""
    begin = time.perf_counter()
    deadline = begin + time_limit
    rng = np.random.default_rng(seed)
    edges = EdgeChecker(collides, resolution)
    path, goal, nodes = rrt_connect(start, goals, bounds, edges, rng, deadline, step)
    verified = False
    if path is not None:
        if simplify:
            path = shortcut(path, edges, rng, deadline + 0.5 * time_limit)
        # the whole path again, every segment, by a fresh count
        again = EdgeChecker(collides, resolution)
        verified = all(again.free(a, b) for a, b in itertools.pairwise(path))
        verified = verified and not bool(collides(path[:1])[0])
        edges.checks += again.checks
    figures = {"time_s": time.perf_counter() - begin, "checks": float(edges.checks),
               "nodes": float(nodes), "verified": float(verified)}  # fmt: skip
    return path, goal, figures
