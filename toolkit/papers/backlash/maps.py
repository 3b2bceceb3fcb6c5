"""Backlash error maps and [P1]'s Fig. 6: how far the backlash-affected tool lands from
where it was commanded."""

from __future__ import annotations

import operator
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import InvalidParameterError
from ...robot import load
from .law import DEFAULT_DELTA, DEFAULT_K_H
from .layer import Backlash

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ErrorMap", "Figure6", "draw_figure6", "error_grid", "error_map", "figure6"]


# ---------------------------------------------------------------------- error maps
class ErrorMap(NamedTuple):
    """Tip-position error caused by backlash over a set of commanded configurations."""

    q: np.ndarray  # (N, n) commands
    error: np.ndarray  # (N,) |p_actual - p_ideal| [m]
    mean: float
    median: float
    p95: float
    max: float


def _layer(value: object) -> Backlash:
    if not isinstance(value, Backlash):
        raise InvalidParameterError(f"layer must be a Backlash, got {value!r:.100}")
    return value


def _progress(total: int, enabled: bool) -> Callable[[int], None]:
    """A minimal progress bar on stderr (no dependency)."""

    def show(done: int) -> None:
        if enabled:
            width = 30
            filled = int(width * done / max(total, 1))
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
            if done >= total:
                sys.stderr.write("\n")
            sys.stderr.flush()

    return show


def _errors(layer: Backlash, q: np.ndarray, chunk: int, progress: bool) -> np.ndarray:
    show = _progress(len(q), progress)
    out = np.empty(len(q))
    for start in range(0, len(q), chunk):
        part = q[start : start + chunk]
        actual = layer.tip_positions(part)
        ideal = layer.tips(part)
        out[start : start + chunk] = np.linalg.norm(actual - ideal, axis=1)
        show(min(start + chunk, len(q)))
    return out


def _summary(q: np.ndarray, err: np.ndarray) -> ErrorMap:
    return ErrorMap(
        q,
        err,
        float(err.mean()),
        float(np.median(err)),
        float(np.percentile(err, 95)),
        float(err.max()),
    )


def error_map(
    layer: Backlash,
    n: int = 10_000,
    *,
    seed: int | None = 0,
    chunk: int = 20_000,
    progress: bool = False,
) -> ErrorMap:
    """Tip-position error from backlash at ``n`` random commands within the limits.

    ``chunk``: commands evaluated per batch (>= 1); ``progress``: a bar on stderr.
    """
    layer = _layer(layer)
    progress = _validate.flag(progress, "progress")
    n = _validate.count(n, "n")
    chunk = _validate.count(chunk, "chunk")
    q = layer.robot.random_q(n, seed=seed)
    return _summary(q, _errors(layer, q, chunk, progress))


def error_grid(
    layer: Backlash,
    joints: tuple[int, int] = (1, 2),
    steps: int = 41,
    base: ArrayLike | None = None,
    *,
    progress: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Error over a grid of two joints (0-based indices) across their ranges.

    Returns (values of joint a (steps,), values of joint b (steps,), error (steps, steps)
    [m]) with the other joints at ``base`` (default: zero, clipped to the limits).
    """
    robot = _layer(layer).robot
    progress = _validate.flag(progress, "progress")
    steps = _validate.count(steps, "steps", minimum=2, maximum=10_000)
    try:
        i, j = (operator.index(k) for k in joints)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"joints must be two joint indices, got {joints!r:.100}"
        ) from None
    if not (0 <= i < robot.nq and 0 <= j < robot.nq and i != j):
        raise InvalidParameterError(f"joints must be two different indices in 0..{robot.nq - 1}")
    q0 = (
        np.clip(np.zeros(robot.nq), robot.joints.lower, robot.joints.upper)
        if base is None
        else base
    )
    q0 = robot.joints.check(q0)
    a = np.linspace(robot.joints.lower[i], robot.joints.upper[i], steps)
    b = np.linspace(robot.joints.lower[j], robot.joints.upper[j], steps)
    A, B = np.meshgrid(a, b, indexing="ij")
    q = np.repeat(q0[None, :], steps * steps, axis=0)
    q[:, i], q[:, j] = A.ravel(), B.ravel()
    err = _errors(layer, q, 20_000, progress)
    return a, b, err.reshape(steps, steps)


# ---------------------------------------------------------------------- [P1], Fig. 6
class Figure6(NamedTuple):
    """Tool paths of Fig. 6: A -> B (horizontal, case 19) and A -> B' (vertical, case 20)."""

    ideal_b: np.ndarray  # (S, 3) tool positions without backlash [m]
    actual_b: np.ndarray  # (S, 3) with backlash
    ideal_b2: np.ndarray
    actual_b2: np.ndarray
    max_deviation_b: float  # [m]
    max_deviation_b2: float


def figure6(
    delta: float = DEFAULT_DELTA,
    k_h: float = DEFAULT_K_H,
    payload: float = 0.5,
    steps: int = 101,
) -> Figure6:
    """Data of [P1]'s Fig. 6 for the Katana 6M180 (joint-space straight-line moves)."""
    robot = load("katana_6m180")
    layer = Backlash(robot, delta=delta, k_h=k_h, payload=payload)
    s = np.linspace(0.0, 1.0, _validate.count(steps, "steps", minimum=2, maximum=100_000))[:, None]
    q_b = np.array([0.0, 0.0, 0.0, -np.pi / 2, 0.0])
    q_b2 = np.array([0.0, np.pi / 2, 0.0, -np.pi / 2, 0.0])
    out = []
    for goal in (q_b, q_b2):
        path = s * goal
        out.append(robot.fk(path)[:, :3, 3])
        out.append(layer.fk(path)[:, :3, 3])
    dev_b = float(np.max(np.linalg.norm(out[0] - out[1], axis=1)))
    dev_b2 = float(np.max(np.linalg.norm(out[2] - out[3], axis=1)))
    return Figure6(out[0], out[1], out[2], out[3], dev_b, dev_b2)


def draw_figure6(data: Figure6 | None = None, ax: Axes | None = None) -> Axes:
    """Draw Fig. 6 (x-z plane of the base, mm) with matplotlib; returns the axes."""
    import matplotlib.pyplot as plt

    data = figure6() if data is None else data
    if not isinstance(data, Figure6):
        raise InvalidParameterError(f"data must be what figure6() returns, got {data!r:.100}")
    _validate.axes(ax)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    mm = 1000.0
    for ideal, actual, label in (
        (data.ideal_b, data.actual_b, "A -> B (horizontal)"),
        (data.ideal_b2, data.actual_b2, "A -> B' (vertical)"),
    ):
        (line,) = ax.plot(ideal[:, 0] * mm, ideal[:, 2] * mm, "--", label=f"{label}, no backlash")
        ax.plot(
            actual[:, 0] * mm,
            actual[:, 2] * mm,
            "-",
            color=line.get_color(),
            label=f"{label}, backlash",
        )
    ax.plot([data.ideal_b[0, 0] * mm], [data.ideal_b[0, 2] * mm], "ko")
    ax.annotate(
        "A",
        (data.ideal_b[0, 0] * mm, data.ideal_b[0, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.annotate(
        "B",
        (data.ideal_b[-1, 0] * mm, data.ideal_b[-1, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.annotate(
        "B'",
        (data.ideal_b2[-1, 0] * mm, data.ideal_b2[-1, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.set_xlabel("x, base frame [mm]")
    ax.set_ylabel("z, base frame [mm]")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        "Katana 6M180 tool path ([P1], Fig. 6): max deviation "
        f"{data.max_deviation_b * mm:.1f} mm (B), {data.max_deviation_b2 * mm:.1f} mm (B')",
        fontsize=9,
    )
    return ax
