"""Kinematics of robot manipulators on Pinocchio.

Catalogue models (Katana 6M, ...) are rendered from the toolkit's own xacro
templates; any URDF file and the robots of example-robot-data load as well.

The package is its architecture (docs/architecture.md): below, what every package uses
(:mod:`toolkit.common`, :mod:`toolkit.errors`); the core's concepts
(:mod:`toolkit.kinematics`, :mod:`toolkit.ik`, :mod:`toolkit.collision`,
:mod:`toolkit.descriptions`), composed for the user by :mod:`toolkit.robot`
(:class:`Robot`), and :mod:`toolkit.calibration`; :mod:`toolkit.papers` holds the four
papers' models (also reachable as ``toolkit.katana``, ``toolkit.backlash``, ...);
:mod:`toolkit.maps` builds on both; the apps (:mod:`toolkit.report`, :mod:`toolkit.viz`,
:mod:`toolkit.cli`) on all.

>>> import toolkit
>>> robot = toolkit.load("katana_6m180")
>>> robot.fk([0, 0, 0, 0, 0]).round(4)[:3, 3].tolist()
[0.329, 0.0, 0.5043]
"""

import sys as _sys

from . import calibration, collision, dynamics, errors, ik, maps, motion, planning
from ._version import __version__
from .cli import warmup
from .collision import Scene
from .descriptions import available_models, model_arguments, urdf_path, urdf_text
from .errors import CacheError as CacheError
from .errors import CollisionWarning as CollisionWarning
from .errors import ConfigurationError as ConfigurationError
from .errors import ConvergenceError as ConvergenceError
from .errors import FrameNotFoundError as FrameNotFoundError
from .errors import GeometryError as GeometryError
from .errors import InertiaWarning as InertiaWarning
from .errors import InstallationError as InstallationError
from .errors import InvalidParameterError as InvalidParameterError
from .errors import MapStoreError as MapStoreError
from .errors import ModelLoadError as ModelLoadError
from .errors import RenderError as RenderError
from .errors import ToolkitError as ToolkitError
from .errors import UnknownModelError as UnknownModelError
from .errors import UnreachableTargetsWarning as UnreachableTargetsWarning
from .errors import UnsupportedModelError as UnsupportedModelError
from .ik import IKOptions, IKResult, PathResult
from .papers import arm5dof, backlash, bending, katana, structures
from .robot import EXAMPLE_ROBOTS, Robot, load, load_example, load_urdf

# the paper modules keep their short names: ``import toolkit.katana`` and
# ``from toolkit.backlash import Backlash`` reach the same module objects
for _name, _module in list(_sys.modules.items()):
    if _name.startswith(f"{__name__}.papers.") and not _name.endswith("._planar"):
        _sys.modules[__name__ + _name[len(f"{__name__}.papers") :]] = _module

# objects pickled before the package had its concept folders name their classes by the old
# module paths (toolkit._scene.Scene, toolkit.options.IKOptions, toolkit.batch...): those
# paths still resolve, so such pickles load
# (and toolkit.ik.options, toolkit.ik.structure..., before the IK had its two rooms)
for _old, _new in (
    ("_scene", collision.scene),
    ("options", ik.numeric.options),
    ("batch", ik.numeric.batch),
    ("ik.options", ik.numeric.options),
    ("ik.batch", ik.numeric.batch),
    ("ik.solver", ik.numeric.solver),
    ("ik.chain", ik.analytic.chain),
    ("ik.structure", ik.analytic.structure),
    ("ik.branches", ik.analytic.branches),
):
    _sys.modules.setdefault(f"{__name__}.{_old}", _new)

__all__ = [
    "EXAMPLE_ROBOTS",
    "IKOptions",
    "IKResult",
    "PathResult",
    "Robot",
    "Scene",
    "__version__",
    "arm5dof",
    "available_models",
    "backlash",
    "bending",
    "calibration",
    "collision",
    "dynamics",
    "ik",
    "katana",
    "load",
    "load_example",
    "load_urdf",
    "maps",
    "model_arguments",
    "motion",
    "planning",
    "structures",
    "urdf_path",
    "urdf_text",
    "warmup",
    *errors.__all__,
]
