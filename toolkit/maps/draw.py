"""Pictures of maps: slices through the base axis (XZ) and at chosen heights (XY), coloured
by reachability index or error, with a colour bar and units; coloured voxels in the
meshcat viewer."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..common import validate as _validate
from ..errors import InvalidParameterError
from .results import AccuracyMap, ReachabilityMap

__all__ = ["draw_placement", "draw_slices", "map_values", "show_voxels"]


_STATISTICS = tuple(
    f"{kind}{name}" for kind in ("", "rotation_", "compensated_") for name in ("mean", "p95", "max")
)


def map_values(
    result: Any, statistic: str = "p95", payload: int = 0, k_h: int = 0
) -> tuple[np.ndarray, str, float]:
    """(values (nx, ny, nz), label with unit, scale to the unit) of a map: the
    reachability index, or an accuracy map's ``statistic`` (mean, p95, max,
    rotation_..., compensated_...) for one payload and k_H (indices)."""
    if not isinstance(statistic, str) or statistic not in _STATISTICS:
        raise InvalidParameterError(
            f"statistic must be one of {', '.join(_STATISTICS)}, got {statistic!r:.40}"
        )
    payload = _validate.count(payload, "payload index", minimum=0)
    k_h = _validate.count(k_h, "k_h index", minimum=0)
    if isinstance(result, ReachabilityMap):
        if payload or k_h:
            raise InvalidParameterError("a reachability map has no payload or k_h index")
        return result.index, "reachability index (fraction of orientations)", 1.0
    if not isinstance(result, AccuracyMap):
        raise InvalidParameterError(f"expected a map from toolkit.maps, got {result!r:.80}")
    values = getattr(result, statistic, None) if isinstance(statistic, str) else None
    if not isinstance(values, np.ndarray) or values.ndim != 5:
        raise InvalidParameterError(
            f"statistic {statistic!r} is not in this map; choose mean, p95, max, rotation_mean, "
            "rotation_p95, rotation_max (or compensated_... with compensate=True)"
        )
    if payload >= len(result.payloads) or k_h >= len(result.k_h):
        raise InvalidParameterError(
            f"indices: payload < {len(result.payloads)} and k_h < {len(result.k_h)}, "
            f"got {payload} and {k_h}"
        )
    angle = statistic.startswith("rotation")
    name = statistic.replace("_", " ")
    label = f"{name} tool {'orientation' if angle else 'position'} error\n"
    label += f"from backlash [{'deg' if angle else 'mm'}], payload {result.payloads[payload]:g} kg"
    return values[payload, k_h], label, (np.degrees(1.0) if angle else 1e3)


def _level(value: float) -> str:
    return f"{0.0 if abs(value) < 0.005 else value:.2f}"  # no "-0.00"


def _nearest(axis_values: np.ndarray, level: float) -> int:
    return int(np.argmin(np.abs(axis_values - level)))


def draw_slices(
    result: Any,
    *,
    heights: Sequence[float] | None = None,
    statistic: str = "p95",
    payload: int = 0,
    k_h: int = 0,
    axes: Sequence[Any] | None = None,
    title: str | None = None,
) -> Sequence[Any]:
    """An XZ slice through the base axis (y = 0) and XY slices at ``heights`` [m] (default:
    the height of the reach centre; ``[]``: the XZ slice alone), coloured by the map's
    values (:func:`map_values`), equal axis scales, one colour bar; into ``axes``
    (1 + len(heights)) or a new figure."""
    import matplotlib.pyplot as plt

    if title is not None and not isinstance(title, str):
        raise InvalidParameterError(f"title must be text or None, got {title!r:.80}")
    values, label, scale = map_values(result, statistic, payload, k_h)
    grid = result.grid
    centres = result.centers
    xs, ys, zs = centres[:, 0, 0, 0], centres[0, :, 0, 1], centres[0, 0, :, 2]
    heights = _heights(heights, grid.reach_centre[2])
    _validate.axes(axes, "axes", count=1 + len(heights))
    if axes is None:
        _, made = plt.subplots(
            1, 1 + len(heights), figsize=(4.6 * (1 + len(heights)) + 1.2, 4.6), layout="constrained"
        )
        axes = list(np.atleast_1d(made))
    shown = values * scale
    if scale == 1.0:  # a reachability map: unreached voxels are grey, like NaN errors
        shown = np.where(shown > 0, shown, np.nan)
    finite = shown[np.isfinite(shown)]
    top = 1.0 if scale == 1.0 else (float(finite.max()) if finite.size else 1.0)
    cmap = plt.get_cmap("viridis").with_extremes(bad="#eeeeee")
    j = _nearest(ys, 0.0)
    image = _panel(axes[0], shown[:, j, :], xs, zs, grid.voxel, cmap, top)
    axes[0].set_title(f"XZ slice at y = {_level(ys[j])} m (through the base axis)", fontsize=10)
    axes[0].set_ylabel("z [m]")
    for ax, h in zip(axes[1:], heights, strict=True):
        k = _nearest(zs, h)
        _panel(ax, shown[:, :, k], xs, ys, grid.voxel, cmap, top)
        ax.set_title(f"XY slice at z = {_level(zs[k])} m", fontsize=10)
        ax.set_ylabel("y [m]")
    for ax in axes:
        ax.set_aspect("equal")
        ax.plot([0], [0], "r+", ms=10, mew=2)  # the base axis
    fig = axes[0].figure
    bar = fig.colorbar(image, ax=list(axes))
    bar.set_label(label, fontsize=10)
    bar.ax.tick_params(labelsize=9)
    fig.suptitle(
        title or f"{_robot_name(result)}: voxel {grid.voxel:g} m (grey: not reached)", fontsize=10
    )
    return axes


def _heights(heights: Sequence[float] | None, default: float) -> list[float]:
    if heights is None:
        return [default]
    levels = _validate.array(heights, "heights [m]")
    if levels.ndim != 1:
        raise InvalidParameterError(f"heights must be a list of heights [m], got {heights!r:.80}")
    return [float(h) for h in levels]


def _panel(
    ax: Any, cut: np.ndarray, u: np.ndarray, v: np.ndarray, voxel: float, cmap: Any, top: float
) -> Any:
    """One slice (nu, nv) as an image with its voxel edges, x on the horizontal axis."""
    half = voxel / 2
    extent = (u[0] - half, u[-1] + half, v[0] - half, v[-1] + half)
    image = ax.imshow(
        np.ma.masked_invalid(cut.T), origin="lower", extent=extent, cmap=cmap, vmin=0, vmax=top
    )
    ax.set_xlabel("x [m]")
    return image


def _robot_name(result: Any) -> str:
    return str(result.robot_name or "map")


def show_voxels(
    result: Any,
    viewer: Any,
    *,
    statistic: str = "p95",
    payload: int = 0,
    k_h: int = 0,
    name: str = "map",
) -> int:
    """Coloured points at the voxel centres of a map in a :class:`toolkit.viz.Viewer`,
    beside the robot (viridis colours, as in :func:`draw_slices`; unreached voxels left
    out); returns the number of voxels drawn."""
    import matplotlib.pyplot as plt

    if not isinstance(name, str) or not name:
        raise InvalidParameterError(f"name must be a non-empty text, got {name!r:.80}")
    scene = getattr(viewer, "meshcat", None)
    if scene is None:
        raise InvalidParameterError(f"viewer must be a toolkit.viz.Viewer, got {viewer!r:.80}")
    import meshcat.geometry as g

    values, _, scale = map_values(result, statistic, payload, k_h)
    shown = values * scale
    keep = np.isfinite(shown) & (shown > 0)
    if not keep.any():
        return 0
    top = 1.0 if scale == 1.0 else float(shown[keep].max())
    colours = plt.get_cmap("viridis")(np.clip(shown[keep] / top, 0, 1))[:, :3]
    points = result.centers[keep]
    scene[name].set_object(g.PointCloud(points.T, colours.T, size=result.grid.voxel * 0.6))
    return int(keep.sum())


def draw_placement(result: Any, path: Any = None, ax: Any = None) -> Any:
    """A placement (:func:`toolkit.maps.placement`) as a heat map of the estimated fraction
    of tasks reached from each base position, the tasks' (x, y) as dots, the verified
    candidates as circles and the best as a star; equal axes in metres. Saved to ``path``
    when given; returns the axes."""
    import matplotlib.pyplot as plt

    fields = ("xs", "ys", "heat", "tasks", "bases", "reach")
    if type(result).__name__ != "Placement" or not all(hasattr(result, f) for f in fields):
        raise InvalidParameterError(
            f"expected a placement from toolkit.maps.placement, got {result!r:.80}"
        )
    _validate.axes(ax, "ax")
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 5.2), layout="constrained")
    xs, ys = result.xs, result.ys
    step = float(xs[1] - xs[0]) if len(xs) > 1 else float(ys[1] - ys[0]) if len(ys) > 1 else 0.1
    half = step / 2
    extent = (xs[0] - half, xs[-1] + half, ys[0] - half, ys[-1] + half)
    image = ax.imshow(result.heat.T * 100, origin="lower", extent=extent, cmap="viridis",
                      vmin=0, vmax=100)  # fmt: skip
    tasks = result.tasks[:, :3, 3]
    ax.plot(tasks[:, 0], tasks[:, 1], ".", color="#ff7f0e", ms=4, label="tasks (x, y)")
    ax.plot(result.bases[1:, 0], result.bases[1:, 1], "o", mfc="none", mec="white", ms=8,
            label="verified candidates")  # fmt: skip
    bx, by, _, yaw = result.bases[0]
    ax.plot([bx], [by], "*", color="red", ms=16, mec="white",
            label=f"best: {100 * result.reach[0]:.1f} % verified")  # fmt: skip
    ax.arrow(bx, by, 0.08 * np.cos(yaw), 0.08 * np.sin(yaw), color="red", width=0.004)
    ax.set_aspect("equal")
    ax.set_xlabel("base x [m]")
    ax.set_ylabel("base y [m]")
    ax.set_title(f"{_robot_name(result)}: where to put the base ({len(tasks)} tasks)",
                 fontsize=10)  # fmt: skip
    ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    bar = ax.figure.colorbar(image, ax=ax)
    bar.set_label("tasks reached from the base, estimated [%]", fontsize=10)
    if path is not None:
        ax.figure.savefig(path, dpi=110)
    return ax
