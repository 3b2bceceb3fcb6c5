"""Joint backlash ([P1], eqs. 16-17): the joint-output angle is the command plus an offset.

One module per concept:

* :mod:`~toolkit.backlash.law`: eq. 17 (:func:`offset`, :func:`hysteresis_offsets`);
* :mod:`~toolkit.backlash.fixed_point`: theta = q_cmd + dtheta(M(theta)) for N commands;
* :mod:`~toolkit.backlash.layer`: :class:`Backlash` on any robot (torques, output angles,
  actual poses, compensation);
* :mod:`~toolkit.backlash.calibration`: :func:`calibrate` (delta, k_H) from measurements;
* :mod:`~toolkit.backlash.maps`: error maps and [P1]'s Fig. 6;
* :mod:`~toolkit.backlash.motion`: the backlash along a motion (the motion's torques
  beside gravity's), and the commands that undo it;
* :mod:`~toolkit.backlash.simulation`: the links driven through their gaps by forward
  dynamics (:func:`simulate`), a check of the motion's reading by another route.
"""

from .calibration import Calibration, calibrate
from .fixed_point import OutputAngles
from .law import DEFAULT_DELTA, DEFAULT_K_H, TORQUE_TOL, hysteresis_offsets, offset
from .layer import Backlash
from .maps import ErrorMap, Figure6, draw_figure6, error_grid, error_map, figure6
from .motion import (
    MotionBacklash,
    along,
    compensate_motion,
    draw_motion_backlash,
    draw_parting,
    dynamic_outputs,
    parting,
    pick_and_place,
)
from .simulation import SimulatedBacklash, simulate

__all__ = [
    "DEFAULT_DELTA",
    "DEFAULT_K_H",
    "TORQUE_TOL",
    "Backlash",
    "Calibration",
    "ErrorMap",
    "Figure6",
    "MotionBacklash",
    "OutputAngles",
    "SimulatedBacklash",
    "along",
    "calibrate",
    "compensate_motion",
    "draw_figure6",
    "draw_motion_backlash",
    "draw_parting",
    "dynamic_outputs",
    "error_grid",
    "error_map",
    "figure6",
    "hysteresis_offsets",
    "offset",
    "parting",
    "pick_and_place",
    "simulate",
]
