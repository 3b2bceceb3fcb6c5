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

from ..errors import ConfigurationError, InvalidParameterError, ToolkitError

__all__ = [
    "array",
    "axes",
    "count",
    "flag",
    "number",
    "one_of",
    "per_joint",
    "real_array",
    "vector3",
]

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
    if isinstance(value, bool | np.bool_ | str | bytes | complex | np.complexfloating):
        raise error(f"{what} must be a number (real, not bool or text), got {value!r:.100}")
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise error(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise error(f"{what} must be finite, got {value!r}")
    if lower is not None and (x <= lower if strict else x < lower):
        raise error(f"{what} must be {'>' if strict else '>='} {lower}, got {value!r}")
    if upper is not None and x > upper:
        raise error(f"{what} must be <= {upper}, got {value!r}")
    return x


MAX_COUNT = 10**8
"""The largest count (samples, iterations, ...) accepted unless a routine says otherwise."""


def count(
    value: object,
    what: str,
    *,
    minimum: int = 1,
    maximum: int | None = MAX_COUNT,
    error: ErrorType = InvalidParameterError,
) -> int:
    """A whole number in [minimum, maximum] (bools and non-integral floats are refused)."""
    if not isinstance(value, int | np.integer) or isinstance(value, bool) or value < minimum:
        raise error(f"{what} must be a whole number >= {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise error(f"{what} must be at most {maximum}, got {value!r}")
    return int(value)


def real_array(value: object, what: str, error: ErrorType = InvalidParameterError) -> np.ndarray:
    """``value`` as a float64 array: real numbers only (no bools, complex, text or objects)."""
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value  # the common case, kept fast (q in a loop)
    try:
        raw = np.asarray(value)
        if raw.dtype.kind in "bcUSV" or isinstance(value, bool):
            raise TypeError
        arr = raw.astype(float)
    except (TypeError, ValueError, OverflowError):
        raise error(f"{what} must be numeric (real numbers), got {value!r:.200}") from None
    return arr


def array(
    value: object,
    what: str,
    *,
    shape: tuple[int, ...] | None = None,
    error: ErrorType = InvalidParameterError,
) -> np.ndarray:
    """``value`` as a finite float64 array (of ``shape`` when given; -1 matches any size)."""
    arr = real_array(value, what, error)
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


def flag(value: object, what: str) -> bool:
    """A yes/no option: True or False only (no truthy stand-ins)."""
    if not isinstance(value, bool | np.bool_):
        raise InvalidParameterError(f"{what} must be True or False, got {value!r:.100}")
    return bool(value)


def axes(value: object, what: str = "ax", count: int | None = None) -> object:
    """Matplotlib axes to draw into (``count`` of them in a sequence), or None."""
    if value is None:
        return None
    try:
        items = [value] if count is None else list(value)  # type: ignore[call-overload]
    except TypeError:
        items = []
    ok = (count is None or len(items) == count) and not isinstance(value, str | bytes)
    if not ok or not all(callable(getattr(item, "plot", None)) for item in items):
        n = "matplotlib axes" if count is None else f"{count} matplotlib axes"
        raise InvalidParameterError(f"{what} must be {n} or None, got {value!r:.100}")
    return value


def vector3(value: object, what: str, error: ErrorType = ConfigurationError) -> np.ndarray:
    """``value`` as a float64 array of shape (3,), or ``error`` saying what is wrong."""
    try:
        arr = real_array(value, what, error)
    except ToolkitError:
        raise error(f"{what} must be 3 numbers, got {value!r:.100}") from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise error(f"{what} must be 3 finite numbers, got {value!r}")
    return arr


def pose(value: object, what: str, shapes: str = "a finite 4x4 pose") -> np.ndarray:
    """``value`` as a 4x4 float64 homogeneous transform: finite, its 3x3 block a rotation
    (orthonormal to 1e-6, determinant +1), its last row (0, 0, 0, 1); ``shapes`` names
    what is accepted in the message of a wrong shape."""
    arr = real_array(value, what)
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{what} must be {shapes}")
    R = arr[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise InvalidParameterError(f"{what}: its 3x3 block is not a rotation matrix")
    if np.abs(arr[3] - [0, 0, 0, 1]).max() > 1e-12:
        raise InvalidParameterError(f"{what}: the last row must be (0, 0, 0, 1)")
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
