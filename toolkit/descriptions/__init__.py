"""Robot descriptions: xacro templates rendered to URDF (and their verified cache), the
catalogue of the toolkit's own models, URDF files read safely with their packages found,
and Pinocchio models built and checked from them.

* :mod:`~toolkit.descriptions.catalogue`: the registry of catalogue models (each paper
  module registers its own);
* :mod:`~toolkit.descriptions.render`: xacro -> URDF with checked arguments, cached;
* :mod:`~toolkit.descriptions.files`: reading a description (size, encoding, untrusted
  folders), ``package://`` and ``$(find ...)`` lookup;
* :mod:`~toolkit.descriptions.models`: ``pinocchio.Model`` from URDF text, the default tool
  frame, example-robot-data's robots.

Nothing here builds a :class:`~toolkit.robot.Robot`: :mod:`toolkit.robot` does, from these.
"""

from . import catalogue, files, models, render, srdf
from .catalogue import MODELS, ModelSpec, available_models, get_spec, register
from .files import (
    MAX_LINKS,
    PackageResolver,
    check_size,
    read_description,
    urdf_source,
)
from .models import (
    EXAMPLE_ROBOTS,
    ExampleRobot,
    build_model,
    default_tip,
    example_robot_data_dir,
    example_robots,
    srdf_beside,
    tip_candidates,
)
from .render import (
    committed_urdf_path,
    model_arguments,
    resolve_arguments,
    templates_dir,
    urdf_path,
    urdf_text,
)
from .srdf import Srdf, read_srdf

__all__ = [
    "EXAMPLE_ROBOTS",
    "MAX_LINKS",
    "MODELS",
    "ExampleRobot",
    "ModelSpec",
    "PackageResolver",
    "Srdf",
    "available_models",
    "build_model",
    "catalogue",
    "check_size",
    "committed_urdf_path",
    "default_tip",
    "example_robot_data_dir",
    "example_robots",
    "files",
    "get_spec",
    "model_arguments",
    "models",
    "read_description",
    "read_srdf",
    "register",
    "render",
    "resolve_arguments",
    "srdf",
    "srdf_beside",
    "templates_dir",
    "tip_candidates",
    "urdf_path",
    "urdf_source",
    "urdf_text",
]
