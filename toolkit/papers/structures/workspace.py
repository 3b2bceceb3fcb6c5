"""The reach space of point M: sampled clouds, volumes (Monte Carlo with exact membership
for [P3]'s structures) and the analytic volumes of three of them."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ... import _validate
from ...robot import Robot, as_robot
from .inverse import closed_form_ik
from .models import STRUCTURES, default_rho, point_m

__all__ = ["Workspace", "analytic_volume", "draw_workspace", "workspace", "workspace_volume"]


class Workspace(NamedTuple):
    """Sampled reach space of a point."""

    points: np.ndarray  # (N, 3)
    volume: float  # [m^3]
    method: str


def workspace(
    robot: Robot, n: int = 20_000, rho: object | None = None, seed: int | None = 0
) -> np.ndarray:
    """Point cloud (n, 3) of M (or the tip origin) over uniform random joint values."""
    rho_ = point_m(robot, rho)
    q = robot.random_q(_validate.count(n, "n"), seed=seed)
    T = robot.fk(q)
    return T[:, :3, 3] + T[:, :3, :3] @ rho_


def workspace_volume(
    robot: Robot, n: int = 200_000, rho: object | None = None, seed: int | None = 0
) -> Workspace:
    """Volume of the reach space [m^3].

    [P3] structures: Monte Carlo over the cloud's bounding box with exact membership
    by :func:`closed_form_ik` (a point belongs when a solution within the limits exists);
    relative standard error about sqrt((1 - p) / (p n)). Other robots: occupied voxels
    of a sampled cloud (edge = extent / 40), a coarse estimate.
    """
    n = _validate.count(n, "n")
    cloud = workspace(robot, min(n, 50_000), rho, seed)
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    pad = 0.02 * (hi - lo).max()
    lo, hi = lo - pad, hi + pad
    if robot.facts.get("structure") in STRUCTURES and robot.params:
        rng = np.random.default_rng(None if seed is None else seed + 1)
        m = max(int(n) // 10, 1000)
        pts = rng.uniform(lo, hi, size=(m, 3))
        inside = sum(bool(closed_form_ik(robot, p, rho)) for p in pts)
        return Workspace(
            cloud, float(np.prod(hi - lo) * inside / m), "monte-carlo + closed-form IK"
        )
    edge = (hi - lo).max() / 40
    keys = np.unique(np.floor((cloud - lo) / edge).astype(np.int64), axis=0)
    return Workspace(cloud, float(len(keys) * edge**3), "voxels")


def analytic_volume(robot: Robot) -> float | None:
    """Exact reach-space volume of M for the Cartesian (box), cylindrical (hollow cylinder)
    and spherical (spherical shell) structures at their default point M; None otherwise."""
    name = as_robot(robot).facts.get("structure")
    lo, hi = robot.lower, robot.upper
    if name == "cartesian":
        return float(np.prod(hi - lo))
    if name == "cylindrical":
        # M = Rz(f1)(0, f3 + d, a + f2) with rho = (0, 0, -d): radius f3 + d, full turn
        d = -float(default_rho(robot)[2])
        turn = min(hi[0] - lo[0], 2 * np.pi) / (2 * np.pi)
        return float(turn * np.pi * ((hi[2] + d) ** 2 - (lo[2] + d) ** 2) * (hi[1] - lo[1]))
    if name == "spherical":
        d = float(default_rho(robot)[2])
        full = hi[0] - lo[0] >= 2 * np.pi - 1e-9 and hi[1] - lo[1] >= np.pi - 1e-9
        if not full:
            return None
        return float(4 / 3 * np.pi * ((hi[2] + d) ** 3 - (lo[2] + d) ** 3))
    return None


def draw_workspace(robot: Robot, n: int = 5000, ax: Any = None) -> Any:
    """Scatter plot of the reach space into 3-D axes ``ax`` (default: a new figure);
    returns the axes."""
    import matplotlib.pyplot as plt

    _validate.axes(ax)
    pts = workspace(robot, n)
    if ax is None:
        fig = plt.figure(figsize=(5, 5))
        ax = fig.add_subplot(projection="3d")
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], s=1, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{robot.name}: reach space of M", fontsize=9)
    return ax
