"""The five catalogue models of [P3] and what every function of this package asks of one:
its structure (the ``structure`` fact, never its name), dimensions and point M."""

from __future__ import annotations

import numpy as np

from ...common import validate as _validate
from ...descriptions import ModelSpec, register
from ...errors import UnknownModelError
from ...robot import Robot, as_robot

__all__ = ["STRUCTURES", "default_rho", "dimensions", "point_m", "structure_of"]

STRUCTURES = ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic")
"""The five structures of [P3], in its order (Cartesian PPP ... anthropomorphic RRR)."""
for _name, _pairs in zip(STRUCTURES, ("PPP", "RPP", "RRP", "RRP", "RRR"), strict=True):
    register(
        ModelSpec(
            name=_name,
            template=f"{_name}.urdf.xacro",
            description=f"{_name} 3-DOF positioning structure ({_pairs}; [P3])",
            positive=frozenset({"a", "b", "c", "d", "m1", "m2", "m3", "m4"}),
            limit_pairs=tuple((f"j{i}_lower", f"j{i}_upper") for i in range(1, 4)),
            tip="link4",
            facts={"structure": _name},
        )
    )


def default_rho(robot: Robot) -> np.ndarray:
    """Coordinates of the model's ``point_m`` frame in the end link (frame 4)."""
    fid = as_robot(robot).frames.id("point_m")
    return np.array(robot.model.frames[fid].placement.translation)


def structure_of(robot: Robot) -> str:
    """The structure a [P3] model carries in its facts (not inferred from its name)."""
    kind = robot.facts.get("structure") if isinstance(robot, Robot) else None
    if not isinstance(kind, str):
        raise UnknownModelError(
            getattr(robot, "name", repr(robot)), STRUCTURES, what="[P3] structure"
        )
    return kind


def dimensions(robot: Robot) -> tuple[str, float, float, float]:
    name = structure_of(robot)
    p = robot.params
    return name, float(p["a"]), float(p["b"]), float(p["c"])


def point_m(robot: Robot, rho: object | None) -> np.ndarray:
    """rho as given, else the model's point M ([P3] models) or the tip's origin."""
    as_robot(robot)
    if rho is not None:
        return _validate.vector3(rho, "rho")
    return default_rho(robot) if "point_m" in list(robot.frames) else np.zeros(3)
