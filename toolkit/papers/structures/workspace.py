"""The reach space of point M: sampled clouds, volumes (Monte Carlo with exact membership
for [P3]'s structures) and the analytic volumes of three of them."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from ...common import validate as _validate
from ...errors import InvalidParameterError, UnsupportedModelError
from ...robot import Robot, as_robot
from .inverse import closed_form_ik
from .models import STRUCTURES, default_rho, point_m

__all__ = [
    "ReachSection",
    "Workspace",
    "analytic_volume",
    "draw_sections",
    "draw_workspace",
    "reach_section",
    "workspace",
    "workspace_volume",
]


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
    lo, hi = robot.joints.lower, robot.joints.upper
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
    ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], s=6, alpha=0.85, c=pts[:, 2], cmap="viridis")
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
    half = max(np.ptp(pts, axis=0).max() / 2, 1e-3)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))  # equal scales
    ax.locator_params(nbins=4)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{robot.name}: sampled reach space of M", fontsize=10)
    return ax


class ReachSection(NamedTuple):
    """Reach space of M on a plane of the base frame: a grid and its membership."""

    plane: str  # "xz" (at y = level) or "xy" (at z = level)
    level: float  # [m]
    u: np.ndarray  # (nu,) first in-plane coordinate [m] (x)
    v: np.ndarray  # (nv,) second in-plane coordinate [m] (z for "xz", y for "xy")
    inside: np.ndarray  # (nv, nu) bool: a solution within the joint limits exists


def reach_section(
    robot: Robot, plane: str, level: float | None = None, n: int = 80, rho: object | None = None
) -> ReachSection:
    """Exact cross-section of M's reach space ([P3] structures): every grid point of the
    plane is tested with :func:`closed_form_ik`. ``plane`` is ``"xz"`` (through the base
    axis, y = 0, unless the reach space lies off it: then through its middle) or ``"xy"``
    (at the middle height unless ``level`` [m] is given)."""
    robot = as_robot(robot)
    if robot.facts.get("structure") not in STRUCTURES:
        raise UnsupportedModelError(f"{robot.name}: sections need one of [P3]'s structures")
    if not isinstance(plane, str) or plane not in ("xz", "xy"):
        raise InvalidParameterError(f"plane must be 'xz' or 'xy', got {plane!r}")
    n = _validate.count(n, "n", minimum=4, maximum=400)
    cloud = workspace(robot, 20_000, rho)
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    pad = 0.08 * (hi - lo).max()
    lo, hi = lo - pad, hi + pad
    axis = 1 if plane == "xz" else 2
    if level is None:
        middle = (lo[axis] + hi[axis]) / 2
        level = 0.0 if plane == "xz" and lo[axis] < 0 < hi[axis] else float(middle)
    level = _validate.number(level, "level")
    second = 2 if plane == "xz" else 1
    u = np.linspace(lo[0], hi[0], n)
    v = np.linspace(lo[second], hi[second], n)
    inside = np.zeros((n, n), dtype=bool)
    for i, b in enumerate(v):
        for j, a in enumerate(u):
            point = np.array([a, level, b] if plane == "xz" else [a, b, level])
            inside[i, j] = bool(closed_form_ik(robot, point, rho))
    return ReachSection(plane, float(level), u, v, inside)


def draw_sections(
    robot: Robot, axes: Sequence[Any] | None = None, n: int = 80, rho: object | None = None
) -> Sequence[Any]:
    """The XZ (through the base axis) and XY (at mid height) sections of M's reach space,
    filled, with equal axis scales, into two 2-D ``axes`` (default: a new figure)."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    _validate.axes(axes, "axes", count=2)
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(8, 4))
    for ax, plane in zip(axes, ("xz", "xy"), strict=True):
        cut = reach_section(robot, plane, n=n, rho=rho)
        ax.pcolormesh(
            cut.u, cut.v, cut.inside, cmap=ListedColormap(["white", "tab:blue"]),
            shading="nearest", vmin=0, vmax=1,
        )  # fmt: skip
        ax.contour(cut.u, cut.v, cut.inside.astype(float), levels=[0.5], colors="k", linewidths=0.8)
        ax.plot([0], [0], "k+", ms=10)  # the base axis (xz) or the base origin's projection
        other = "y" if plane == "xz" else "z"
        ax.set_xlabel("x [m]")
        ax.set_ylabel(("z" if plane == "xz" else "y") + " [m]")
        ax.set_aspect("equal")
        ax.set_title(
            f"{robot.name}: {plane.upper()} section at {other} = {cut.level:.2f} m", fontsize=10
        )
    return axes
