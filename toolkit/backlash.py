"""Joint backlash (paper 1, eqs. 16-17): the joint-output angle is the command plus an offset.

Paper 1 models the angle at the joint output as

    theta_i = theta'_i + dtheta_i(M_i)                                   (eq. 16)
    dtheta_i(M_i) = delta * (1/2 sign(M_i) + k_H M_i / M_H,i)            (eq. 17)

with theta'_i the angle before the gap (the command the encoder sees), M_i the torque
acting on joint i, M_H,i the joint's nominal torque (eq. 1), delta the backlash [rad]
and k_H a stiffness-like coefficient.

Conventions of this module (see docs/backlash.md):

* **The torque acting on the joint** is the torque the links and the payload exert on
  the joint output, about the joint axis, positive towards increasing theta. For a
  static arm it is minus Pinocchio's generalized gravity ``-g(theta)``; along a
  trajectory it is ``-rnea(theta, dtheta, ddtheta)``. With this sign the offset moves
  the output the way the load pulls it: the arm sags.
* **sign(0) = 0 (a dead zone)**: a joint whose torque is within ``torque_tol`` of zero
  rests in the middle of its gap (no offset). :func:`hysteresis_offsets` gives the other
  choice for trajectories: the joint keeps the side of its last contact.
* The torque depends on the output angles, so :meth:`Backlash.output_angles` solves the
  fixed point ``theta = q_cmd + dtheta(M(theta))``.
"""

from __future__ import annotations

import copy
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

from .chain import SerialChain
from .errors import ConfigurationError, InvalidParameterError, ToolkitError
from .ik import IKResult, parse_mask, parse_target

if TYPE_CHECKING:
    from .robot import Robot

__all__ = [
    "DEFAULT_DELTA",
    "DEFAULT_K_H",
    "Backlash",
    "Calibration",
    "ErrorMap",
    "Figure6",
    "OutputAngles",
    "calibrate",
    "draw_figure6",
    "error_grid",
    "error_map",
    "figure6",
    "hysteresis_offsets",
    "offset",
]

DEFAULT_DELTA = 0.035
"""Backlash of the Katana's Maxon gearheads at no load [rad] (paper 1)."""
DEFAULT_K_H = 0.2
"""A mid-range stiffness coefficient (paper 1 gives 0.05 ... 0.4)."""
_BATCH_MIN = 32  # below this many configurations, single Pinocchio calls are faster
TORQUE_TOL = 1e-9
"""Torques with |M| <= this [N m] count as zero: the dead zone of sign(0)."""


def _as_float_array(value: object, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{what} must be numeric, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{what} has NaN or infinite entries")
    return arr


def offset(
    torque: object,
    nominal_torque: object,
    delta: object = DEFAULT_DELTA,
    k_h: object = DEFAULT_K_H,
    *,
    torque_tol: float = TORQUE_TOL,
) -> np.ndarray:
    """Backlash offset dtheta = delta (sign(M)/2 + k_H M / M_H) [rad] (paper 1, eq. 17).

    Elementwise and broadcasting: ``torque`` may be (n,) or (N, n) against per-joint
    ``nominal_torque``, ``delta`` and ``k_h`` (scalars or (n,)). ``|M| <= torque_tol``
    counts as zero torque: no offset (the dead-zone reading of sign(0)).
    """
    m = _as_float_array(torque, "torque")
    m_h, d, k = _law_parameters(nominal_torque, delta, k_h)
    return _eq17(m, m_h, d, k, torque_tol)


def _law_parameters(nominal_torque: object, delta: object, k_h: object):
    """Checked (M_H, delta, k_H) arrays of eq. 17."""
    m_h = _as_float_array(nominal_torque, "nominal_torque")
    d = _as_float_array(delta, "delta")
    k = _as_float_array(k_h, "k_h")
    if np.any(m_h <= 0):
        raise InvalidParameterError("nominal_torque must be > 0")
    if np.any(d < 0):
        raise InvalidParameterError("delta must be >= 0")
    return m_h, d, k


def _eq17(m: np.ndarray, m_h, d, k, torque_tol: float = TORQUE_TOL) -> np.ndarray:
    """Eq. 17 on checked arrays; |M| <= torque_tol gives no offset (the dead zone)."""
    return np.where(np.abs(m) > torque_tol, d * (0.5 * np.sign(m) + k * m / m_h), 0.0)


def hysteresis_offsets(
    torques: object,
    nominal_torque: object,
    delta: object = DEFAULT_DELTA,
    k_h: object = DEFAULT_K_H,
    *,
    band: float = TORQUE_TOL,
    initial_side: object = 0.0,
) -> np.ndarray:
    """Offsets along a trajectory where a joint keeps the side of its last contact.

    ``torques`` has shape (T, n) (one row per time step). While ``|M_i| <= band`` the
    joint stays on the side it last touched (``initial_side``: -1, 0 or +1 per joint
    before the first contact, 0 meaning the middle of the gap), and the torque-dependent
    term of eq. 17 still applies. Returns offsets of shape (T, n).
    """
    m = _as_float_array(torques, "torques")
    if m.ndim != 2:
        raise InvalidParameterError(f"torques must have shape (T, n), got {m.shape}")
    m_h, d, k = _law_parameters(nominal_torque, delta, k_h)
    side = np.broadcast_to(_as_float_array(initial_side, "initial_side"), m.shape[1:]).copy()
    out = np.empty_like(m)
    for t, row in enumerate(m):
        touching = np.abs(row) > band
        side = np.where(touching, np.sign(row), side)
        out[t] = d * (0.5 * side + k * row / m_h)
    return out


class OutputAngles(NamedTuple):
    """The solved fixed point theta = q_cmd + dtheta(M(theta)) of one or N commands."""

    theta: np.ndarray  # joint-output angles, (n,) or (N, n)
    torque: np.ndarray  # torque acting on each joint at theta [N m]
    residual: np.ndarray | float  # max |theta - q_cmd - dtheta(M(theta))| [rad]
    iterations: int  # the most iterations any configuration needed
    converged: np.ndarray | bool
    in_gap: np.ndarray  # joints resting inside their gap (torque zero there), bool


class Backlash:
    """The joint-offset layer of paper 1 on any :class:`~toolkit.robot.Robot`.

    Args:
        robot: the robot whose joints have backlash.
        delta: backlash [rad], scalar or one per joint (default 0.035, paper 1).
        k_h: stiffness-like coefficient, scalar or per joint (paper 1: 0.05 ... 0.4).
        nominal_torque: M_H per joint [N m]; defaults to
            :func:`toolkit.katana.nominal_torques` for the Katana models, required otherwise.
        payload: point mass [kg] at the robot's tip frame.
    """

    def __init__(
        self,
        robot: Robot,
        delta: float | Sequence[float] = DEFAULT_DELTA,
        k_h: float | Sequence[float] = DEFAULT_K_H,
        nominal_torque: Sequence[float] | np.ndarray | None = None,
        payload: float = 0.0,
    ) -> None:
        self.robot = robot
        n = robot.nq
        self.delta = self._per_joint(delta, "delta", n, lower=0.0)
        self.k_h = self._per_joint(k_h, "k_h", n, lower=0.0)
        if nominal_torque is None:
            if not robot.name.startswith("katana_"):
                raise InvalidParameterError(
                    f"{robot.name}: give nominal_torque (one M_H per joint, N m); only the "
                    "Katana models have default nominal torques (paper 1, eq. 1)"
                )
            from .katana import nominal_torques

            nominal_torque = nominal_torques()[:n]
        self.nominal_torque = self._per_joint(nominal_torque, "nominal_torque", n, lower=None)
        if np.any(self.nominal_torque <= 0):
            raise InvalidParameterError("nominal_torque must be > 0 for every joint")
        payload_arr = _as_float_array(payload, "payload")
        if payload_arr.shape != () or payload_arr < 0:
            raise InvalidParameterError(f"payload must be a mass >= 0 [kg], got {payload!r}")
        self.payload = float(payload_arr)
        self.model = self._model_with_payload(robot, self.payload)
        self.data = self.model.createData()
        try:
            self.chain: SerialChain | None = SerialChain(self.model, robot.frame_id(None))
        except ToolkitError:
            self.chain = None  # not a plain serial chain: batches loop over Pinocchio

    @staticmethod
    def _per_joint(value: object, what: str, n: int, lower: float | None) -> np.ndarray:
        arr = _as_float_array(value, what)
        if arr.ndim == 0:
            arr = np.full(n, float(arr))
        if arr.shape != (n,):
            raise InvalidParameterError(f"{what} must be a scalar or have shape ({n},)")
        if lower is not None and np.any(arr < lower):
            raise InvalidParameterError(f"{what} must be >= {lower}, got {arr.tolist()}")
        arr = arr.copy()
        arr.setflags(write=False)
        return arr

    @staticmethod
    def _model_with_payload(robot: Robot, payload: float) -> pin.Model:
        """A copy of the robot's model with a point mass at the tip frame."""
        model = pin.Model(robot.model)
        if payload > 0:
            frame = model.frames[robot.frame_id(None)]
            point = pin.Inertia(payload, np.zeros(3), np.zeros((3, 3)))
            joint = frame.parentJoint
            model.inertias[joint] = model.inertias[joint] + frame.placement.act(point)
        return model

    def with_parameters(self, delta: object, k_h: object) -> Backlash:
        """A copy of this layer with other delta and k_H (same robot, torques and payload)."""
        other = copy.copy(self)
        other.delta = self._per_joint(delta, "delta", self.robot.nq, lower=0.0)
        other.k_h = self._per_joint(k_h, "k_h", self.robot.nq, lower=0.0)
        return other

    def __repr__(self) -> str:
        return (
            f"Backlash({self.robot.name!r}, delta={self.delta.tolist()}, "
            f"k_h={self.k_h.tolist()}, payload={self.payload})"
        )

    # ------------------------------------------------------------------ torques
    def torques(
        self,
        theta: object,
        dtheta: object | None = None,
        ddtheta: object | None = None,
    ) -> np.ndarray:
        """Torque acting on each joint [N m] at the output angles theta.

        Static (no velocities): ``-g(theta)``, the weight of the links and the payload.
        Along a trajectory: ``-rnea(theta, dtheta, ddtheta)``. Accepts (n,) or (N, n).
        """
        q = self.robot.check_q(theta, batch=True)
        if dtheta is None and ddtheta is None:
            out = self._static_torques(np.atleast_2d(q))
            return out if q.ndim == 2 else out[0]
        v = self.robot.check_q(np.zeros_like(q) if dtheta is None else dtheta, batch=True)
        a = self.robot.check_q(np.zeros_like(q) if ddtheta is None else ddtheta, batch=True)
        if v.shape != q.shape or a.shape != q.shape:
            raise ConfigurationError("theta, dtheta and ddtheta must have the same shape")
        rows = zip(np.atleast_2d(q), np.atleast_2d(v), np.atleast_2d(a), strict=True)
        out = np.array([-pin.rnea(self.model, self.data, *r) for r in rows])
        return out if q.ndim == 2 else out[0]

    def offsets(self, torque: object) -> np.ndarray:
        """Eq. 17 with this layer's delta, k_H and nominal torques."""
        return offset(torque, self.nominal_torque, self.delta, self.k_h)

    def _static_torques(self, theta: np.ndarray) -> np.ndarray:
        """torques(theta) for a checked (N, n) array, without re-validating it."""
        if self.chain is not None and len(theta) >= _BATCH_MIN:
            return self.chain.gravity_load(theta)
        return np.array(
            [-pin.computeGeneralizedGravity(self.model, self.data, row) for row in theta]
        )

    def _offsets(self, torque: np.ndarray) -> np.ndarray:
        """offsets(torque) for a checked array, without validating it again."""
        return _eq17(torque, self.nominal_torque, self.delta, self.k_h)

    # ------------------------------------------------------------------ fixed point
    def output_angles(
        self,
        q_cmd: object,
        *,
        tol: float = 1e-12,
        max_iter: int = 100,
        full_output: bool = False,
        start: object | None = None,
    ):
        """Joint-output angles theta solving theta = q_cmd + dtheta(M(theta)) (eqs. 16-17).

        Fixed-point iteration from theta = q_cmd; it converges in a few steps because
        delta k_H |dM/dtheta| / M_H is far below 1. A joint whose torque changes sign
        inside its gap (a pendulum-like load hanging in the middle of the gap) makes the
        plain iteration flip between the two contact sides; such a joint is detected and
        placed where its torque vanishes, inside [q - delta/2, q + delta/2], by bisection
        (``in_gap``). The residual is the fixed-point residual of the joints in contact
        and the bracket width of the joints in their gap.

        Where a joint's load changes sign across its gap the other way (pushing away from
        the middle, like an inverted pendulum), both contact sides are equilibria and the
        output depends on the side the joint came from: the iteration starts from
        ``start`` (default: the command itself) and settles on the side nearest to it.

        Returns theta ((n,) or (N, n)); with ``full_output=True`` an :class:`OutputAngles`.
        """
        q = self.robot.check_q(q_cmd, batch=True)
        single = q.ndim == 1
        q2 = np.atleast_2d(q)
        N = len(q2)
        if start is None:
            theta = q2.copy()
        else:
            theta = np.array(np.broadcast_to(self.robot.check_q(start, batch=True), q2.shape))
        side_prev = np.zeros_like(q2)
        in_gap = np.zeros(q2.shape, dtype=bool)
        lo = q2 - self.delta / 2
        hi = q2 + self.delta / 2
        f_lo = np.full(q2.shape, np.nan)  # torque at lo (> 0) once known
        f_hi = np.full(q2.shape, np.nan)  # torque at hi (<= 0) once known
        kept = np.zeros(q2.shape)  # Illinois: +1 if lo moved last, -1 if hi moved last
        theta_prev = q2.copy()
        torque_prev = np.zeros(q2.shape)
        active = np.arange(N)
        iterations = 0
        for iterations in range(1, max_iter + 1):  # noqa: B007 - reported below
            th, qa = theta[active], q2[active]
            torque = self._static_torques(th)
            side = np.where(np.abs(torque) > TORQUE_TOL, np.sign(torque), 0.0)
            entering = (side * side_prev[active] < 0) & ~in_gap[active]
            if entering.any():
                # the previous iterate lies on the other side: bracket the zero between them
                prev_t, prev_m = theta_prev[active], torque_prev[active]
                pos_prev = entering & (prev_m > 0)  # previous point pulls up: lower end
                lo[active] = np.where(pos_prev, prev_t, np.where(entering, th, lo[active]))
                f_lo[active] = np.where(pos_prev, prev_m, np.where(entering, torque, f_lo[active]))
                hi[active] = np.where(pos_prev, th, np.where(entering, prev_t, hi[active]))
                f_hi[active] = np.where(pos_prev, torque, np.where(entering, prev_m, f_hi[active]))
            gap = in_gap[active] | entering
            side_prev[active] = side
            theta_prev[active], torque_prev[active] = th, torque
            new = qa + self._offsets(torque)
            if gap.any():
                new = np.where(
                    gap, self._gap_step(active, gap, th, torque, lo, hi, f_lo, f_hi, kept), new
                )
                in_gap[active] = gap
            step = np.max(np.abs(new - th), axis=1)
            theta[active] = new
            active = active[step > tol]
            if active.size == 0:
                break
        torque = self._static_torques(theta)
        contact_res = np.abs(theta - q2 - self._offsets(torque))
        slope = np.abs(f_lo - f_hi) / np.maximum(hi - lo, 1e-300)
        gap_res = np.where(np.isfinite(slope) & (slope > 0), np.abs(torque) / slope, hi - lo)
        residual = np.max(np.where(in_gap, gap_res, contact_res), axis=1)
        converged = residual <= max(10 * tol, 1e-10)
        if not full_output:
            return theta[0] if single else theta
        if single:
            return OutputAngles(
                theta[0], torque[0], float(residual[0]), iterations, bool(converged[0]), in_gap[0]
            )
        return OutputAngles(theta, torque, residual, iterations, converged, in_gap)

    @staticmethod
    def _gap_step(active, gap, th, torque, lo, hi, f_lo, f_hi, kept) -> np.ndarray:
        """One Illinois (regula falsi) step towards the zero torque of joints in their gap.

        M > 0 pulls theta up, so a stable equilibrium inside the gap lies above a point
        where M > 0: that point becomes the lower end of the bracket.
        """
        lo_a, hi_a = lo[active], hi[active]
        flo, fhi, kept_a = f_lo[active], f_hi[active], kept[active]
        clipped = np.clip(th, lo_a, hi_a)
        up = gap & (torque > 0)
        down = gap & (torque <= 0)
        # Illinois: halve the stale end's torque when the same end moves twice
        fhi = np.where(up & (kept_a > 0), fhi / 2, fhi)
        flo = np.where(down & (kept_a < 0), flo / 2, flo)
        lo_a = np.where(up, clipped, lo_a)
        flo = np.where(up, torque, flo)
        hi_a = np.where(down, clipped, hi_a)
        fhi = np.where(down, torque, fhi)
        kept_a = np.where(up, 1.0, np.where(down, -1.0, kept_a))
        lo[active], hi[active], f_lo[active], f_hi[active], kept[active] = (
            lo_a,
            hi_a,
            flo,
            fhi,
            kept_a,
        )
        known = np.isfinite(flo) & np.isfinite(fhi) & (flo - fhi > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            secant = (lo_a * (-fhi) + hi_a * flo) / (flo - fhi)
        return np.where(known, secant, (lo_a + hi_a) / 2)

    def fk(self, q_cmd: object, frame: str | None = None) -> np.ndarray:
        """Actual pose (4x4, or (N, 4, 4)) of ``frame`` when the joints are commanded to q_cmd."""
        return self.robot.fk(self.output_angles(q_cmd), frame)

    def tip_positions(self, q_cmd: object) -> np.ndarray:
        """Actual tip positions (N, 3) for commands (N, n): vectorised where the chain allows."""
        return self._tips(np.atleast_2d(self.output_angles(q_cmd)))

    def _tips(self, q: np.ndarray) -> np.ndarray:
        """Tip positions (N, 3) at joint values (N, n): vectorised where the chain allows."""
        if self.chain is not None and len(q) >= _BATCH_MIN:
            return self.chain.tip_positions(q)
        return self.robot.fk(q)[:, :3, 3]

    # ------------------------------------------------------------------ compensation
    def command_for(self, theta: object) -> np.ndarray:
        """The command that makes the joint outputs reach theta: q_cmd = theta - dtheta(M(theta)).

        Exact, because the torque depends on the output angles only.
        """
        t = self.robot.check_q(theta, batch=True)
        return t - self.offsets(self.torques(t))

    def compensate(
        self,
        target: object,
        q0: object | None = None,
        *,
        mask: object | None = None,
        tol: float = 1e-6,
        **ik_options: object,
    ) -> IKResult:
        """The command that puts the actual (backlash-affected) tool on ``target``.

        Solves the IK for the output angles theta, then commands
        q_cmd = theta - dtheta(M(theta)). ``success`` is True only when the command is
        inside the joint limits and the actual pose, recomputed through the fixed point
        (started at the intended outputs, see :meth:`output_angles`), meets ``tol`` on the
        masked axes.
        """
        ik = self.robot.ik(target, q0, mask=mask, tol=tol, **ik_options)
        q_cmd = self.command_for(ik.q)
        R_t, p_t, position_only = parse_target(target)
        w = parse_mask(mask, position_only)
        # the fixed point from the intended outputs: if a joint has two equilibria, the
        # arm reaches the target when it approaches from that side
        actual = self.robot.fk(self.output_angles(q_cmd, start=ik.q))
        dp = (p_t - actual[:3, 3]) * w[:3]
        dr = pin.log3(actual[:3, :3].T @ R_t) * w[3:] if not position_only else np.zeros(3)
        p_err, r_err = float(np.linalg.norm(dp)), float(np.linalg.norm(dr))
        ok = bool(ik.success and p_err <= tol and r_err <= tol and self.robot.within_limits(q_cmd))
        return IKResult(q_cmd, ok, p_err, r_err, ik.iterations, ik.restarts)


# ---------------------------------------------------------------------- calibration
class Calibration(NamedTuple):
    """Estimated backlash parameters with their standard errors."""

    delta: np.ndarray | float  # [rad], per joint when calibrated per joint
    k_h: np.ndarray | float
    delta_stderr: np.ndarray | float
    k_h_stderr: np.ndarray | float
    rms: float  # residual RMS [m] (tip positions) or [rad] (joint angles)
    iterations: int
    converged: bool


def calibrate(
    robot: Robot,
    commands: object,
    measured_tip_positions: object | None = None,
    *,
    measured_angles: object | None = None,
    payload: float = 0.0,
    nominal_torque: Sequence[float] | None = None,
    per_joint: bool = False,
    initial: tuple[float, float] = (0.02, 0.1),
    max_iter: int = 50,
) -> Calibration:
    """Estimate delta and k_H by nonlinear least squares (Levenberg-Marquardt).

    Args:
        robot: the robot model.
        commands: commanded configurations, shape (N, n).
        measured_tip_positions: tool positions [m] from an external tracker, (N, 3).
        measured_angles: joint-output angles [rad] (inclinometers), (N, n); give this
            or ``measured_tip_positions``.
        payload: payload [kg] during the measurements.
        per_joint: estimate one (delta, k_H) pair per joint instead of a shared pair
            (joints whose torque never leaves the dead zone are not identifiable).

    Returns:
        :class:`Calibration` with the estimates, their standard errors (from the
        Gauss-Newton covariance s^2 (J^T J)^-1) and the residual RMS.
    """
    q = robot.check_q(commands, batch=True)
    if q.ndim != 2 or len(q) < 2:
        raise InvalidParameterError("commands must have shape (N, n) with N >= 2")
    if (measured_tip_positions is None) == (measured_angles is None):
        raise InvalidParameterError("give exactly one of measured_tip_positions, measured_angles")
    if measured_angles is not None:
        measured = _as_float_array(measured_angles, "measured_angles")
        want = q.shape
    else:
        measured = _as_float_array(measured_tip_positions, "measured_tip_positions")
        want = (len(q), 3)
    if measured.shape != want:
        raise InvalidParameterError(f"measurements must have shape {want}, got {measured.shape}")
    n = robot.nq
    groups = n if per_joint else 1
    params = np.concatenate([np.full(groups, initial[0]), np.full(groups, initial[1])])

    base = Backlash(robot, nominal_torque=nominal_torque, payload=payload)

    def predict(p: np.ndarray) -> np.ndarray:
        if per_joint:
            layer = base.with_parameters(np.abs(p[:groups]), np.abs(p[groups:]))
        else:
            layer = base.with_parameters(abs(p[0]), abs(p[1]))
        if measured_angles is not None:
            return layer.output_angles(q).ravel()
        return layer.tip_positions(q).ravel()

    target = measured.ravel()
    residual = predict(params) - target
    cost = residual @ residual
    lam = 1e-3
    converged = False
    iterations = 0
    for iterations in range(1, max_iter + 1):  # noqa: B007 - reported below
        J = np.empty((len(residual), len(params)))
        for i in range(len(params)):
            h = 1e-7 * max(1.0, abs(params[i]))
            dp = np.zeros_like(params)
            dp[i] = h
            J[:, i] = (predict(params + dp) - predict(params - dp)) / (2 * h)
        # parameters the data cannot see (a joint whose torque stays in the dead zone,
        # e.g. a vertical axis) are left at their start values
        norms = np.linalg.norm(J, axis=0)
        free = norms > 1e-9 * norms.max()
        Jf = J[:, free]
        JtJ = Jf.T @ Jf
        g = Jf.T @ residual
        improved = False
        while lam < 1e10:
            step = np.zeros_like(params)
            step[free] = np.linalg.solve(JtJ + lam * np.diag(np.diag(JtJ) + 1e-12), -g)
            trial = params + step
            r_new = predict(trial) - target
            c_new = r_new @ r_new
            if c_new < cost:
                improved = True
                rel = (cost - c_new) / max(cost, 1e-300)
                params, residual, cost = trial, r_new, c_new
                lam = max(lam / 10, 1e-12)
                break
            lam *= 10
        if not improved or rel < 1e-12 or np.max(np.abs(step)) < 1e-12:
            converged = True
            break
    dof = max(len(residual) - len(params), 1)
    s2 = cost / dof
    stderr = np.full(len(params), np.inf)  # unidentifiable parameters: infinite error
    try:
        stderr[free] = np.sqrt(np.clip(np.diag(s2 * np.linalg.inv(JtJ)), 0, None))
    except np.linalg.LinAlgError:
        pass
    rms = float(np.sqrt(cost / len(residual)))
    if per_joint:
        return Calibration(
            np.abs(params[:groups]),
            np.abs(params[groups:]),
            stderr[:groups],
            stderr[groups:],
            rms,
            iterations,
            converged,
        )
    return Calibration(
        float(abs(params[0])),
        float(abs(params[1])),
        float(stderr[0]),
        float(stderr[1]),
        rms,
        iterations,
        converged,
    )


# ---------------------------------------------------------------------- error maps
class ErrorMap(NamedTuple):
    """Tip-position error caused by backlash over a set of commanded configurations."""

    q: np.ndarray  # (N, n) commands
    error: np.ndarray  # (N,) |p_actual - p_ideal| [m]
    mean: float
    median: float
    p95: float
    max: float


def _progress(total: int, enabled: bool) -> Callable[[int], None]:
    """A minimal progress bar on stderr (no dependency)."""

    def show(done: int) -> None:
        if enabled:
            width = 30
            filled = int(width * done / max(total, 1))
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
            if done >= total:
                sys.stderr.write("\n")
            sys.stderr.flush()

    return show


def _errors(layer: Backlash, q: np.ndarray, chunk: int, progress: bool) -> np.ndarray:
    show = _progress(len(q), progress)
    out = np.empty(len(q))
    for start in range(0, len(q), chunk):
        part = q[start : start + chunk]
        actual = layer.tip_positions(part)
        ideal = layer._tips(part)
        out[start : start + chunk] = np.linalg.norm(actual - ideal, axis=1)
        show(min(start + chunk, len(q)))
    return out


def _summary(q: np.ndarray, err: np.ndarray) -> ErrorMap:
    return ErrorMap(
        q,
        err,
        float(err.mean()),
        float(np.median(err)),
        float(np.percentile(err, 95)),
        float(err.max()),
    )


def error_map(
    layer: Backlash,
    n: int = 10_000,
    *,
    seed: int | None = 0,
    chunk: int = 20_000,
    progress: bool = False,
) -> ErrorMap:
    """Tip-position error from backlash at ``n`` random commands within the limits."""
    if int(n) < 1:
        raise InvalidParameterError("n must be >= 1")
    q = layer.robot.random_q(int(n), seed=seed)
    return _summary(q, _errors(layer, q, chunk, progress))


def error_grid(
    layer: Backlash,
    joints: tuple[int, int] = (1, 2),
    steps: int = 41,
    base: object | None = None,
    *,
    progress: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Error over a grid of two joints (0-based indices) across their ranges.

    Returns (values of joint a (steps,), values of joint b (steps,), error (steps, steps)
    [m]) with the other joints at ``base`` (default: zero, clipped to the limits).
    """
    robot = layer.robot
    i, j = joints
    if not (0 <= i < robot.nq and 0 <= j < robot.nq and i != j):
        raise InvalidParameterError(f"joints must be two different indices in 0..{robot.nq - 1}")
    q0 = np.clip(np.zeros(robot.nq), robot.lower, robot.upper) if base is None else base
    q0 = robot.check_q(q0)
    a = np.linspace(robot.lower[i], robot.upper[i], steps)
    b = np.linspace(robot.lower[j], robot.upper[j], steps)
    A, B = np.meshgrid(a, b, indexing="ij")
    q = np.repeat(q0[None, :], steps * steps, axis=0)
    q[:, i], q[:, j] = A.ravel(), B.ravel()
    err = _errors(layer, q, 20_000, progress)
    return a, b, err.reshape(steps, steps)


# ---------------------------------------------------------------------- paper 1, Fig. 6
class Figure6(NamedTuple):
    """Tool paths of Fig. 6: A -> B (horizontal, case 19) and A -> B' (vertical, case 20)."""

    ideal_b: np.ndarray  # (S, 3) tool positions without backlash [m]
    actual_b: np.ndarray  # (S, 3) with backlash
    ideal_b2: np.ndarray
    actual_b2: np.ndarray
    max_deviation_b: float  # [m]
    max_deviation_b2: float


def figure6(
    delta: float = DEFAULT_DELTA,
    k_h: float = DEFAULT_K_H,
    payload: float = 0.5,
    steps: int = 101,
) -> Figure6:
    """Data of paper 1's Fig. 6 for the Katana 6M180 (joint-space straight-line moves)."""
    from .loaders import load

    robot = load("katana_6m180")
    layer = Backlash(robot, delta=delta, k_h=k_h, payload=payload)
    s = np.linspace(0.0, 1.0, steps)[:, None]
    q_b = np.array([0.0, 0.0, 0.0, -np.pi / 2, 0.0])
    q_b2 = np.array([0.0, np.pi / 2, 0.0, -np.pi / 2, 0.0])
    out = []
    for goal in (q_b, q_b2):
        path = s * goal
        out.append(robot.fk(path)[:, :3, 3])
        out.append(layer.fk(path)[:, :3, 3])
    dev_b = float(np.max(np.linalg.norm(out[0] - out[1], axis=1)))
    dev_b2 = float(np.max(np.linalg.norm(out[2] - out[3], axis=1)))
    return Figure6(*out, dev_b, dev_b2)


def draw_figure6(data: Figure6 | None = None, ax=None):
    """Draw Fig. 6 (x-z plane of the base, mm) with matplotlib; returns the axes."""
    import matplotlib.pyplot as plt

    data = figure6() if data is None else data
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    mm = 1000.0
    for ideal, actual, label in (
        (data.ideal_b, data.actual_b, "A -> B (horizontal)"),
        (data.ideal_b2, data.actual_b2, "A -> B' (vertical)"),
    ):
        (line,) = ax.plot(ideal[:, 0] * mm, ideal[:, 2] * mm, "--", label=f"{label}, no backlash")
        ax.plot(
            actual[:, 0] * mm,
            actual[:, 2] * mm,
            "-",
            color=line.get_color(),
            label=f"{label}, backlash",
        )
    ax.plot([data.ideal_b[0, 0] * mm], [data.ideal_b[0, 2] * mm], "ko")
    ax.annotate(
        "A",
        (data.ideal_b[0, 0] * mm, data.ideal_b[0, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.annotate(
        "B",
        (data.ideal_b[-1, 0] * mm, data.ideal_b[-1, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.annotate(
        "B'",
        (data.ideal_b2[-1, 0] * mm, data.ideal_b2[-1, 2] * mm),
        xytext=(5, 5),
        textcoords="offset points",
    )
    ax.set_xlabel("x, base frame [mm]")
    ax.set_ylabel("z, base frame [mm]")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        "Katana 6M180 tool path (paper 1, Fig. 6): max deviation "
        f"{data.max_deviation_b * mm:.1f} mm (B), {data.max_deviation_b2 * mm:.1f} mm (B')",
        fontsize=9,
    )
    return ax
