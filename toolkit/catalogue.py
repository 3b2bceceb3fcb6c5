"""The model catalogue: which xacro template and fixed arguments make each named model.

A :class:`ModelSpec` says how to render one catalogue model: its template in
``urdf/``, the arguments the model fixes (the Katana's ``variant``), the
arguments that must be positive, the lower/upper limit pairs, the tool frame,
and an optional geometry check run on the resolved arguments before rendering.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from .errors import UnknownModelError

__all__ = ["MODELS", "STRUCTURES", "ModelSpec", "available_models", "get_spec", "register"]

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


MODELS: dict[str, ModelSpec] = {}


def register(spec: ModelSpec) -> ModelSpec:
    """Add a model to the catalogue (its name must be new)."""
    if spec.name in MODELS:
        raise ValueError(f"model {spec.name!r} is already registered")
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


# --------------------------------------------------------------------------- Katana 6M
_KATANA_LIMITS = tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 7))
_KATANA_POSITIVE = frozenset(
    {"base_height", "a2", "a3", "a4", "a5"}
    | {f"m_link{i}" for i in range(1, 6)}
    | {"m_base", "m_gripper"}
)
for _variant, _dof, _what in (
    ("6m180", 5, "gripper coaxial with link 5"),
    ("6m90a", 6, "angled gripper, alpha6 = -90 deg"),
    ("6m90b", 6, "angled gripper, alpha6 = +90 deg"),
):
    register(
        ModelSpec(
            name=f"katana_{_variant}",
            template="katana.urdf.xacro",
            description=f"Katana {_variant.upper()} ({_dof} DOF, {_what}; paper 1)",
            fixed={"variant": _variant},
            hidden=frozenset({"j6_lower", "j6_upper"}) if _dof == 5 else frozenset(),
            positive=_KATANA_POSITIVE,
            limit_pairs=_KATANA_LIMITS[:_dof],
        )
    )

# --------------------------------------------------------------------------- paper 2
register(
    ModelSpec(
        name="arm5dof",
        template="arm5dof.urdf.xacro",
        description="5-DOF arm of paper 2 (geometric IK; lengths 3/50/25/5 read as cm)",
        positive=frozenset(
            {"upper_arm", "forearm", "m_base", "m_link1", "m_upper_arm", "m_forearm"}
            | {"m_wrist", "m_gripper", "base_offset", "gripper"}
        ),
        limit_pairs=tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 6)),
    )
)

# --------------------------------------------------------------------------- paper 3
STRUCTURES = ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic")
for _name, _pairs in zip(STRUCTURES, ("PPP", "RPP", "RRP", "RRP", "RRR"), strict=True):
    register(
        ModelSpec(
            name=_name,
            template=f"{_name}.urdf.xacro",
            description=f"{_name} 3-DOF positioning structure ({_pairs}; paper 3)",
            positive=frozenset({"a", "b", "c", "d", "m1", "m2", "m3", "m4"}),
            limit_pairs=tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 4)),
            tip="link4",
        )
    )


# --------------------------------------------------------------------------- paper 4
def _check_bending(values: Mapping[str, float]) -> None:
    from .errors import GeometryError

    if values["d"] >= 2 * values["R"]:
        raise GeometryError(
            f"bending: the hole circle must fit on the sphere, d < 2R "
            f"(got d={values['d']}, R={values['R']})"
        )
    if values["alpha_fraction"] > 1:
        raise GeometryError("bending: alpha_fraction must be in (0, 1]")
    if values["links"] > 8:
        raise GeometryError("bending: at most 8 links")


register(
    ModelSpec(
        name="bending",
        template="bending.urdf.xacro",
        description="cable-driven bending manipulator, n rolling elements per link (paper 4)",
        positive=frozenset({"R", "d", "h0", "m_element", "alpha_fraction"}),
        nonnegative=frozenset({"L_t"}),
        integers=frozenset({"n", "links"}),
        tip="tool",
        mimic=True,
        check=_check_bending,
    )
)
