"""The toolkit's exceptions: one base class, one subclass per kind of problem.

Every message names the problem and, for an unknown name, lists the valid ones.
The subclasses also derive from the matching built-in (``ValueError`` or
``LookupError``), so ``except ValueError`` keeps working for callers that do not
know the toolkit.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

__all__ = [
    "CacheError",
    "CollisionWarning",
    "ConfigurationError",
    "ConvergenceError",
    "FrameNotFoundError",
    "GeometryError",
    "InertiaWarning",
    "InstallationError",
    "InvalidParameterError",
    "MapStoreError",
    "ModelLoadError",
    "RenderError",
    "ToolkitError",
    "UnknownModelError",
    "UnreachableTargetsWarning",
    "UnsupportedModelError",
]


def _rebuilt(cls: type[ToolkitError], args: tuple[Any, ...], state: dict[str, Any]) -> Any:
    """An error as it was pickled: its arguments and attributes, without its constructor."""
    error = cls.__new__(cls)
    error.args = args
    error.__dict__.update(state)
    return error


class ToolkitError(Exception):
    """Base class of every error the toolkit raises on purpose (never raised itself).

    Every one pickles with its message and attributes, whatever its constructor takes, so
    it crosses a process boundary intact (a forked worker's error, a Dask task's)."""

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuilt, (type(self), self.args, dict(self.__dict__)))


def _names(valid: Iterable[str], limit: int = 60) -> str:
    names = sorted(valid)
    shown = ", ".join(names[:limit])
    if len(names) > limit:
        shown += f", ... ({len(names) - limit} more)"
    return shown


def _closest(name: object, valid: list[str]) -> str:
    """ ", did you mean 'a' or 'b'?" for the valid names closest to ``name`` (none: "")."""
    import difflib

    close = difflib.get_close_matches(str(name), valid, n=3, cutoff=0.6)
    if not close:
        return ""
    quoted = [repr(c) for c in close]
    head = ", ".join(quoted[:-1]) + " or " if len(quoted) > 1 else ""
    return f" (did you mean {head}{quoted[-1]}?)"


class UnknownModelError(ToolkitError, LookupError):
    """A model name that is not in the catalogue (or not among the example robots)."""

    def __init__(self, name: str, valid: Iterable[str], what: str = "model") -> None:
        self.name = name
        self.valid = sorted(valid)
        super().__init__(
            f"unknown {what} {name!r}{_closest(name, self.valid)}; valid names: "
            f"{_names(self.valid)}"
        )

    def __str__(self) -> str:  # LookupError would otherwise quote the message
        return str(self.args[0])


class FrameNotFoundError(ToolkitError, LookupError):
    """A frame name the model does not have."""

    def __init__(self, name: str, valid: Iterable[str], robot: str = "") -> None:
        self.name = name
        self.valid = sorted(valid)
        where = f" in robot {robot!r}" if robot else ""
        super().__init__(
            f"unknown frame {name!r}{where}{_closest(name, self.valid)}; valid frames: "
            f"{_names(self.valid)}"
        )

    def __str__(self) -> str:
        return str(self.args[0])


class InvalidParameterError(ToolkitError, ValueError):
    """A template argument or function parameter that is unknown, non-finite or out of range."""


class GeometryError(ToolkitError, ValueError):
    """Impossible geometry: for example a hole circle wider than the sphere (d >= 2R)."""


class ConfigurationError(ToolkitError, ValueError):
    """A joint configuration of the wrong shape, or with NaN or infinite entries."""


class RenderError(ToolkitError, RuntimeError):
    """xacro failed to render a template (the message carries xacro's own)."""


class ModelLoadError(ToolkitError, ValueError):
    """A robot description that cannot be read: a missing file, or one Pinocchio rejects."""


class UnsupportedModelError(ToolkitError, ValueError):
    """A model outside what a routine handles (e.g. a joint type the vectorised chain lacks)."""


class InstallationError(ToolkitError, RuntimeError):
    """A file the toolkit ships or depends on is missing: templates, example-robot-data."""


class CacheError(ToolkitError, OSError):
    """No cache folder could take a rendered URDF."""


class MapStoreError(ToolkitError, RuntimeError):
    """A workspace map's store cannot be used: missing zarr, an unreadable store, or a
    store made by another map (robot, grid, orientations, seed or version)."""


class ConvergenceError(ToolkitError, ArithmeticError):
    """An iteration did not converge where the caller needs a converged answer.

    ``residual`` holds the worst residual reached. Routines that can report failure in
    their result (IK, ``Backlash.solve``, calibration) do so instead of raising.
    """

    def __init__(self, message: str, residual: float) -> None:
        super().__init__(message)
        self.residual = residual


class InertiaWarning(UserWarning):
    """A description gives links with shapes no inertia: their dynamics are refused."""


class CollisionWarning(UserWarning):
    """A motion shown or replayed touches the robot itself or the scene (the viewer's
    ``play`` of an unverified path, say): the warning names the time and the pair."""


class UnreachableTargetsWarning(UserWarning):
    """Targets fix more directions than the robot's joints move its frame in (a 5-joint arm
    given full poses): most of them cannot be reached, whatever the solver does."""
