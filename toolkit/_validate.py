"""The toolkit's one family of input checks: every public function validates through these.

Each check returns the value in a canonical form (float, int, float64 array) or raises
a :class:`~toolkit.errors.ToolkitError` subclass whose message names the argument,
the value received and what is allowed. ``error`` selects the subclass where the
caller's domain calls for another one (a joint vector is a ``ConfigurationError``,
impossible geometry a ``GeometryError``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from .errors import ConfigurationError, InvalidParameterError, ToolkitError

__all__ = ["array", "count", "number", "one_of", "per_joint", "vector3"]

ErrorType = type[ToolkitError]


def number(
    value: object,
    what: str,
    *,
    lower: float | None = None,
    upper: float | None = None,
    strict: bool = False,
    error: ErrorType = InvalidParameterError,
) -> float:
    """A finite real number within [lower, upper] (open at ``lower`` with ``strict``)."""
    if isinstance(value, bool) or isinstance(value, str):
        raise error(f"{what} must be a number, got {value!r}")
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise error(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise error(f"{what} must be finite, got {value!r}")
    if lower is not None and (x <= lower if strict else x < lower):
        raise error(f"{what} must be {'>' if strict else '>='} {lower}, got {value!r}")
    if upper is not None and x > upper:
        raise error(f"{what} must be <= {upper}, got {value!r}")
    return x


def count(
    value: object, what: str, *, minimum: int = 1, error: ErrorType = InvalidParameterError
) -> int:
    """A whole number >= ``minimum`` (bools and non-integral floats are refused)."""
    if not isinstance(value, int | np.integer) or isinstance(value, bool) or value < minimum:
        raise error(f"{what} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def array(
    value: object,
    what: str,
    *,
    shape: tuple[int, ...] | None = None,
    error: ErrorType = InvalidParameterError,
) -> np.ndarray:
    """``value`` as a finite float64 array (of ``shape`` when given; -1 matches any size)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{what} must be numeric, got {value!r}") from None
    if shape is not None and (
        arr.ndim != len(shape)
        or any(s not in (-1, a) for s, a in zip(shape, arr.shape, strict=False))
    ):
        dims = ", ".join("N" if s == -1 else str(s) for s in shape)
        want = f"({dims},)" if len(shape) == 1 else f"({dims})"
        raise error(f"{what} must have shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise error(f"{what} has NaN or infinite entries")
    return arr


def vector3(value: object, what: str, error: ErrorType = ConfigurationError) -> np.ndarray:
    """``value`` as a float64 array of shape (3,), or ``error`` saying what is wrong."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{what} must be 3 numbers, got {value!r}") from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise error(f"{what} must be 3 finite numbers, got {value!r}")
    return arr


def per_joint(value: object, what: str, n: int, *, lower: float | None = None) -> np.ndarray:
    """A scalar or an (n,) array as a read-only (n,) float64 array, each >= ``lower``."""
    arr = array(value, what)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise InvalidParameterError(f"{what} must be a scalar or have shape ({n},)")
    if lower is not None and np.any(arr < lower):
        raise InvalidParameterError(f"{what} must be >= {lower}, got {arr.tolist()}")
    arr = arr.copy()
    arr.setflags(write=False)
    return arr


def one_of(value: object, what: str, valid: Iterable[str]) -> str:
    """A string among ``valid`` (the message lists them)."""
    options = tuple(valid)
    if not isinstance(value, str) or value not in options:
        raise InvalidParameterError(f"unknown {what} {value!r}; valid: {', '.join(options)}")
    return value
