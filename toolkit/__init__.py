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

import importlib
import importlib.abc
import importlib.machinery
import sys as _sys
import threading as _threading
from types import ModuleType
from typing import TYPE_CHECKING, Any

from . import errors
from ._version import __version__
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

if TYPE_CHECKING:  # what the first use of any other name loads (below)
    from . import calibration, collision, dynamics, ik, maps, motion, planning
    from .cli import warmup
    from .collision import Scene
    from .descriptions import available_models, model_arguments, urdf_path, urdf_text
    from .ik import IKOptions, IKResult, PathResult
    from .papers import arm5dof, backlash, bending, katana, structures
    from .robot import EXAMPLE_ROBOTS, Robot, load, load_example, load_urdf

# The package loads on first use: ``import toolkit`` (and ``toolkit --help``) imports only
# the errors; the first other name asked of it (``toolkit.load``), or an import of one of its
# short or old module names, loads the whole package at once, as an eager import did.
_SUBPACKAGES = frozenset((
    "calibration", "cli", "collision", "common", "descriptions", "dynamics", "ik",
    "kinematics", "maps", "motion", "papers", "planning", "report", "robot", "viz",
))  # fmt: skip
_PAPERS = ("arm5dof", "backlash", "bending", "katana", "structures")
# objects pickled before the package had its concept folders name their classes by the old
# module paths (toolkit._scene.Scene, toolkit.options.IKOptions, toolkit.batch...): those
# paths still resolve, so such pickles load
# (and toolkit.ik.options, toolkit.ik.structure..., before the IK had its two rooms)
_OLD = {
    "_scene": "collision.scene",
    "options": "ik.numeric.options",
    "batch": "ik.numeric.batch",
    "ik.options": "ik.numeric.options",
    "ik.batch": "ik.numeric.batch",
    "ik.solver": "ik.numeric.solver",
    "ik.chain": "ik.analytic.chain",
    "ik.structure": "ik.analytic.structure",
    "ik.branches": "ik.analytic.branches",
}
_LOCK = _threading.RLock()
_LOADED: list[bool] = []
_BUSY: list[int] = []
"""The thread loading the package, while it does."""


def _load() -> None:
    """Import the package's concepts and bind the names of :data:`__all__` (once)."""
    with _LOCK:
        if _LOADED or _BUSY:
            return
        _BUSY.append(_threading.get_ident())
        try:
            _bind()
            _LOADED.append(True)
        finally:
            _BUSY.clear()


def _bind() -> None:
    """:func:`_load`'s imports and names (importing a concept never asks the package for
    a name: ``__getattr__`` answers nothing while this runs)."""
    for name in ("calibration", "collision", "dynamics", "ik", "maps", "motion", "planning"):
        importlib.import_module(f"{__name__}.{name}")
    papers = importlib.import_module(f"{__name__}.papers")
    from .cli import warmup
    from .collision import Scene
    from .descriptions import available_models, model_arguments, urdf_path, urdf_text
    from .ik import IKOptions, IKResult, PathResult
    from .robot import EXAMPLE_ROBOTS, Robot, load, load_example, load_urdf

    globals().update(
        warmup=warmup, Scene=Scene, available_models=available_models,
        model_arguments=model_arguments, urdf_path=urdf_path, urdf_text=urdf_text,
        IKOptions=IKOptions, IKResult=IKResult, PathResult=PathResult,
        EXAMPLE_ROBOTS=EXAMPLE_ROBOTS, Robot=Robot, load=load, load_example=load_example,
        load_urdf=load_urdf,
    )  # fmt: skip
    for name in _PAPERS:
        globals()[name] = getattr(papers, name)
    # the paper modules keep their short names: ``import toolkit.katana`` and
    # ``from toolkit.backlash import Backlash`` reach the same module objects
    for name, module in list(_sys.modules.items()):
        if name.startswith(f"{__name__}.papers.") and not name.endswith("._planar"):
            _sys.modules.setdefault(__name__ + name[len(f"{__name__}.papers") :], module)
    for old, new in _OLD.items():
        _sys.modules.setdefault(f"{__name__}.{old}", _sys.modules[f"{__name__}.{new}"])


def __getattr__(name: str) -> Any:
    if name.startswith("__") or _threading.get_ident() in _BUSY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    if name in _SUBPACKAGES:  # a concept asked for alone (``from .. import dynamics``)
        return importlib.import_module(f"{__name__}.{name}")
    _load()
    try:
        return globals()[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__() -> list[str]:
    """The package's names without loading it (``dir(toolkit)``, a REPL's completion): its
    face (:data:`__all__`), its concepts and its version."""
    return sorted({*__all__, *_SUBPACKAGES, "__version__"})


class _ShortNames(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """``import toolkit.katana`` (a paper's short name, and its submodules) and the old
    module paths of :data:`_OLD`: the package loaded, the module that name stands for."""

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> Any:
        head, _, rest = fullname.partition(".")
        if head != __name__ or not rest:
            return None
        if rest.split(".")[0] not in _PAPERS and rest not in _OLD:
            return None
        _load()
        target = f"{__name__}.{_OLD[rest]}" if rest in _OLD else f"{__name__}.papers.{rest}"
        if target not in _sys.modules:
            importlib.import_module(target)  # a paper's submodule not imported yet
        # the name is the import system's to bind: left bound, it would run the file anew
        _sys.modules.pop(fullname, None)
        return importlib.machinery.ModuleSpec(fullname, self, loader_state=target)

    def create_module(self, spec: Any) -> ModuleType:
        module: ModuleType = _sys.modules[spec.loader_state]
        return module

    def exec_module(self, module: ModuleType) -> None:
        return None


if not any(isinstance(f, _ShortNames) for f in _sys.meta_path):
    _sys.meta_path.insert(0, _ShortNames())

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
