"""The backlash law of [P1], eqs. 16-17: the joint-output angle is the command plus an offset.

    theta_i = theta'_i + dtheta_i(M_i)                                   (eq. 16)
    dtheta_i(M_i) = delta * (1/2 sign(M_i) + k_H M_i / M_H,i)            (eq. 17)

with theta'_i the angle before the gap (the command the encoder sees), M_i the torque
acting on joint i, M_H,i the joint's nominal torque (eq. 1), delta the backlash [rad]
and k_H a stiffness-like coefficient. ``|M| <= torque_tol`` counts as zero torque: the
joint rests in the middle of its gap (the dead-zone reading of sign(0));
:func:`hysteresis_offsets` gives the other reading for trajectories.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...common import validate as _validate
from ...errors import InvalidParameterError

__all__ = ["DEFAULT_DELTA", "DEFAULT_K_H", "TORQUE_TOL", "hysteresis_offsets", "offset"]

DEFAULT_DELTA = 0.035
"""Backlash of the Katana's Maxon gearheads at no load [rad] ([P1])."""
DEFAULT_K_H = 0.2
"""A mid-range stiffness coefficient ([P1] gives 0.05 ... 0.4)."""
TORQUE_TOL = 1e-9
"""Torques with |M| <= this [N m] count as zero: the dead zone of sign(0)."""


def law_parameters(
    nominal_torque: ArrayLike, delta: ArrayLike, k_h: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Checked (M_H > 0, delta >= 0, k_H) arrays of eq. 17."""
    m_h = _validate.array(nominal_torque, "nominal_torque")
    d = _validate.array(delta, "delta")
    k = _validate.array(k_h, "k_h")
    for arr, what in ((m_h, "nominal_torque"), (d, "delta"), (k, "k_h")):
        if arr.ndim > 1:
            raise InvalidParameterError(
                f"{what} must be a scalar or one per joint, got {arr.shape}"
            )
    if np.any(m_h <= 0):
        raise InvalidParameterError("nominal_torque must be > 0")
    if np.any(d < 0):
        raise InvalidParameterError("delta must be >= 0")
    return m_h, d, k


def eq17(
    m: np.ndarray,
    m_h: np.ndarray,
    d: np.ndarray,
    k: np.ndarray,
    torque_tol: float = TORQUE_TOL,
) -> np.ndarray:
    """Eq. 17 on checked arrays; |M| <= torque_tol gives no offset (the dead zone)."""
    return np.where(np.abs(m) > torque_tol, d * (0.5 * np.sign(m) + k * m / m_h), 0.0)


def offset(
    torque: ArrayLike,
    nominal_torque: ArrayLike,
    delta: ArrayLike = DEFAULT_DELTA,
    k_h: ArrayLike = DEFAULT_K_H,
    *,
    torque_tol: float = TORQUE_TOL,
) -> np.ndarray:
    """Backlash offset dtheta = delta (sign(M)/2 + k_H M / M_H) [rad] ([P1], eq. 17).

    Elementwise and broadcasting: ``torque`` [N m] may be (n,) or (N, n) against per-joint
    ``nominal_torque`` [N m], ``delta`` [rad] and ``k_h`` (scalars or (n,)).
    ``|M| <= torque_tol`` counts as zero torque: no offset.
    """
    m = _validate.array(torque, "torque")
    if m.ndim > 2:
        raise InvalidParameterError(f"torque must have shape (n,) or (N, n), got {m.shape}")
    tol = _validate.number(torque_tol, "torque_tol", lower=0.0)
    params = law_parameters(nominal_torque, delta, k_h)
    try:
        np.broadcast_shapes(m.shape, *(p.shape for p in params))
    except ValueError:
        raise InvalidParameterError(
            f"torque (shape {m.shape}) and the per-joint nominal_torque {params[0].shape}, "
            f"delta {params[1].shape} and k_h {params[2].shape} must agree in the number of "
            "joints"
        ) from None
    return eq17(m, *params, tol)


def hysteresis_offsets(
    torques: ArrayLike,
    nominal_torque: ArrayLike,
    delta: ArrayLike = DEFAULT_DELTA,
    k_h: ArrayLike = DEFAULT_K_H,
    *,
    band: float = TORQUE_TOL,
    initial_side: ArrayLike = 0.0,
) -> np.ndarray:
    """Offsets along a trajectory where a joint keeps the side of its last contact.

    ``torques`` has shape (T, n) (one row per time step). While ``|M_i| <= band`` the
    joint stays on the side it last touched (``initial_side``: -1, 0 or +1 per joint
    before the first contact, 0 meaning the middle of the gap), and the torque-dependent
    term of eq. 17 still applies. Returns offsets of shape (T, n) [rad].
    """
    m = _validate.array(torques, "torques")
    if m.ndim != 2:
        raise InvalidParameterError(f"torques must have shape (T, n), got {m.shape}")
    m_h, d, k = law_parameters(nominal_torque, delta, k_h)
    band = _validate.number(band, "band", lower=0.0)
    side0 = _validate.array(initial_side, "initial_side")
    if side0.ndim > 1 or not np.all(np.isin(side0, (-1.0, 0.0, 1.0))):
        raise InvalidParameterError("initial_side must be -1, 0 or +1 (scalar or per joint)")
    try:
        np.broadcast_shapes(m.shape[1:], m_h.shape, d.shape, k.shape, side0.shape)
    except ValueError:
        raise InvalidParameterError(
            "torques, nominal_torque, delta, k_h and initial_side must agree on the joints"
        ) from None
    side = np.broadcast_to(side0, m.shape[1:]).copy()
    out = np.empty_like(m)
    for t, row in enumerate(m):
        touching = np.abs(row) > band
        side = np.where(touching, np.sign(row), side)
        out[t] = d * (0.5 * side + k * row / m_h)
    return out
