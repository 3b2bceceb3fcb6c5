"""Residuals and the identification Jacobian of a calibration problem (see
:mod:`toolkit.calibration`): the derivative of every prediction with respect to every
parameter, from Pinocchio's frame Jacobians and exp6's Jacobian (exact at any estimate),
the layer's part by central differences of its output angles."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import InvalidParameterError
from ._measure import Block, Measurements, rotation_residual
from ._model import Errors, ParameterSet

__all__ = ["GRAVITY", "Problem", "predict"]

GRAVITY = np.array([0.0, 0.0, -1.0])  # the direction of gravity in the world frame
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def predict(pset: ParameterSet, errors: Errors, Q: np.ndarray, frame: int) -> np.ndarray:
    """World poses (N, 4, 4) of frame id ``frame`` at commands Q under ``errors``."""
    model = pset.model(errors)
    data = model.createData()
    theta = pset.output_angles(errors, Q)
    out = np.empty((len(Q), 4, 4))
    for i, th in enumerate(theta):
        pin.framesForwardKinematics(model, data, th)
        out[i] = (errors.base * data.oMf[frame]).homogeneous
    return out


class Problem:
    """Configurations Q (N, nq) and measurements of them, for one parameter set."""

    def __init__(self, pset: ParameterSet, Q: np.ndarray, measurements: Measurements) -> None:
        if not isinstance(measurements, Measurements) or not measurements.blocks:
            raise InvalidParameterError("measurements must be a non-empty toolkit Measurements")
        self.pset, self.Q = pset, Q
        self.blocks: list[tuple[Block, np.ndarray, int]] = []
        for b in measurements.blocks:
            at = np.arange(len(Q)) if b.at is None else b.at
            if len(at) != len(b.values) or (len(at) and at.max() >= len(Q)):
                raise InvalidParameterError(
                    f"{len(b.values)} {b.kind} measurements for {len(Q)} configurations: "
                    "give one per configuration, or their indices with at="
                )
            frame = pset.tip if b.kind != "gravity" else pset.robot.frames.id(b.link)
            self.blocks.append((b, at, frame))
        self.sigma = np.concatenate([b.sigma.ravel() for b, _, _ in self.blocks])
        # one group of rows per measurement (3 or 6 rows), for the robust weights
        self.groups = np.concatenate(
            [np.repeat(np.arange(len(b.values)), b.rows) for b, _, _ in self.blocks]
        )
        offsets = np.cumsum([0] + [len(b.values) for b, _, _ in self.blocks])
        self.groups = self.groups + np.repeat(
            offsets[:-1], [len(b.values) * b.rows for b, _, _ in self.blocks]
        )
        self.count = int(offsets[-1])
        model = pset.robot.model
        self._subtrees = [set(int(j) for j in model.subtrees[i]) for i in range(model.njoints)]

    # ------------------------------------------------------------------ evaluation
    def residuals(self, errors: Errors) -> np.ndarray:
        """Measured minus predicted, every row (not yet divided by sigma)."""
        return self.evaluate(errors, jacobian=False)[0]

    def evaluate(self, errors: Errors, jacobian: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(residuals (R,), Jacobian of the predictions (R, P)) at ``errors``: the
        kinematics of each configuration once, whatever number of blocks measured it
        (frame Jacobians only when the Jacobian is asked for)."""
        pset = self.pset
        model = pset.model(errors)
        data = model.createData()
        theta = pset.output_angles(errors, self.Q)
        entries = [(b, k, int(i), f) for b, at, f in self.blocks for k, i in enumerate(at)]
        res: list[np.ndarray] = [np.empty(0)] * len(entries)
        jac: list[np.ndarray] = [np.empty(0)] * len(entries)
        if jacobian:
            dtheta = self._dtheta(errors)
            jexp = {
                key: pin.Jexp6(pin.log6(pset.placement_error(errors, *key)).vector)
                for key in pset.groups
            }
        last = -1
        for e in sorted(range(len(entries)), key=lambda e: entries[e][2]):
            b, k, i, frame = entries[e]
            if i != last:
                if jacobian:
                    pin.computeJointJacobians(model, data, theta[i])
                    pin.updateFramePlacements(model, data)
                else:
                    pin.framesForwardKinematics(model, data, theta[i])
                last = i
            W = errors.base * data.oMf[frame]
            res[e] = self._residual(b, k, W)
            if jacobian:
                jac[e] = self._rows(b, k, model, data, frame, W, errors, dtheta[i], jexp)
        r = np.concatenate(res)
        return r, (np.vstack(jac) if jacobian else np.zeros((len(r), 0)))

    @staticmethod
    def _residual(b: Block, k: int, W: pin.SE3) -> np.ndarray:
        if b.kind == "position":
            return np.asarray(b.values[k] - W.translation)
        if b.kind == "pose":
            M = b.values[k]
            return np.concatenate(
                [M[:3, 3] - W.translation, rotation_residual(M[:3, :3], W.rotation)]
            )
        return np.asarray(b.values[k] - W.rotation.T @ GRAVITY)

    def _rows(
        self, b: Block, k: int, model: pin.Model, data: pin.Data, frame: int, W: pin.SE3,
        errors: Errors, dtheta: np.ndarray, jexp: dict[tuple[str, int], np.ndarray],
    ) -> np.ndarray:  # fmt: skip
        """The measurement's rows of the Jacobian: (position, rotation) derivatives in
        the world frame, then mapped to what is measured."""
        dp, dphi = self._motion(model, data, frame, W, errors, dtheta, jexp)
        if b.kind == "position":
            return dp
        if b.kind == "pose":  # the residual log3(R_m R^T) moves by -Jlog3(R_m R^T) dphi
            E = b.values[k][:3, :3] @ W.rotation.T
            return np.vstack([dp, pin.Jlog3(E) @ dphi])
        return np.asarray(W.rotation.T @ _skew(GRAVITY) @ dphi)

    def _motion(
        self, model: pin.Model, data: pin.Data, frame: int, W: pin.SE3, errors: Errors,
        dtheta: np.ndarray, jexp: dict[tuple[str, int], np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        pset = self.pset
        P = len(pset.params)
        dp, dphi = np.zeros((3, P)), np.zeros((3, P))
        Rb = errors.base.rotation
        Jf = pin.getFrameJacobian(model, data, frame, _LWA)
        moved = Rb @ Jf[:3] @ dtheta, Rb @ Jf[3:] @ dtheta  # through the joint angles
        dp += moved[0]
        dphi += moved[1]
        p = W.translation
        joint = int(model.frames[frame].parentJoint)
        subtrees = self._subtrees
        for k, par in enumerate(pset.params):
            if par.kind in ("offsets", "compliance", "backlash"):
                continue
            if par.kind == "geometry":
                if joint not in subtrees[par.joint]:
                    continue  # the measured frame is not downstream of this joint
                F = errors.base * data.oMi[model.parents[par.joint]]
                F = F * model.jointPlacements[par.joint]
            elif par.kind == "tool":
                if frame != pset.tip:
                    continue
                F = W
            else:
                F = errors.base
            axis = F.rotation[:, par.axis % 3]
            if par.axis < 3:
                dp[:, k] += axis
            else:
                dp[:, k] += np.cross(axis, p - F.translation)
                dphi[:, k] += axis
        for key, cols in pset.groups.items():  # a move of exp6(v)'s frame, per unit of v
            J6 = jexp[key]
            dp[:, cols] = dp[:, cols] @ J6
            dphi[:, cols] = dphi[:, cols] @ J6
        return dp, dphi

    def _dtheta(self, errors: Errors) -> np.ndarray:
        """d theta / d step (N, nv, P): offsets and the layer through its output angles
        (central differences), compliance from the gravity torques."""
        pset, Q = self.pset, self.Q
        model = pset.robot.model
        out = np.zeros((len(Q), model.nv, len(pset.params)))
        layer = errors.layer
        G = np.atleast_2d(pset.robot.gravity(Q)) if "compliance" in pset.kinds else None
        for k, par in enumerate(pset.params):
            if par.kind == "offsets":
                out[:, :, k] = self._through_layer(errors, par.joint)
            elif par.kind == "compliance":
                assert G is not None
                iv = model.idx_vs[par.joint]
                out[:, iv, k] = -G[:, iv]
            elif par.kind == "backlash":
                out[:, :, k] = self._layer_step(errors, layer, par.joint, par.axis)
        return out

    def _through_layer(self, errors: Errors, joint: int) -> np.ndarray:
        model = self.pset.robot.model
        if errors.layer is None:
            d = np.zeros((len(self.Q), model.nv))
            d[:, model.idx_vs[joint]] = 1.0
            return d
        h = 1e-6
        up, down = replace_offset(errors, joint, h), replace_offset(errors, joint, -h)
        ahead, behind = self.pset.output_angles(up, self.Q), self.pset.output_angles(down, self.Q)
        return np.asarray((ahead - behind) / (2 * h))

    def _layer_step(self, errors: Errors, layer: Any, joint: int, which: int) -> np.ndarray:
        i = self.pset.joints.index(joint)
        delta, k_h = np.array(layer.delta, dtype=float), np.array(layer.k_h, dtype=float)
        base = delta if which == 0 else k_h
        h = 1e-6 * max(1.0, abs(base[i]))
        lower = -h if base[i] >= h else 0.0  # delta and k_H are >= 0: one-sided at 0
        rows = []
        for shift in (h, lower):
            values = base.copy()
            values[i] += shift
            moved = (
                layer.with_parameters(values, k_h)
                if which == 0
                else layer.with_parameters(delta, values)
            )
            rows.append(self.pset.output_angles(_with_layer(errors, moved), self.Q))
        return np.asarray((rows[0] - rows[1]) / (h - lower))


def replace_offset(errors: Errors, joint: int, h: float) -> Errors:
    """``errors`` with joint ``joint``'s offset moved by h."""
    offsets = errors.offsets.copy()
    offsets[joint] += h
    return replace(errors, offsets=offsets)


def _with_layer(errors: Errors, layer: Any) -> Errors:
    return replace(errors, layer=layer)
