"""The xacro arguments of a calibrated catalogue model (see :mod:`toolkit.calibration`).

A catalogue model is rendered from named arguments (the Katana's ``a2``, ``base_height``,
...). The calibrated URDF holds every identified error; the arguments can hold only the
ones their template exposes. :func:`fit_arguments` finds the arguments that move the
tool (a render with each one nudged, no knowledge of the template), then fits them by
Gauss-Newton to the calibrated model's tool positions, and says how much is left over.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..descriptions import get_spec
from ..errors import UnsupportedModelError
from ..robot import load
from ._arm import ArmModel

__all__ = ["XacroFit", "fit_arguments"]

STEP = 1e-5  # [m or rad]: the nudge that finds and differentiates the arguments


@dataclass(frozen=True)
class XacroFit:
    """``arguments``: the fitted values of the arguments that move the tool (pass them to
    ``toolkit.load(name, **arguments)``); ``nominal``: their values before; ``rms``: the
    tool position error [m] left between that model and the calibrated one (what the
    template's arguments cannot express: joint zeros, twists, the base and tool frames)."""

    arguments: dict[str, float]
    nominal: dict[str, float]
    rms: float


def _positions(name: str, args: Mapping[str, float], Q: np.ndarray) -> np.ndarray:
    return np.asarray(load(name, **args).fk(Q)[:, :3, 3])


def fit_arguments(arm: ArmModel, Q: np.ndarray, iterations: int = 5) -> XacroFit:
    """The template arguments of ``arm``'s catalogue model that best reproduce its tool
    positions at commands Q (module doc)."""
    robot = arm.robot
    if not robot.params:
        raise UnsupportedModelError(
            f"{robot.name}: not a catalogue model, so no xacro arguments (use the URDF)"
        )
    spec = get_spec(robot.name)
    base = {k: float(v) for k, v in robot.params.items()
            if k not in spec.fixed and k not in spec.integers
            and isinstance(v, int | float)}  # fmt: skip
    target = arm.positions(Q)
    here = _positions(robot.name, base, Q)
    moving = [k for k in base
              if np.abs(_positions(robot.name, {**base, k: base[k] + STEP}, Q) - here).max()
              > 1e-3 * STEP]  # fmt: skip
    values, now = dict(base), here
    for _ in range(iterations):
        residual = (target - now).ravel()
        J = np.column_stack([
            ((_positions(robot.name, {**values, k: values[k] + STEP}, Q) - now) / STEP).ravel()
            for k in moving
        ])  # fmt: skip
        step = np.linalg.lstsq(J, residual, rcond=None)[0]
        for k, dv in zip(moving, step, strict=True):
            values[k] += float(dv)
        now = _positions(robot.name, values, Q)
        if np.abs(step).max() < 1e-10:
            break
    left = target - now
    rms = float(np.sqrt(np.mean(np.sum(left**2, axis=1))))
    return XacroFit({k: values[k] for k in moving}, {k: base[k] for k in moving}, rms)
