"""What the maps need of a joint-offset layer (:class:`toolkit.papers.backlash.Backlash`,
[P1]'s backlash model) given in place of a robot: a protocol, so that the maps neither
import the papers package nor decide by a class name."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..robot import Robot

__all__ = ["OffsetLayer", "layer_of"]


@runtime_checkable
class OffsetLayer(Protocol):
    """A layer over ``robot`` whose joint outputs differ from the commands by offsets that
    depend on the torques: its gap ``delta`` and coefficient ``k_h`` per joint, the
    ``nominal_torque`` and the ``payload`` [kg]; ``solve`` gives the outputs of commands,
    ``command_for`` the commands that give outputs, and ``with_parameters`` /
    ``with_payload`` copies with other coefficients or another payload."""

    robot: Robot
    delta: np.ndarray
    k_h: np.ndarray
    nominal_torque: np.ndarray
    payload: float

    def solve(self, q_cmd: ArrayLike, **options: Any) -> Any: ...

    def command_for(self, theta: ArrayLike) -> np.ndarray: ...

    def with_parameters(self, delta: ArrayLike, k_h: ArrayLike) -> OffsetLayer: ...

    def with_payload(self, payload: float) -> OffsetLayer: ...


def layer_of(value: object) -> OffsetLayer | None:
    """``value`` if it is a joint-offset layer, else None (a robot)."""
    return value if isinstance(value, OffsetLayer) else None
