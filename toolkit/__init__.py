"""Kinematics of robot manipulators on Pinocchio.

Catalogue models (Katana 6M, ...) are rendered from the toolkit's own xacro
templates; any URDF file and the robots of example-robot-data load as well.

Layers: the core (:mod:`toolkit.robot`, :mod:`toolkit.ik`, :mod:`toolkit.engine`,
:mod:`toolkit.render`, :mod:`toolkit.catalogue`, :mod:`toolkit.loaders`,
:mod:`toolkit.errors`) knows no paper; :mod:`toolkit.papers` holds the four papers'
models (also reachable as ``toolkit.katana``, ``toolkit.backlash``, ...); the apps
(:mod:`toolkit.report`, :mod:`toolkit.viz`, :mod:`toolkit.cli`) use both.

>>> import toolkit
>>> robot = toolkit.load("katana_6m180")
>>> robot.fk([0, 0, 0, 0, 0]).round(4)[:3, 3].tolist()
[0.329, 0.0, 0.5043]
"""

import sys as _sys

from . import collision, maps
from ._scene import Scene
from ._version import __version__
from ._warmup import warmup
from .catalogue import available_models
from .errors import (
    CacheError,
    ConfigurationError,
    ConvergenceError,
    FrameNotFoundError,
    GeometryError,
    InstallationError,
    InvalidParameterError,
    MapStoreError,
    ModelLoadError,
    RenderError,
    ToolkitError,
    UnknownModelError,
    UnsupportedModelError,
)
from .ik import IKOptions, IKResult, PathResult
from .loaders import EXAMPLE_ROBOTS, load, load_example, load_urdf
from .papers import arm5dof, backlash, bending, katana, structures
from .render import model_arguments, urdf_path, urdf_text
from .robot import Robot

# the paper modules keep their short names: ``import toolkit.katana`` and
# ``from toolkit.backlash import Backlash`` reach the same module objects
for _name, _module in list(_sys.modules.items()):
    if _name.startswith(f"{__name__}.papers.") and not _name.endswith("._planar"):
        _sys.modules[__name__ + _name[len(f"{__name__}.papers") :]] = _module

__all__ = [
    "EXAMPLE_ROBOTS",
    "CacheError",
    "ConfigurationError",
    "ConvergenceError",
    "FrameNotFoundError",
    "GeometryError",
    "IKOptions",
    "IKResult",
    "InstallationError",
    "InvalidParameterError",
    "MapStoreError",
    "ModelLoadError",
    "PathResult",
    "RenderError",
    "Robot",
    "Scene",
    "ToolkitError",
    "UnknownModelError",
    "UnsupportedModelError",
    "__version__",
    "arm5dof",
    "available_models",
    "backlash",
    "bending",
    "collision",
    "katana",
    "load",
    "load_example",
    "load_urdf",
    "maps",
    "model_arguments",
    "structures",
    "urdf_path",
    "urdf_text",
    "warmup",
]
