"""The error parameters of a robot and the model they make (see :mod:`toolkit.calibration`).

An estimate holds, per moving joint, a placement error E_j (the joint's placement becomes
M_j E_j), a zero offset and a compliance; a base error E_b (the world sees E_b times the
model) and a tool error E_t (the tool frame becomes its placement times E_t); and, with a
joint-offset layer, its delta and k_H per joint. The joint-output angles are

    theta = h(q + offset) - compliance * g(q)

with h the layer's output angles (the identity without a layer) and g(q) the joint
torques [N m] that hold the arm against gravity at the command q. Every parameter moves
additively; the identification Jacobian maps a change of v through exp6's Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import InvalidParameterError, UnsupportedModelError
from ..robot import Robot

__all__ = ["AXES", "KINDS", "Errors", "OutOfBounds", "Parameter", "ParameterSet"]

KINDS = ("offsets", "geometry", "base", "tool", "compliance", "backlash")
AXES = ("x", "y", "z", "rx", "ry", "rz")
_ONE_DOF = ("RX", "RY", "RZ", "RevoluteUnaligned", "PX", "PY", "PZ", "PrismaticUnaligned")


class OutOfBounds(ValueError):
    """A step that takes a parameter out of its range (the fit tries a shorter one)."""


@dataclass(frozen=True)
class Parameter:
    """One error parameter: ``name`` (e.g. ``geometry.joint2.rz``), ``kind`` (one of
    :data:`KINDS`), ``joint`` (Pinocchio joint id; 0 for base and tool), ``axis`` (0-5 for
    a placement error: x, y, z [m], rx, ry, rz [rad]; 0 or 1 for the layer's delta, k_H)."""

    name: str
    kind: str
    joint: int
    axis: int = 0


@dataclass
class Errors:
    """One estimate of every error (the nominal robot: all identity and zero)."""

    placements: dict[int, pin.SE3]
    base: pin.SE3
    tool: pin.SE3
    offsets: np.ndarray  # per joint id (index 0 unused)
    compliance: np.ndarray  # rad / (N m), per joint id
    layer: Any = None  # a joint-offset layer with delta and k_h, or None


def _added(error: pin.SE3, twist: np.ndarray) -> pin.SE3:
    return pin.exp6(pin.log6(error).vector + twist)


def _kinds(parameters: object) -> tuple[str, ...]:
    if isinstance(parameters, str):
        parameters = (parameters,)
    try:
        kinds: tuple[object, ...] = tuple(parameters)  # type: ignore[arg-type]
    except TypeError:
        raise InvalidParameterError(
            f"parameters must be names from {KINDS}, got {parameters!r:.80}"
        ) from None
    unknown = [k for k in kinds if k not in KINDS]
    if unknown or not kinds:
        raise InvalidParameterError(
            f"unknown parameter set(s) {unknown or kinds!r}; choose from {', '.join(KINDS)}"
        )
    return tuple(k for k in KINDS if k in kinds)  # one order, whatever was asked


class ParameterSet:
    """The error parameters of ``robot`` chosen by kind (module doc); ``layer`` is a
    joint-offset layer (a :class:`toolkit.backlash.Backlash`) for "backlash"."""

    def __init__(self, robot: Robot, parameters: object, layer: Any = None) -> None:
        if not isinstance(robot, Robot):
            raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r:.80}")
        self.robot = robot
        self.kinds = _kinds(parameters)
        model = robot.model
        self.joints = [
            j
            for j in range(1, model.njoints)
            if model.joints[j].shortname().replace("JointModel", "") in _ONE_DOF
        ]
        if ("offsets" in self.kinds or "compliance" in self.kinds) and not self.joints:
            raise UnsupportedModelError(f"{robot.name}: no revolute or prismatic joint")
        if "backlash" in self.kinds and layer is None:
            raise InvalidParameterError('"backlash" needs the layer: layer=Backlash(robot)')
        if layer is not None and getattr(layer, "robot", None) is not robot:
            raise InvalidParameterError("the layer must be built on the same robot")
        self.layer = layer
        self.tip = robot.frames.id(None)
        self.params = self._list()
        self.names = [p.name for p in self.params]
        # the placement errors' six entries, by (kind, joint): their columns in the set
        self.groups: dict[tuple[str, int], list[int]] = {}
        for k, p in enumerate(self.params):
            if p.kind in ("geometry", "base", "tool"):
                self.groups.setdefault((p.kind, p.joint), []).append(k)

    def same_as_offsets(self) -> dict[int, str]:
        """{parameter index: offset name} of the placement errors that are a joint's zero
        offset by construction: the turn about a revolute joint's own (principal) axis, the
        shift along a prismatic joint's, when offsets are in the set."""
        if "offsets" not in self.kinds or "geometry" not in self.kinds:
            return {}
        model, out = self.robot.model, {}
        for j in self.joints:
            short = model.joints[j].shortname().replace("JointModel", "")
            if short[-1:] not in ("X", "Y", "Z") or short[0] not in ("R", "P"):
                continue  # an unaligned axis: left to the numeric test
            axis = "XYZ".index(short[-1]) + (3 if short[0] == "R" else 0)
            k = self.groups[("geometry", j)][axis]
            out[k] = f"offset.{model.names[j]}"
        return out

    def placement_error(self, errors: Errors, kind: str, joint: int) -> pin.SE3:
        """The current placement error of a (kind, joint) group."""
        if kind == "base":
            return errors.base
        if kind == "tool":
            return errors.tool
        return errors.placements.get(joint, pin.SE3.Identity())

    def _list(self) -> list[Parameter]:
        names = self.robot.model.names
        out: list[Parameter] = []
        for kind in self.kinds:
            if kind == "offsets" or kind == "compliance":
                out += [Parameter(f"{kind[:-1] if kind == 'offsets' else kind}.{names[j]}",
                                  kind, j) for j in self.joints]  # fmt: skip
            elif kind == "geometry":
                for j in range(1, self.robot.model.njoints):
                    out += [Parameter(f"geometry.{names[j]}.{a}", kind, j, i)
                            for i, a in enumerate(AXES)]  # fmt: skip
            elif kind in ("base", "tool"):
                out += [Parameter(f"{kind}.{a}", kind, 0, i) for i, a in enumerate(AXES)]
            else:  # backlash: delta and k_H of each joint of the layer
                for j in self.joints:
                    out += [Parameter(f"backlash.delta.{names[j]}", kind, j, 0),
                            Parameter(f"backlash.k_h.{names[j]}", kind, j, 1)]  # fmt: skip
        return out

    def __len__(self) -> int:
        return len(self.params)

    # ------------------------------------------------------------------ estimates
    def nominal(self) -> Errors:
        """The robot as described: no error."""
        n = self.robot.model.njoints
        return Errors({}, pin.SE3.Identity(), pin.SE3.Identity(), np.zeros(n), np.zeros(n),
                      self.layer)  # fmt: skip

    def values(self, errors: Errors) -> np.ndarray:
        """The parameters' values at an estimate (placement errors as log6: v [m], w
        [rad]; the layer's delta [rad] and k_H)."""
        out = np.zeros(len(self.params))
        for k, p in enumerate(self.params):
            out[k] = self._value(errors, p)
        return out

    def _value(self, e: Errors, p: Parameter) -> float:
        if p.kind == "offsets":
            return float(e.offsets[p.joint])
        if p.kind == "compliance":
            return float(e.compliance[p.joint])
        if p.kind == "backlash":
            i = self.joints.index(p.joint)
            return float((e.layer.delta if p.axis == 0 else e.layer.k_h)[i])
        se3 = {"base": e.base, "tool": e.tool}.get(p.kind)
        if se3 is None:
            se3 = e.placements.get(p.joint, pin.SE3.Identity())
        return float(pin.log6(se3).vector[p.axis])

    def update(self, errors: Errors, step: np.ndarray) -> Errors:
        """The estimate moved by ``step`` (one entry per parameter): every value adds
        (a placement error E = exp6(v) becomes exp6(v + step))."""
        blocks: dict[tuple[str, int], np.ndarray] = {}
        offsets, compliance = errors.offsets.copy(), errors.compliance.copy()
        layer = errors.layer
        delta = None if layer is None else np.array(layer.delta, dtype=float)
        k_h = None if layer is None else np.array(layer.k_h, dtype=float)
        for p, s in zip(self.params, step, strict=True):
            if p.kind == "offsets":
                offsets[p.joint] += s
            elif p.kind == "compliance":
                compliance[p.joint] += s
            elif p.kind == "backlash":
                i = self.joints.index(p.joint)
                target = delta if p.axis == 0 else k_h
                target[i] += s  # type: ignore[index]
            else:
                blocks.setdefault((p.kind, p.joint), np.zeros(6))[p.axis] += s
        placements = dict(errors.placements)
        base, tool = errors.base, errors.tool
        for (kind, j), twist in blocks.items():
            if kind == "base":
                base = _added(base, twist)
            elif kind == "tool":
                tool = _added(tool, twist)
            else:
                placements[j] = _added(placements.get(j, pin.SE3.Identity()), twist)
        if layer is not None and "backlash" in self.kinds:
            if np.any(delta < 0) or np.any(k_h < 0):  # type: ignore[operator]
                raise OutOfBounds("delta and k_H must stay >= 0")
            layer = layer.with_parameters(delta, k_h)
        return replace(errors, placements=placements, base=base, tool=tool, offsets=offsets,
                       compliance=compliance, layer=layer)  # fmt: skip

    # ------------------------------------------------------------------ the model
    def model(self, errors: Errors) -> pin.Model:
        """The robot's Pinocchio model with the placement and tool errors applied."""
        model = pin.Model(self.robot.model)
        for j, error in errors.placements.items():
            model.jointPlacements[j] = model.jointPlacements[j] * error
        frame = model.frames[self.tip]
        frame.placement = frame.placement * errors.tool
        model.frames[self.tip] = frame
        return model

    def output_angles(self, errors: Errors, Q: np.ndarray) -> np.ndarray:
        """theta (N, nq) for commands Q (N, nq) (module doc)."""
        X = Q.copy()
        idx = self.robot.model.idx_qs
        for j in self.joints:
            X[:, idx[j]] += errors.offsets[j]
        if errors.layer is not None:
            X = np.asarray(errors.layer.output_angles(X), dtype=float).reshape(Q.shape)
        if np.any(errors.compliance):
            G = np.atleast_2d(self.robot.gravity(Q))
            for j in self.joints:
                X[:, idx[j]] -= errors.compliance[j] * G[:, self.robot.model.idx_vs[j]]
        return X
