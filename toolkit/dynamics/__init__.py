"""Rigid-body dynamics of a robot, on one configuration or a batch: the joint torques a
motion needs (:func:`inverse_dynamics`, Pinocchio's RNEA), the joint-space inertia
(:func:`mass_matrix`, CRBA), the motion torques cause (:func:`forward_dynamics`, ABA),
each with an optional payload at a frame.

Free functions of a robot (a :class:`~toolkit.robot.Robot`: its model and its input
checks); the robot's model is never changed (a payload is added to a copy, kept per robot,
payload and frame). The algorithms are in :mod:`toolkit.dynamics.rigid`, the payload in
:mod:`toolkit.dynamics.payload`.
"""

from . import payload as payload
from . import rigid as rigid
from .payload import Payload
from .payload import require_inertia as require_inertia
from .rigid import forward_dynamics, gravity, inverse_dynamics, mass_matrix

__all__ = [
    "Payload",
    "forward_dynamics",
    "gravity",
    "inverse_dynamics",
    "mass_matrix",
]
