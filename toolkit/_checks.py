"""Input checks shared by several modules (the messages name the argument)."""

from __future__ import annotations

import numpy as np

from .errors import ConfigurationError, ToolkitError

__all__ = ["vector3"]


def vector3(value: object, what: str, error: type[ToolkitError] = ConfigurationError) -> np.ndarray:
    """``value`` as a float64 array of shape (3,), or ``error`` saying what is wrong."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{what} must be 3 numbers, got {value!r}") from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise error(f"{what} must be 3 finite numbers, got {value!r}")
    return arr
