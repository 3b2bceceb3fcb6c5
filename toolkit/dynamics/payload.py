"""A payload fixed to a robot's frame, and the robot's model carrying it (a copy: the
robot's own model is never changed); what the dynamics need of a robot."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import pinocchio as pin

from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..kinematics import Backend, Frames, JointLayout

__all__ = ["DynamicsSubject", "Payload", "model_with"]


@runtime_checkable
class DynamicsSubject(Protocol):
    """What the dynamics need of a robot (a :class:`~toolkit.robot.Robot`)."""

    model: pin.Model
    joints: JointLayout  # its checks of q and of velocities
    frames: Frames
    kinematics: Backend

    @property
    def tip(self) -> str: ...


@dataclass(frozen=True)
class Payload:
    """A rigid load fixed to a frame: ``mass`` [kg], its centre of mass ``com`` [m] in the
    frame (default its origin), its ``inertia`` [kg m^2] about the centre of mass in the
    frame's axes (default none: a point mass), ``frame`` (default the robot's tip)."""

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[float, ...] = (0.0,) * 9
    frame: str | None = None

    @classmethod
    def of(cls, value: object) -> Payload | None:
        """A payload from None, a mass [kg] (a point mass at the tip) or a Payload, checked."""
        if value is None:
            return None
        if not isinstance(value, Payload):
            value = cls(_validate.number(value, "payload [kg]"))
        mass = _validate.number(value.mass, "payload mass [kg]", lower=0.0)
        com = _validate.real_array(value.com, "payload com [m]").ravel()
        inertia = _validate.real_array(value.inertia, "payload inertia [kg m^2]").reshape(-1)
        if com.shape != (3,) or inertia.shape != (9,):
            raise InvalidParameterError("payload com is 3 numbers [m], its inertia 3 x 3")
        if not (np.all(np.isfinite(com)) and np.all(np.isfinite(inertia))):
            raise InvalidParameterError("payload com and inertia must be finite")
        I3 = inertia.reshape(3, 3)
        if np.abs(I3 - I3.T).max() > 1e-9 or np.linalg.eigvalsh(I3).min() < -1e-12:
            raise InvalidParameterError("payload inertia must be symmetric, positive semidefinite")
        return cls(mass, tuple(com.tolist()), tuple(inertia.tolist()), value.frame)


def require_inertia(robot: DynamicsSubject, what: str) -> None:
    """Refuse ``what`` (a dynamics answer) for a robot whose description gives links with
    shapes no inertia (``facts["without_inertia"]``, found at load), or whose moving bodies
    weigh nothing at all: every torque would read 0 and every acceleration NaN."""
    missing = tuple(getattr(robot, "facts", {}).get("without_inertia") or ())
    model = robot.model
    if not missing and sum(model.inertias[j].mass for j in range(1, model.njoints)) <= 0.0:
        missing = tuple(model.names[j] for j in range(1, model.njoints))
    if missing:
        raise UnsupportedModelError(
            f"{getattr(robot, 'name', 'the robot')}: {what} needs the links' inertia, and its "
            f"description gives none for {', '.join(missing[:12])}"
            f"{' ...' if len(missing) > 12 else ''}: add <inertial> blocks (mass, origin, "
            "inertia) to them"
        )


def model_with(robot: DynamicsSubject, payload: object) -> pin.Model:
    """The robot's model, or a copy with the payload's body added to its frame's joint."""
    load = Payload.of(payload)
    if load is None:
        return robot.model
    model = pin.Model(robot.model)
    frame = model.frames[robot.frames.id(load.frame)]
    where = frame.placement * pin.SE3(np.eye(3), np.array(load.com))
    body = pin.Inertia(load.mass, np.zeros(3), np.array(load.inertia).reshape(3, 3))
    model.appendBodyToJoint(int(frame.parentJoint), body, where)
    return model
