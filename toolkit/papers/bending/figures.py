"""[P4]'s figures 4 and 5: shapes of a curling link and of multi-link manipulators."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ...common import validate as _validate
from ...errors import InvalidParameterError
from .geometry import Geometry, shape

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from mpl_toolkits.mplot3d import Axes3D

__all__ = ["draw_figure4", "draw_figure5", "figure4", "figure5"]

Shapes5 = list[tuple[str, list[float], list[float], np.ndarray]]
Shapes4 = list[tuple[float, np.ndarray]]


def figure5(R: float = 0.02, d: float = 0.016, h0: float = 0.008, n: int = 5) -> Shapes5:
    """Shapes of 2-, 3- and 4-link manipulators ([P4], Fig. 5) for sample angles.

    Returns a list of (title, alphas, psis, centres (links n + 1, 3)).
    """
    a_m = Geometry(R, d, h0).alpha_m
    cases = [
        ("2 links", [0.8 * a_m, 0.8 * a_m], [0.0, np.pi]),
        ("3 links", [0.6 * a_m, 0.9 * a_m, 0.5 * a_m], [0.0, np.pi / 2, np.pi]),
        ("4 links", [0.5 * a_m, 0.7 * a_m, 0.9 * a_m, 0.6 * a_m], [0.0, 0.0, np.pi / 2, np.pi]),
    ]
    return [(t, a, p, shape(a, p, n, R, h0)) for t, a, p in cases]


def figure4(R: float = 0.02, d: float = 0.016, h0: float = 0.008, n: int = 10) -> Shapes4:
    """A 10-element link curling above its base plane ([P4], Fig. 4): shapes for
    alpha = 3, 6, 9, 12 and 16 deg (those within alpha_m), in the X-Z plane.
    Returns [(alpha, centres)]."""
    a_m = Geometry(R, d, h0).alpha_m
    alphas = [a for a in np.radians([3.0, 6.0, 9.0, 12.0, 16.0]) if a <= a_m]
    return [(float(a), shape([a], [0.0], n, R, h0)) for a in alphas]


def _shapes(data: object, width: int, made_by: str) -> Any:
    """``data`` as made by ``made_by``: items of ``width`` fields ending in centres (M, 3)."""
    try:
        items = [tuple(item) for item in data]  # type: ignore[attr-defined]
    except TypeError:
        items = []
    if not items or any(len(item) != width for item in items):
        raise InvalidParameterError(f"data must be what {made_by} returns, got {data!r:.100}")
    checked = []
    for item in items:
        *head, pts = item
        head = [h if isinstance(h, str) else _validate.array(h, "data") for h in head]
        checked.append((*head, _validate.array(pts, "data centres", shape=(-1, 3))))
    return checked


def draw_figure5(
    data: Shapes5 | None = None, axes: Sequence[Axes3D] | None = None
) -> Sequence[Axes3D]:
    """Draw Fig. 5 (3-D shapes, equal axis scales, mm) into ``axes`` (one 3-D axes per
    manipulator; default: a new figure); returns the axes."""
    import matplotlib.pyplot as plt

    data = figure5() if data is None else _shapes(data, 4, "figure5()")
    _validate.axes(axes, "axes", count=len(data))
    if axes is None:
        new = plt.figure(figsize=(12, 4.2))
        axes = [new.add_subplot(1, len(data), i + 1, projection="3d") for i in range(len(data))]
    for ax, (title, alphas, psis, pts) in zip(axes, data, strict=True):
        mm = pts * 1e3
        ax.plot(mm[:, 0], mm[:, 1], mm[:, 2], "o-", ms=3)
        ax.set_title(
            f"{title}: alpha = {', '.join(f'{np.degrees(a):.0f}' for a in alphas)} deg;\n"
            f"psi = {', '.join(f'{np.degrees(p):.0f}' for p in psis)} deg",
            fontsize=8,
        )
        centre, half = mm.mean(axis=0), max(np.ptp(mm, axis=0).max() / 2, 1.0)
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.set_xlabel("X [mm]")
        ax.set_ylabel("Y [mm]")
        ax.set_zlabel("Z [mm]")
    fig: Any = axes[0].figure
    fig.tight_layout()
    return axes


def draw_figure4(data: Shapes4 | None = None, ax: Axes | None = None) -> Axes:
    """Draw Fig. 4 (X-Z plane, mm) into ``ax`` (default: a new figure); returns the axes."""
    import matplotlib.pyplot as plt

    data = figure4() if data is None else _shapes(data, 2, "figure4()")
    _validate.axes(ax)
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    for alpha, pts in data:
        ax.plot(
            pts[:, 0] * 1e3,
            pts[:, 2] * 1e3,
            "o-",
            ms=3,
            label=f"alpha = {np.degrees(alpha):.1f} deg",
        )
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("X0 [mm]")
    ax.set_ylabel("Z0 [mm]")
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    ax.set_title("10-element link curling above its base plane ([P4], Fig. 4)", fontsize=9)
    return ax
