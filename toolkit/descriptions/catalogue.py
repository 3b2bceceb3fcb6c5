"""The model catalogue: which xacro template and fixed arguments make each named model.

A :class:`ModelSpec` says how to render one catalogue model: its template in
``urdf/``, the arguments the model fixes (the Katana's ``variant``), the
arguments that must be positive, the lower/upper limit pairs, the tool frame,
an optional geometry check run on the resolved arguments before rendering, and the
model's facts. The paper modules (``toolkit.papers``) register their models here; this
module knows nothing about any of them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ..errors import InvalidParameterError, UnknownModelError

__all__ = ["MODELS", "ModelSpec", "available_models", "get_spec", "register"]

GeometryCheck = Callable[[Mapping[str, float]], None]


@dataclass(frozen=True)
class ModelSpec:
    """How to render one catalogue model from its xacro template.

    Attributes:
        name: catalogue name, e.g. ``"katana_6m180"``.
        template: file name of the xacro template in ``urdf/``.
        description: one line for ``toolkit list``.
        fixed: arguments this model fixes; users cannot override them.
        hidden: template arguments that do not apply to this model (unknown to users).
        positive: arguments that must be strictly positive (lengths, masses).
        nonnegative: arguments that must be >= 0.
        integers: arguments that must be whole numbers >= 1.
        limit_pairs: (lower, upper) argument pairs with lower < upper required.
        tip: name of the tool frame.
        mimic: parse ``<mimic>`` joints (Pinocchio >= 3.8).
        check: extra geometry check on the resolved numeric arguments.
        facts: per-model facts handed to the loaded :class:`~toolkit.robot.Robot` as
            ``robot.facts`` (e.g. ``nominal_torque``, ``structure``), so that code never
            infers them from the model's name.
    """

    name: str
    template: str
    description: str
    fixed: Mapping[str, str] = field(default_factory=dict)
    hidden: frozenset[str] = frozenset()
    positive: frozenset[str] = frozenset()
    nonnegative: frozenset[str] = frozenset()
    integers: frozenset[str] = frozenset()
    limit_pairs: tuple[tuple[str, str], ...] = ()
    tip: str = "tool"
    mimic: bool = False
    check: GeometryCheck | None = None
    facts: Mapping[str, object] = field(default_factory=dict)


MODELS: dict[str, ModelSpec] = {}


def register(spec: ModelSpec) -> ModelSpec:
    """Add a model to the catalogue (its name must be new)."""
    if not isinstance(spec, ModelSpec):
        raise InvalidParameterError(f"spec must be a ModelSpec, got {spec!r:.100}")
    if spec.name in MODELS:
        raise InvalidParameterError(f"model {spec.name!r} is already registered")
    MODELS[spec.name] = spec
    return spec


def available_models() -> list[str]:
    """Names of every catalogue model, sorted."""
    return sorted(MODELS)


def get_spec(name: str) -> ModelSpec:
    """The spec of a catalogue model; :class:`UnknownModelError` lists the valid names."""
    try:
        return MODELS[name]
    except (KeyError, TypeError):
        raise UnknownModelError(str(name), MODELS) from None
