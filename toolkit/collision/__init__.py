"""Collisions: the robot's own links and the objects of a :class:`Scene` (exact, on coal).

* **The robot's collision model** comes from the URDF's ``<collision>`` elements (meshes
  through coal/assimp, primitives as primitives), by Pinocchio's ``GeometryModel``. A
  robot whose file has no collision elements falls back to its visual shapes, with a
  :class:`CollisionGeometryWarning`.
* **Pairs checked**: every pair of shapes on different links, less the pairs of links
  joined by a joint (adjacent links touch by design) and less the pairs an SRDF disables
  (``<disable_collisions>``: ``load_example`` finds example-robot-data's SRDFs,
  ``load_urdf(..., srdf=path)`` takes one). Every robot shape against every scene object;
  an attached object against the links other than its own and against the scene.
* **Exact**: coal's narrow phase on the real meshes (no sphere approximation); a distance
  is negative when shapes penetrate.

For a robot without an SRDF, :func:`disabled_pairs` finds the pairs that are never or
always in collision over random configurations (the MoveIt setup assistant's method) and
can write them as an SRDF.

The package: :mod:`~toolkit.collision.scene` (the :class:`Scene`),
:mod:`~toolkit.collision.checker` (the :class:`Checker` on coal),
:mod:`~toolkit.collision.bounds` and :mod:`~toolkit.collision.bound_kernels` (its compiled
pre-filter), :mod:`~toolkit.collision.pairs` (:func:`disabled_pairs`). A robot's collision
queries (``Robot.in_collision``, ``collision_checker``, collision-free IK) build a
checker per scene and keep it.

Shapes fixed to the robot's base are checked against the scene's fixed objects once per
checker (the answer is the same at every configuration: ``Checker.base_hits``); a
*support* the robot stands on (a floor, ``Scene.add_box(..., support=True)``) may be
touched by them and entered by :data:`SUPPORT_SLACK`, any other object not at all.

A :class:`Scene` is plain data (shapes, sizes, poses): it prints, pickles, compares, and
saves to / loads from a small JSON file (``Scene.save``, ``Scene.load``; the CLI's
``--scene``).

:func:`sphere_model` covers a robot's shapes with spheres, every point of their surfaces
inside one (:mod:`toolkit.collision.spheres`): the cheap, conservative stand-in planners
check first.
"""

from . import bound_kernels as bound_kernels
from . import bounds as bounds
from . import broad as broad
from . import checker as checker
from . import convex as convex
from . import convex_kernels as convex_kernels
from . import gap_kernels as gap_kernels
from . import pairs as pairs
from . import parts as parts
from . import pieces as pieces
from . import scene as scene
from . import shapes as shapes
from . import spheres as spheres
from . import stored as stored
from .bounds import Bounds as Bounds
from .bounds import Packed as Packed
from .checker import Checker as Checker
from .checker import CollisionSubject as CollisionSubject
from .pairs import disabled_pairs
from .scene import FLOOR as FLOOR
from .scene import KINDS as KINDS
from .scene import MAX_POINTS as MAX_POINTS
from .scene import SUPPORT_SLACK as SUPPORT_SLACK
from .scene import CheckerTimeout as CheckerTimeout
from .scene import CollisionGeometryWarning as CollisionGeometryWarning
from .scene import Scene as Scene
from .scene import SceneObject as SceneObject
from .spheres import SphereModel, sphere_model

__all__ = [*scene.__all__, "SphereModel", "disabled_pairs", "sphere_model"]
# Bounds, Checker, CollisionSubject, FLOOR and the modules: the API between packages
