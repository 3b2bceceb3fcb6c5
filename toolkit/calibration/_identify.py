"""Identifiability, pose selection and identification (see :mod:`toolkit.calibration`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InvalidParameterError
from ._jacobian import Problem
from ._model import Errors, OutOfBounds, ParameterSet

__all__ = ["Fit", "Identifiability", "identifiability", "levenberg_marquardt"]

DEPENDENT = 1e-6  # a column whose part outside the kept ones is this small is not identifiable
HUBER = 3.0  # standardised residual norm beyond which a measurement is down-weighted
OUTLIER = 5.0  # ... and beyond which it is reported as an outlier


@dataclass(frozen=True)
class Identifiability:
    """Which parameters the measurements can tell apart.

    ``kept``: indices of the identifiable parameters (in the set's order); ``fixed``:
    {name: the kept parameters it moves the measurements like (empty: it moves nothing)};
    ``singular_values`` of the scaled Jacobian of the kept ones; ``condition`` their
    ratio; ``o1`` Borm and Menq's observability index (the geometric mean of the singular
    values over the square root of the number of configurations); ``d_optimality``
    det(A^T A)^(1/m)."""

    names: tuple[str, ...]
    kept: tuple[int, ...]
    fixed: dict[str, tuple[str, ...]]
    singular_values: np.ndarray
    condition: float
    o1: float
    d_optimality: float

    def __str__(self) -> str:
        lines = [
            f"{len(self.kept)} of {len(self.names)} parameters identifiable; condition number "
            f"{self.condition:.3g}, O1 {self.o1:.3g}, D-optimality {self.d_optimality:.3g}"
        ]
        for name, like in self.fixed.items():
            why = f"moves the measurements like {', '.join(like)}" if like else "moves nothing"
            lines.append(f"  fixed {name}: {why}")
        return "\n".join(lines)


def scaled(J: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """J with rows divided by sigma and unit columns; and the column norms."""
    A = J / sigma[:, None]
    norms = np.linalg.norm(A, axis=0)
    return A / np.where(norms > 0, norms, 1.0), norms


def identifiability(
    names: list[str], J: np.ndarray, sigma: np.ndarray, poses: int,
    same: dict[int, str] | None = None,
) -> Identifiability:  # fmt: skip
    """Ordered Gram-Schmidt on the scaled Jacobian: a parameter is kept unless its column
    lies in the span of those kept before it (the set's order: offsets, geometry, base,
    tool, compliance, backlash). ``same``: {index: name} of parameters that are another
    one by construction (a joint placement's turn about the joint's axis is its offset),
    fixed whatever the numbers say."""
    same = same or {}
    A, norms = scaled(J, sigma)
    norms = np.where(norms > DEPENDENT * max(float(norms.max(initial=0.0)), 1e-300), norms, 0.0)
    basis: list[np.ndarray] = []
    kept: list[int] = []
    fixed: dict[str, tuple[str, ...]] = {}
    for k in range(A.shape[1]):
        if k in same:
            fixed[names[k]] = (same[k],)
            continue
        col = A[:, k]
        rest = col - sum((b @ col) * b for b in basis) if basis else col.copy()
        if norms[k] > 0 and np.linalg.norm(rest) > DEPENDENT:
            basis.append(rest / np.linalg.norm(rest))
            kept.append(k)
            continue
        like: tuple[str, ...] = ()
        if norms[k] > 0 and kept:
            coef = np.linalg.lstsq(A[:, kept], col, rcond=None)[0]
            like = tuple(names[kept[i]] for i in np.flatnonzero(np.abs(coef) > 0.05))
        fixed[names[k]] = like
    s = np.linalg.svd(A[:, kept], compute_uv=False) if kept else np.zeros(0)
    positive = s[s > 0]
    geo = float(np.exp(np.mean(np.log(positive)))) if len(positive) else 0.0
    return Identifiability(
        tuple(names), tuple(kept), fixed, s,
        float(s[0] / s[-1]) if len(s) and s[-1] > 0 else float("inf"),
        geo / np.sqrt(max(poses, 1)), geo**2,
    )  # fmt: skip


@dataclass(frozen=True)
class Fit:
    """The estimate, the standard deviations of the kept parameters (in the set's order;
    NaN for fixed ones), the robust weights per measurement, the standardised residual
    norms before and after, the iterations, and whether it converged."""

    errors: Errors
    std: np.ndarray
    weights: np.ndarray
    before: np.ndarray
    after: np.ndarray
    iterations: int
    converged: bool


def _group_norms(problem: Problem, r: np.ndarray) -> np.ndarray:
    z2 = (r / problem.sigma) ** 2
    return np.sqrt(np.bincount(problem.groups, weights=z2, minlength=problem.count))


def _cost(s: np.ndarray, robust: bool) -> float:
    if not robust:
        return float(0.5 * np.sum(s**2))
    return float(np.sum(np.where(s <= HUBER, 0.5 * s**2, HUBER * s - 0.5 * HUBER**2)))


def _weights(s: np.ndarray, robust: bool) -> np.ndarray:
    if not robust:
        return np.ones_like(s)
    return np.where(s <= HUBER, 1.0, HUBER / np.maximum(s, 1e-300))


# long: one Levenberg-Marquardt loop with its acceptance test and covariance
def levenberg_marquardt(
    problem: Problem, pset: ParameterSet, start: Errors, kept: tuple[int, ...], *,
    robust: bool = True, max_iter: int = 50, tol: float = 1e-9,
) -> Fit:  # fmt: skip
    """Minimise the (Huber) robust cost of the standardised residuals over the kept
    parameters, steps composed on the estimate (iteratively reweighted)."""
    if not kept:
        raise InvalidParameterError("no identifiable parameter: nothing to fit")
    errors, lam = start, 1e-3
    r, J = problem.evaluate(errors)
    before = _group_norms(problem, r)
    cost = _cost(before, robust)
    converged, iterations = False, 0
    cols = list(kept)
    for _ in range(max_iter):
        iterations += 1
        s = _group_norms(problem, r)
        w = np.sqrt(_weights(s, robust))[problem.groups] / problem.sigma
        A, b = J[:, cols] * w[:, None], r * w
        H, g = A.T @ A, A.T @ b
        d = np.diag(H).copy()
        improved = False
        while lam < 1e12:
            step = np.zeros(len(pset.params))
            step[cols] = np.linalg.solve(H + lam * np.diag(np.maximum(d, 1e-30)), g)
            try:
                trial = pset.update(errors, step)
            except OutOfBounds:
                lam *= 4
                continue
            r_trial = problem.residuals(trial)
            c_trial = _cost(_group_norms(problem, r_trial), robust)
            if c_trial <= cost:
                small = cost - c_trial <= tol * max(cost, 1e-300)
                errors, cost, lam, improved = trial, c_trial, max(lam / 5, 1e-9), True
                break
            lam *= 4
        if not improved:
            converged = True  # no step lowers the cost: a minimum (to rounding)
            break
        r, J = problem.evaluate(errors)
        if small or np.linalg.norm(step[cols] * np.sqrt(np.maximum(d, 0))) < 1e-4:
            converged = True
            break
    after = _group_norms(problem, r)
    weights = _weights(after, robust)
    w = np.sqrt(weights)[problem.groups] / problem.sigma
    A = J[:, cols] * w[:, None]
    dof = max(len(r) - len(cols), 1)
    factor = max(float(np.sum((r * w) ** 2)) / dof, 1e-300)
    std = np.full(len(pset.params), np.nan)
    std[cols] = np.sqrt(np.diag(np.linalg.pinv(A.T @ A)) * factor)
    return Fit(errors, std, weights, before, after, iterations, converged)


def greedy_d_optimal(blocks: np.ndarray, n: int) -> list[int]:
    """Pick n of the candidates' Jacobian blocks (C, rows, m) that maximise det(A^T A),
    one at a time (each step the candidate adding the most information)."""
    C, _, m = blocks.shape
    info = 1e-9 * np.eye(m)
    chosen: list[int] = []
    free = np.ones(C, dtype=bool)
    for _ in range(n):
        inv = np.linalg.inv(info)
        S = np.einsum("cim,mn,cjn->cij", blocks, inv, blocks)
        gain = np.linalg.slogdet(np.eye(blocks.shape[1])[None] + S)[1]
        gain[~free] = -np.inf
        k = int(np.argmax(gain))
        chosen.append(k)
        free[k] = False
        info = info + blocks[k].T @ blocks[k]
    return chosen


def as_matrix(value: Any, robot: Any, what: str) -> np.ndarray:
    """Joint values (N, nq), checked."""
    q = robot.joints.check(value, batch=True)
    if q.ndim != 2:
        raise InvalidParameterError(f"{what} must have shape (N, {robot.nq})")
    return np.asarray(q, dtype=float)
