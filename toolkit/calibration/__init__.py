"""Calibration: identify a real arm's geometry, zero offsets, compliance and joint-offset
layer (backlash) from measurements, and the accuracy gained.

* :class:`ParameterSet` / ``parameters=``: the error parameters by kind, "offsets" (joint
  zeros), "geometry" (each joint placement: x, y, z [m], rx, ry, rz [rad]), "base",
  "tool", "compliance" (rad per N m of the joint's gravity torque), "backlash" (delta
  and k_H of a joint-offset layer);
* :class:`Measurements`: tool positions (laser tracker), tool poses (camera), link gravity
  directions (accelerometer, inclinometer), each with its standard deviation;
  :func:`read_measurements` / :func:`write_measurements` read and write them with their
  configurations as the CSV file ``toolkit calibrate`` takes, and
  :meth:`Measurements.columns` gives their values back by column;
* :func:`perturb` makes a "true" arm with random errors and :func:`simulate` measures it;
* :func:`identify` fits the identifiable parameters by Levenberg-Marquardt with a Huber
  loss, reports what it cannot identify, and returns a :class:`Calibration` with the
  calibrated model (:attr:`Calibration.robot`, :attr:`Calibration.urdf_text`,
  :attr:`Calibration.layer`) and :meth:`Calibration.validate`;
* :func:`select_poses` picks configurations that make the parameters observable (greedy
  D-optimal).

See docs/calibration.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError, UnsupportedModelError
from ..robot import Robot
from ._arm import DEFAULT, ArmModel
from ._csv import read_measurements, write_measurements
from ._identify import Identifiability, as_matrix, identifiability
from ._identify import levenberg_marquardt as _lm
from ._jacobian import Problem
from ._measure import Measurements
from ._model import KINDS, ParameterSet
from ._select import select_poses
from ._xacro import XacroFit, fit_arguments

__all__ = [
    "KINDS",
    "PLAUSIBLE",
    "ArmModel",
    "Calibration",
    "Identifiability",
    "Measurements",
    "ParameterSet",
    "Validation",
    "XacroFit",
    "identify",
    "perturb",
    "read_measurements",
    "select_poses",
    "simulate",
    "write_measurements",
]


def perturb(
    robot: Robot,
    seed: int = 0,
    *,
    parameters: object = DEFAULT,
    translation: float = 1e-3,
    rotation: float = np.radians(0.2),
    offset: float = np.radians(0.5),
    compliance: float = 0.0,
    layer: Any = None,
    only: Sequence[str] | None = None,
) -> ArmModel:
    """A "true" arm for simulation: uniform errors within +-``translation`` [m],
    +-``rotation`` [rad] (placements, base, tool), +-``offset`` [rad] (joint zeros),
    [0, ``compliance``] [rad/(N m)]; ``layer`` (with its delta and k_H) as it is.
    ``only``: the names of the parameters to perturb (default: all of the set)."""
    pset = ParameterSet(robot, parameters, layer)
    rng = np.random.default_rng(_validate.count(seed, "seed", minimum=0))
    step = np.zeros(len(pset))
    if only is not None:
        unknown = sorted(set(only) - set(pset.names))
        if unknown:
            raise InvalidParameterError(f"unknown parameter name(s): {unknown[:5]}")
    for k, p in enumerate(pset.params):
        if only is not None and p.name not in only:
            continue
        if p.kind in ("geometry", "base", "tool"):
            step[k] = rng.uniform(-1, 1) * (translation if p.axis < 3 else rotation)
        elif p.kind == "offsets":
            step[k] = rng.uniform(-1, 1) * offset
        elif p.kind == "compliance":
            step[k] = rng.uniform(0, 1) * compliance
    return ArmModel(pset, pset.update(pset.nominal(), step))


def _arm(value: object) -> ArmModel:
    if isinstance(value, ArmModel):
        return value
    if isinstance(value, Robot):
        pset = ParameterSet(value, DEFAULT)
        return ArmModel(pset, pset.nominal())
    raise InvalidParameterError(f"expected a Robot or an ArmModel, got {value!r:.80}")


@renames.renamed(link="frame")
def simulate(
    true_arm: object,
    q: ArrayLike,
    kind: str = "positions",
    noise: float | tuple[float, float] = 2e-5,
    *,
    frame: str | None = None,
    seed: int = 0,
    at: ArrayLike | None = None,
) -> Measurements:
    """Measurements of ``true_arm`` (an :class:`ArmModel`, or a Robot as described) at
    commands q: ``kind`` "positions" (noise [m] per axis), "poses" (noise (position [m],
    rotation [rad])) or "gravity" (in ``frame``'s axes; noise per component). ``at``:
    measure only the configurations q[at] (the measurements then say so, for a mixed
    set)."""
    arm = _arm(true_arm)
    Q = as_matrix(q, arm.robot, "q")
    if at is not None:
        index = np.asarray(_validate.array(at, "at"))
        if index.ndim != 1 or not np.all(index == np.round(index)) or np.any(index < 0):
            raise InvalidParameterError("at must be configuration indices >= 0")
        if len(index) and index.max() >= len(Q):
            raise InvalidParameterError(f"at: an index beyond the {len(Q)} configurations")
        measured = simulate(arm, Q[index.astype(np.int64)], kind, noise, frame=frame, seed=seed)
        return Measurements(tuple(replace(b, at=index.astype(np.int64)) for b in measured.blocks))
    rng = np.random.default_rng(_validate.count(seed, "seed", minimum=0))
    if kind == "positions":
        sigma = _validate.number(noise, "noise [m]", lower=0.0, strict=True)
        return Measurements.positions(arm.positions(Q) + rng.normal(0, sigma, (len(Q), 3)), sigma)
    if kind == "poses":
        pair = (noise, noise) if np.isscalar(noise) else noise
        sp, sr = (_validate.number(v, "noise", lower=0.0, strict=True) for v in pair)  # type: ignore[union-attr]
        T = arm.fk(Q)

        for M in T:
            M[:3, 3] += rng.normal(0, sp, 3)
            M[:3, :3] = pin.exp3(rng.normal(0, sr, 3)) @ M[:3, :3]
        return Measurements.poses(T, sp, sr)
    if kind == "gravity":
        if frame is None:
            raise InvalidParameterError('kind="gravity" needs the frame the sensor is on')
        sigma = _validate.number(noise, "noise", lower=0.0, strict=True)
        g = arm.gravity(Q, frame) + rng.normal(0, sigma, (len(Q), 3))
        return Measurements.gravity(frame, g, sigma)
    raise InvalidParameterError(f'kind must be "positions", "poses" or "gravity", got {kind!r}')


@dataclass(frozen=True)
class Validation:
    """Errors at held-out configurations, before (nominal model) and after calibration:
    mean, 95th percentile and max, in metres for positions and poses (position part),
    radians for gravity directions."""

    before: tuple[float, float, float]
    after: tuple[float, float, float]

    @property
    def reduction(self) -> float:
        """1 - mean after / mean before."""
        return 1.0 - self.after[0] / self.before[0] if self.before[0] > 0 else 0.0

    def __str__(self) -> str:
        b, a = self.before, self.after
        return (
            f"mean {b[0]:.4g} -> {a[0]:.4g}, p95 {b[1]:.4g} -> {a[1]:.4g}, "
            f"max {b[2]:.4g} -> {a[2]:.4g} ({self.reduction:.1%} lower mean)"
        )


def _summary(values: np.ndarray) -> tuple[float, float, float]:
    return float(values.mean()), float(np.percentile(values, 95)), float(values.max())


def _errors_of(arm: ArmModel, Q: np.ndarray, measurements: Measurements) -> np.ndarray:
    out = []
    for b in measurements.blocks:
        at = np.arange(len(Q)) if b.at is None else b.at
        if b.kind == "gravity":
            g = arm.gravity(Q[at], b.link)
            out.append(np.arccos(np.clip(np.sum(g * b.values, axis=1), -1.0, 1.0)))
        else:
            p = arm.positions(Q[at])
            target = b.values if b.kind == "position" else b.values[:, :3, 3]
            out.append(np.linalg.norm(p - target, axis=1))
    return np.concatenate(out)


@dataclass
class Calibration:
    """The result of :func:`identify`: the calibrated model (``model``, ``robot``,
    ``urdf_text``, ``layer``), the parameters and their standard deviations by name, what
    was fixed and why (``identifiability``), the standardised residual norms before and
    after, the outliers (measurement indices, in the order of the blocks)."""

    model: ArmModel
    nominal: ArmModel
    parameters: dict[str, float]
    std: dict[str, float]
    identifiability: Identifiability
    residual_before: np.ndarray
    residual_after: np.ndarray
    outliers: list[int]
    iterations: int
    converged: bool
    _robot: Robot | None = field(default=None, repr=False)

    @property
    def urdf_text(self) -> str:
        """The corrected URDF (geometry, offsets, base and tool folded in)."""
        return self.model.urdf_text

    @property
    def robot(self) -> Robot:
        """The calibrated robot, loaded from :attr:`urdf_text` (compliance and the layer
        are not in a URDF: :attr:`model` predicts with them)."""
        if self._robot is None:
            from ..robot import load_urdf

            nominal = self.nominal.robot
            model = nominal.model
            kinds = [model.joints[j].shortname() for j in range(1, model.njoints)]
            robot = load_urdf(
                self.urdf_text,
                tip=nominal.tip,
                name=f"{nominal.name}-calibrated",
                mimic="JointModelMimic" in kinds,  # as the nominal robot was loaded
                floating=bool(kinds) and kinds[0] == "JointModelFreeFlyer",
            )
            if robot.joints.names != nominal.joints.names or robot.nq != nominal.nq:
                raise UnsupportedModelError(
                    f"the calibrated URDF of {nominal.name} reads back with joints "
                    f"{robot.joints.names} (nq {robot.nq}), not the nominal robot's "
                    f"{nominal.joints.names} (nq {nominal.nq}); use fit.model to predict"
                )
            self._robot = robot
        return self._robot

    @property
    def layer(self) -> Any:
        """The joint-offset layer with the identified delta and k_H (None without one)."""
        return self.model.errors.layer

    def xacro_arguments(self, q: ArrayLike | None = None) -> XacroFit:
        """For a catalogue model: the template arguments (lengths such as the Katana's
        ``a2``) that best reproduce the calibrated tool positions at commands q (default:
        200 random ones), and the error they leave [m] (:mod:`._xacro`)."""
        robot = self.nominal.robot
        Q = robot.random_q(200, seed=0) if q is None else as_matrix(q, robot, "q")
        return fit_arguments(self.model, Q)

    def position_errors(self, truth: ArmModel, q: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """In simulation, where the truth is known: the tool position errors [m] of the
        nominal and of the calibrated model against ``truth`` at commands q (N, nq), e.g.
        at the best q of each voxel of a reachability map."""
        if not isinstance(truth, ArmModel):
            raise InvalidParameterError(f"truth must be an ArmModel, got {truth!r:.80}")
        Q = as_matrix(q, self.nominal.robot, "q")
        real = truth.positions(Q)
        before = np.linalg.norm(self.nominal.positions(Q) - real, axis=1)
        return before, np.linalg.norm(self.model.positions(Q) - real, axis=1)

    def validate(self, q: ArrayLike, measurements: Measurements) -> Validation:
        """Errors of the nominal and the calibrated model against measurements taken at
        held-out commands q."""
        Q = as_matrix(q, self.nominal.robot, "q")
        Problem(self.model.pset, Q, measurements)  # checks that they match
        before = _errors_of(self.nominal, Q, measurements)
        after = _errors_of(self.model, Q, measurements)
        return Validation(_summary(before), _summary(after))

    def __str__(self) -> str:
        def rms(s: np.ndarray) -> float:
            return float(np.sqrt(np.mean(s**2)))

        lines = [
            f"calibration of {self.nominal.robot.name}: {len(self.residual_before)} "
            f"measurements, standardised RMS {rms(self.residual_before):.4g} -> "
            f"{rms(self.residual_after):.4g} in {self.iterations} iterations"
            + ("" if self.converged else " (NOT converged)"),
            str(self.identifiability),
        ]
        if self.outliers:
            lines.append(f"  outliers (down-weighted): {self.outliers}")
        return "\n".join(lines)


PLAUSIBLE = {"length": 0.05, "angle": float(np.radians(5.0))}
"""The largest correction :func:`identify` accepts without ``allow_large``: [m] of a joint
placement or the tool, [rad] of a placement's or the tool's rotation or of a joint zero."""


def _check_plausible(pset: ParameterSet, change: np.ndarray) -> None:
    """An error naming the largest implausible correction and its likely causes."""
    worst: tuple[float, str, float, str] | None = None
    for p, value in zip(pset.params, change.tolist(), strict=True):
        if p.kind not in ("geometry", "tool", "offsets"):
            continue
        angle = p.kind == "offsets" or p.axis >= 3
        bound = PLAUSIBLE["angle" if angle else "length"]
        if abs(value) > bound and (worst is None or abs(value) / bound > worst[0]):
            shown = f"{np.degrees(value):.3g} deg" if angle else f"{1e3 * value:.4g} mm"
            limit = f"{np.degrees(bound):g} deg" if angle else f"{1e3 * bound:g} mm"
            worst = (abs(value) / bound, p.name, value, f"{shown} (beyond {limit})")
    if worst is not None:
        raise InvalidParameterError(
            f"the fit moved {worst[1]} by {worst[3]}: more than a real arm's error. Likely "
            "causes: measurements in millimetres instead of metres, a wrong tool frame, or "
            "joint values in another order (or in degrees). Check them, or pass "
            "allow_large=True if the correction is real"
        )


def _problem(robot: Robot, q: ArrayLike, measurements: Measurements, parameters: object,
             layer: Any) -> tuple[ParameterSet, Problem]:  # fmt: skip
    if not isinstance(robot, Robot):
        raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r:.80}")
    pset = ParameterSet(robot, parameters, layer)
    Q = as_matrix(q, robot, "q")
    return pset, Problem(pset, Q, measurements)


def identify(
    robot: Robot,
    q: ArrayLike,
    measurements: Measurements,
    *,
    parameters: object = DEFAULT,
    layer: Any = None,
    robust: bool = True,
    max_iter: int = 50,
    allow_large: bool = False,
) -> Calibration:
    """Fit the identifiable ``parameters`` of ``robot`` to ``measurements`` taken at
    commands q (N, nq); ``layer``: a joint-offset layer whose delta and k_H start the
    "backlash" fit (and which is applied in any case). Parameters the measurements cannot
    tell apart are fixed at their nominal values and reported, never fitted. With
    ``robust``, a measurement beyond 3 standard deviations is down-weighted (Huber);
    beyond 5 it is reported as an outlier.

    A correction beyond what a real arm's errors plausibly are (:data:`PLAUSIBLE`: 5 cm of a
    joint placement or of the tool, 5 degrees of a placement, the tool or a joint zero; the
    base is free, since a tracker's frame may be anywhere) stops the fit with an
    :class:`~toolkit.errors.InvalidParameterError` naming the likely causes (measurements in
    millimetres, a wrong tool frame, joint values in another order or in degrees), unless
    ``allow_large=True``."""
    allow_large = _validate.flag(allow_large, "allow_large")
    pset, problem = _problem(robot, q, measurements, parameters, layer)
    start = pset.nominal()
    _, J = problem.evaluate(start)
    ident = identifiability(pset.names, J, problem.sigma, len(problem.Q), pset.same_as_offsets())
    if len(problem.sigma) <= len(ident.kept):  # the rows, not the robot, limit the rank
        raise InvalidParameterError(
            f"{len(problem.sigma)} measured values for at least {len(ident.kept)} "
            "parameters: too few to fit and check them; measure more configurations"
        )
    fit = _lm(problem, pset, start, ident.kept, robust=_validate.flag(robust, "robust"),
              max_iter=_validate.count(max_iter, "max_iter", minimum=1))  # fmt: skip
    values = pset.values(fit.errors)
    if not allow_large:
        _check_plausible(pset, values - pset.values(start))
    from ._identify import OUTLIER

    return Calibration(
        ArmModel(pset, fit.errors), ArmModel(pset, start),
        dict(zip(pset.names, values.tolist(), strict=True)),
        dict(zip(pset.names, fit.std.tolist(), strict=True)),
        ident, fit.before, fit.after,
        np.flatnonzero(fit.after > OUTLIER).tolist() if robust else [],
        fit.iterations, fit.converged,
    )  # fmt: skip
