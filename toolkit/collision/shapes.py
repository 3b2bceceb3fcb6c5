"""A robot's collision shapes as its description gives them (see :mod:`toolkit.collision`)."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import pinocchio as pin

from ..common import caller_level
from ..descriptions import PackageResolver, read_description
from ..errors import ModelLoadError
from .scene import CollisionGeometryWarning

if TYPE_CHECKING:
    from .checker import CollisionSubject

__all__ = ["robot_geometry"]


def robot_geometry(robot: CollisionSubject) -> tuple[pin.GeometryModel, bool]:
    """The robot's collision shapes (its visual ones, with a warning, when it has none),
    and whether they are the visual stand-ins."""
    if robot.urdf_path is None:
        raise ModelLoadError(f"{robot.name}: no URDF file, so no collision shapes")
    text = read_description(robot.urdf_path)
    text = PackageResolver(None, robot.urdf_path).absolute_uris(text)
    for kind in (pin.GeometryType.COLLISION, pin.GeometryType.VISUAL):
        try:
            geom = pin.buildGeomFromUrdfString(robot.model, text, kind)
        except (ValueError, RuntimeError) as exc:
            raise ModelLoadError(f"{robot.name}: cannot load its shapes: {exc}") from exc
        if geom.ngeoms:
            visual = kind == pin.GeometryType.VISUAL
            if visual:
                warnings.warn(
                    f"{robot.name}: the description has no <collision> shapes; its visual "
                    "shapes stand in for them (pairs that touch at the neutral "
                    "configuration are not checked)",
                    CollisionGeometryWarning,
                    stacklevel=caller_level(),
                )
            return geom, visual
    return geom, False
