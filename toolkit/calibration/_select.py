"""Pose selection for calibration (see :mod:`toolkit.calibration`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..robot import Robot
from ._arm import DEFAULT, ArmModel
from ._identify import as_matrix, greedy_d_optimal, identifiability, scaled
from ._jacobian import Problem
from ._measure import Measurements
from ._model import ParameterSet

__all__ = ["GAP_MARGIN", "clear_of_the_gap", "select_poses"]


@renames.renamed(link="frame")
def select_poses(
    robot: Robot,
    n: int,
    *,
    candidates: ArrayLike | None = None,
    parameters: object = DEFAULT,
    kind: str = "positions",
    frame: str | None = None,
    scene: Any = None,
    collision_free: bool | None = None,
    layer: Any = None,
    seed: int = 0,
) -> np.ndarray:
    """n configurations (n, nq) from ``candidates`` (default: 2,000 random ones within the
    limits) that make the ``parameters`` most observable from ``kind`` measurements
    ("positions", "poses", "gravity" in ``frame``): greedy D-optimal on the scaled
    identification Jacobian of the identifiable parameters. Candidates in collision
    (with the robot itself and ``scene``) are left out when ``collision_free`` (default:
    when the robot has a description file); with a joint-offset ``layer``, so are those
    where a loaded joint's torque is within 2 % of its nominal torque of zero."""
    n = _validate.count(n, "n", minimum=1)
    if candidates is None:
        candidates = robot.random_q(2000, seed=_validate.count(seed, "seed", minimum=0))
    Q = as_matrix(candidates, robot, "candidates")
    if collision_free is None:
        collision_free = robot.urdf_path is not None
    if _validate.flag(collision_free, "collision_free"):
        Q = Q[~np.asarray(robot.in_collision(Q, scene))]
    if layer is not None:
        Q = Q[clear_of_the_gap(layer, Q)]
    if len(Q) < n:
        raise InvalidParameterError(f"{len(Q)} usable candidates for {n} poses")
    if kind not in ("positions", "poses", "gravity"):
        raise InvalidParameterError(f'kind must be "positions", "poses" or "gravity", got {kind!r}')
    if kind == "gravity" and not isinstance(frame, str):
        raise InvalidParameterError('kind="gravity" needs the frame the sensor is on')
    pset = ParameterSet(robot, parameters, layer)
    fake = _fake_measurements(ArmModel(pset, pset.nominal()), Q, kind, frame)
    problem = Problem(pset, Q, fake)
    _, J = problem.evaluate(pset.nominal())
    ident = identifiability(pset.names, J, problem.sigma, len(Q), pset.same_as_offsets())
    A, _ = scaled(J[:, list(ident.kept)], problem.sigma)
    rows = 6 if kind == "poses" else 3
    chosen = greedy_d_optimal(A.reshape(len(Q), rows, -1), n)
    return np.asarray(Q[np.sort(chosen)])


GAP_MARGIN = 0.02  # of each joint's nominal torque: closer to zero, the backlash side is unsure


def clear_of_the_gap(layer: Any, Q: np.ndarray) -> np.ndarray:
    """Flags of the candidates whose loaded joints (median |torque| above the margin) all
    carry a torque farther than the margin from zero: near zero the joint may sit on
    either side of its gap, a jump of delta that no smooth fit can follow."""
    M = np.abs(np.atleast_2d(layer.torques(Q)))
    margin = GAP_MARGIN * np.asarray(layer.nominal_torque, dtype=float)
    loaded = np.median(M, axis=0) > margin
    return np.asarray(np.all(M[:, loaded] > margin[loaded], axis=1))


def _fake_measurements(arm: ArmModel, Q: np.ndarray, kind: str, frame: str | None) -> Measurements:
    """Noise-free measurements of the nominal model (their values do not matter to the
    Jacobian, only their kinds and sigmas)."""
    if kind == "poses":
        return Measurements.poses(arm.fk(Q))
    if kind == "gravity":
        return Measurements.gravity(str(frame), arm.gravity(Q, str(frame)))
    return Measurements.positions(arm.positions(Q))
