"""The settings of a numeric IK solve, validated once: :class:`IKOptions`."""

from __future__ import annotations

import functools
from dataclasses import dataclass, fields, replace
from typing import Any

from ...common import renames
from ...common import validate as _validate
from ...errors import InvalidParameterError

__all__ = ["MAX_TOL", "IKOptions"]

MAX_TOL = 0.01
"""The largest IK tolerance accepted [m and rad]: no "success" for a larger miss."""


@dataclass(frozen=True, eq=True)
class IKOptions:
    """Settings of a numeric IK solve, validated on construction.

    Attributes:
        tol: tolerance on the position [m] and orientation [rad] errors, in (0, MAX_TOL]
            (a solve is never called a success for a miss larger than 1 cm or 0.01 rad).
        max_iter: iterations per start, >= 1.
        restarts: extra random starts after the first, >= 0.
        seed: seed of the restarts' random generator (same seed, same answer), or None.
        time_limit: wall-clock budget [s] after which no new restart begins, > 0, or
            None (``timeout``, its old name, answers for one release with a
            ``DeprecationWarning``).
    """

    tol: float = 1e-6
    max_iter: int = 100
    restarts: int = 500
    seed: int | None = 0
    time_limit: float | None = None

    def __post_init__(self) -> None:
        tol = _validate.number(self.tol, "tol", lower=0, strict=True, upper=MAX_TOL)
        object.__setattr__(self, "tol", tol)
        object.__setattr__(self, "max_iter", _validate.count(self.max_iter, "max_iter"))
        object.__setattr__(self, "restarts", _validate.count(self.restarts, "restarts", minimum=0))
        if self.seed is not None:
            seed = _validate.count(self.seed, "seed", minimum=0, maximum=2**64 - 1)
            object.__setattr__(self, "seed", seed)
        if self.time_limit is not None:
            limit = _validate.number(self.time_limit, "time_limit [s]", lower=0, strict=True)
            object.__setattr__(self, "time_limit", limit)

    @property
    def timeout(self) -> float | None:
        """The old name of :attr:`time_limit` (one release, with a warning)."""
        renames.warn_renamed("IKOptions", "timeout", "time_limit")
        return self.time_limit

    @classmethod
    def build(cls, options: IKOptions | None = None, **overrides: object) -> IKOptions:
        """``options`` (default: the defaults) with keyword ``overrides`` of its fields.

        Built options are remembered (they are immutable), so a solve in a loop with the
        same keywords does not validate them again; a ``seed`` that changes from call to
        call (``seed=i`` in a loop) is checked on its own."""
        renames.rename_keys("IKOptions", overrides, _RENAMED)
        seed = overrides.pop("seed", _NO_SEED)
        try:  # the types are part of the key: tol=True is refused, tol=1.0 is not
            key = (options, *overrides.items(), *map(type, overrides.values()))
            base = _BUILT.get(key)
        except TypeError:  # an unhashable value: validate it below (and refuse it there)
            key, base = None, None
        if base is None:
            base = cls._build(options, overrides)
            if key is not None:
                if len(_BUILT) > 512:
                    _BUILT.clear()
                _BUILT[key] = base
        if seed is _NO_SEED or (type(seed) is int and seed == base.seed):
            return base
        if type(seed) is int and 0 <= seed < 2**64:  # the common loop: skip re-validation
            with_seed = object.__new__(cls)
            with_seed.__dict__.update(base.__dict__)
            object.__setattr__(with_seed, "seed", seed)
            return with_seed
        return cls._build(base, {"seed": seed})

    @classmethod
    def split(
        cls, options: IKOptions | None, overrides: dict[str, object]
    ) -> tuple[IKOptions, int | None]:
        """:meth:`build`, but a plain int ``seed`` keyword (``seed=i`` in a loop) comes back
        beside the options (None: the options' own seed); it is taken out of ``overrides``."""
        renames.rename_keys("IKOptions", overrides, _RENAMED)
        seed = overrides.get("seed")
        if type(seed) is int and 0 <= seed < 2**64:
            del overrides["seed"]
            return cls.build(options, **overrides), seed
        return cls.build(options, **overrides), None  # None (a fresh stream) included

    @classmethod
    def _build(cls, options: IKOptions | None, overrides: dict[str, object]) -> IKOptions:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(overrides) - known)
        if unknown:
            raise InvalidParameterError(
                f"unknown IK option(s) {unknown}; valid: {', '.join(sorted(known))}"
            )
        base = cls() if options is None else options
        if not isinstance(base, IKOptions):
            raise InvalidParameterError(f"options must be an IKOptions, got {options!r}")
        return replace(base, **overrides) if overrides else base  # type: ignore[arg-type]


_BUILT: dict[tuple[object, ...], IKOptions] = {}
_NO_SEED = object()


_RENAMED = {"timeout": "time_limit"}
"""The options' renamed keywords (old: new)."""


_dataclass_init = IKOptions.__init__


@functools.wraps(_dataclass_init)
def _init(self: IKOptions, *args: Any, **kwargs: Any) -> None:
    renames.rename_keys("IKOptions", kwargs, _RENAMED)
    _dataclass_init(self, *args, **kwargs)


IKOptions.__init__ = _init  # type: ignore[method-assign]
renames.RENAMED.extend(("toolkit.ik.numeric.options.IKOptions", old, new)
                      for old, new in _RENAMED.items())  # fmt: skip
