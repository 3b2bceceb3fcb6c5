"""Inverse dynamics, the mass matrix and forward dynamics through Pinocchio (RNEA, CRBA,
ABA), on one configuration or N, with an optional payload (see :mod:`toolkit.dynamics`).
A batch of :data:`COMPILED_MIN` rows or more of a robot on the compiled back end whose
tree has revolute, prismatic and continuous joints only runs the compiled RNEA
(:mod:`toolkit.dynamics.kernels`, on that back end's packed tree) over every core instead
of Pinocchio row by row."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..errors import InvalidParameterError
from ..kinematics import CompiledBackend, joints, parallel
from . import kernels as _kernels
from .payload import DynamicsSubject, model_with, require_inertia

__all__ = [
    "COMPILED_MIN",
    "compiled_tree",
    "forward_dynamics",
    "gravity",
    "inverse_dynamics",
    "mass_matrix",
]

COMPILED_MIN = 8
"""Rows from which ``inverse_dynamics`` runs compiled (fewer: Pinocchio, row by row)."""


def compiled_tree(backend: object) -> tuple[np.ndarray, np.ndarray] | None:
    """The packed tree (ints, flts) of a robot's kinematics back end for
    :func:`toolkit.dynamics.kernels.rnea_batch`, or None where the back end is not compiled
    or the tree has a joint the compiled RNEA does not take (a free flyer, a mimic joint)."""
    if not isinstance(backend, CompiledBackend):
        return None
    ints, flts, _, _ = backend.tree
    plain = np.isin(ints[:, 1], (joints.REVOLUTE, joints.PRISMATIC, joints.CIRCLE)).all()
    simple = (flts[:, 15] == 1.0).all() and (flts[:, 16] == 0.0).all()
    if plain and simple and len(set(ints[:, 3].tolist())) == len(ints):
        return ints, flts
    return None


def _bodies(model: pin.Model) -> np.ndarray:
    """(n, 13): per joint the body's mass, centre of mass (3) and inertia about it (9)."""
    out = np.empty((model.njoints - 1, 13))
    for j in range(1, model.njoints):
        body = model.inertias[j]
        out[j - 1, 0] = body.mass
        out[j - 1, 1:4] = body.lever
        out[j - 1, 4:] = np.asarray(body.inertia).ravel()
    return out


def _rows(robot: DynamicsSubject, q: ArrayLike, named: dict[str, ArrayLike]) -> tuple[
    np.ndarray, list[np.ndarray], bool
]:  # fmt: skip
    """(q (N, nq), the velocity-like arrays (N, nv) in order, whether one configuration)."""
    if not isinstance(robot, DynamicsSubject):
        raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r:.80}")
    Q = robot.joints.check(q, batch=True)
    single = Q.ndim == 1
    Q = np.atleast_2d(Q)
    out = []
    for what, value in named.items():
        V = np.atleast_2d(robot.joints.check_v(value, what, batch=True))
        if V.shape[0] != Q.shape[0]:
            raise InvalidParameterError(
                f"{what} has {V.shape[0]} rows, q has {Q.shape[0]}: one per configuration"
            )
        out.append(V)
    return Q, out, single


def inverse_dynamics(
    robot: DynamicsSubject, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
    payload: object = None,
) -> np.ndarray:  # fmt: skip
    """The joint torques [N m or N] (nv,) that give accelerations ``qdd`` at ``q``, ``qd``
    (or (N, nv) for N rows): M(q) qdd + C(q, qd) qd + g(q) (Pinocchio's RNEA; compiled and
    spread over the cores from :data:`COMPILED_MIN` rows), with a ``payload`` (a mass [kg]
    at the tip, or a :class:`Payload`)."""
    Q, (V, A), single = _rows(robot, q, {"qd": qd, "qdd": qdd})
    require_inertia(robot, "inverse dynamics")
    model = model_with(robot, payload)
    tree = compiled_tree(getattr(robot, "kinematics", None)) if len(Q) >= COMPILED_MIN else None
    if tree is not None:
        gravity = np.array(model.gravity.linear, dtype=float)
        armature = np.ascontiguousarray(model.armature, dtype=float)
        return np.asarray(_kernels.rnea_batch(
            parallel(len(Q)), np.ascontiguousarray(Q, dtype=float),
            np.ascontiguousarray(V, dtype=float), np.ascontiguousarray(A, dtype=float),
            *tree, _bodies(model), gravity, armature,
        ))  # fmt: skip
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *row) for row in zip(Q, V, A, strict=True)])
    return tau[0] if single else tau


def gravity(robot: DynamicsSubject, q: ArrayLike, *, payload: object = None) -> np.ndarray:
    """The generalized gravity torques g(q) [N m or N] (nv,) (or (N, nv)): what the joints
    must exert to hold the arm still (``Robot.gravity``). Without a payload, the kinematics
    back end's own (compiled: over the cores for a batch; else Pinocchio's
    ``computeGeneralizedGravity``); with one (as for :func:`inverse_dynamics`), the RNEA at
    rest on the model carrying it."""
    Q, _, single = _rows(robot, q, {})
    require_inertia(robot, "gravity")
    if payload is not None:
        rest = np.zeros((len(Q), robot.joints.nv))
        tau = inverse_dynamics(robot, Q, rest, rest, payload=payload)
    else:
        tau = np.asarray(robot.kinematics.gravity(Q))
    return tau[0] if single else tau


def mass_matrix(robot: DynamicsSubject, q: ArrayLike, *, payload: object = None) -> np.ndarray:
    """The joint-space inertia matrix M(q) (nv, nv) (or (N, nv, nv)), symmetric (CRBA;
    compiled and spread over the cores from :data:`COMPILED_MIN` rows, as
    :func:`inverse_dynamics`)."""
    Q, _, single = _rows(robot, q, {})
    require_inertia(robot, "the mass matrix")
    model = model_with(robot, payload)
    tree = compiled_tree(getattr(robot, "kinematics", None)) if len(Q) >= COMPILED_MIN else None
    if tree is not None:
        armature = np.ascontiguousarray(model.armature, dtype=float)
        return np.asarray(_kernels.crba_batch(
            parallel(len(Q)), np.ascontiguousarray(Q, dtype=float), *tree, _bodies(model),
            armature, model.nv,
        ))  # fmt: skip
    data = model.createData()
    out = np.empty((len(Q), model.nv, model.nv))
    for k, row in enumerate(Q):
        M = np.array(pin.crba(model, data, row))
        out[k] = np.triu(M) + np.triu(M, 1).T  # CRBA fills the upper triangle
    return out[0] if single else out


def forward_dynamics(
    robot: DynamicsSubject, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, *,
    payload: object = None,
) -> np.ndarray:  # fmt: skip
    """The joint accelerations (nv,) (or (N, nv)) that torques ``tau`` cause at ``q``,
    ``qd`` (Pinocchio's ABA), with a ``payload`` as for :func:`inverse_dynamics`. On a
    model with mimic joints (the bending manipulator), which ABA does not take, by the
    projection the RNEA and CRBA make there: M(q) qdd = tau - rnea(q, qd, 0)."""
    Q, (V, T), single = _rows(robot, q, {"qd": qd, "tau": tau})
    require_inertia(robot, "forward dynamics")
    model = model_with(robot, payload)
    data = model.createData()
    if _has_mimic(model):
        zero = np.zeros(model.nv)
        rows = []
        for row_q, row_v, row_t in zip(Q, V, T, strict=True):
            M = np.array(pin.crba(model, data, row_q))
            M = np.triu(M) + np.triu(M, 1).T
            bias = np.array(pin.rnea(model, data, row_q, row_v, zero))
            rows.append(np.linalg.solve(M, row_t - bias))
        qdd = np.array(rows)
    else:
        qdd = np.array([pin.aba(model, data, *row) for row in zip(Q, V, T, strict=True)])
    return qdd[0] if single else qdd


def _has_mimic(model: pin.Model) -> bool:
    """Whether a joint of the model follows another (Pinocchio's mimic joints)."""
    return any(j.shortname().startswith("JointModelMimic") for j in model.joints)
