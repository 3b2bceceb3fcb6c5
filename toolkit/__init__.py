"""Kinematics of robot manipulators on Pinocchio.

Catalogue models (Katana 6M, ...) are rendered from the toolkit's own xacro
templates; any URDF file and the robots of example-robot-data load as well.

>>> import toolkit
>>> robot = toolkit.load("katana_6m180")
>>> robot.fk([0, 0, 0, 0, 0]).round(4)[:3, 3].tolist()
[0.329, 0.0, 0.5043]
"""

from . import arm5dof, backlash, bending, katana, structures
from .catalogue import available_models
from .errors import (
    ConfigurationError,
    FrameNotFoundError,
    GeometryError,
    InvalidParameterError,
    RenderError,
    ToolkitError,
    UnknownModelError,
)
from .ik import IKResult, PathResult
from .loaders import EXAMPLE_ROBOTS, load, load_example, load_urdf
from .render import model_arguments, urdf_path, urdf_text
from .robot import Robot

__version__ = "0.1.0"

__all__ = [
    "EXAMPLE_ROBOTS",
    "ConfigurationError",
    "FrameNotFoundError",
    "GeometryError",
    "IKResult",
    "InvalidParameterError",
    "PathResult",
    "RenderError",
    "Robot",
    "ToolkitError",
    "UnknownModelError",
    "arm5dof",
    "available_models",
    "backlash",
    "bending",
    "katana",
    "load",
    "load_example",
    "load_urdf",
    "model_arguments",
    "structures",
    "urdf_path",
    "urdf_text",
]
