"""Kinematics: how a Pinocchio model's joints are laid out in q, and the back ends that
compute forward kinematics, frame Jacobians and gravity on many configurations at once.

* :mod:`~toolkit.kinematics.joints`: the joint-coordinate layout (revolute, prismatic,
  continuous (cos, sin), free-flyer, mimic), limits, sampling;
* :mod:`~toolkit.kinematics.backends`: one :class:`Backend` interface, compiled
  (:class:`CompiledBackend`, numba kernels on packed chains) or Pinocchio's own
  (:class:`PinocchioBackend`); :func:`select` picks one; one size policy
  (:func:`parallel`, :func:`serial`) decides when a batch is spread over the cores;
* :mod:`~toolkit.kinematics.kernels`: the compiled loops (frames, FK, Jacobian, gravity,
  integration on each joint's manifold, the seeded restart stream);
* :mod:`~toolkit.kinematics.poses`: the tip's pose alone for verifications, one
  configuration at a time or many vectorized; :mod:`~toolkit.kinematics.trig`: the sine
  and cosine the kernels take at once;
* :mod:`~toolkit.common.compiler`: how numba is used (a private cache folder, the
  launch lock, the threading layer; one Python function compiled serial and parallel).

The IK (:mod:`toolkit.ik`), the collision pre-filter (:mod:`toolkit.collision`) and the
backlash fixed point build their own compiled loops on these kernels.
"""

from ..common import (
    PARALLEL_LOCK,
    EngineCacheWarning,
    Twin,
    cache_folder,
    compile_seconds,
    compiler,
    inline_kernel,
    kernel,
    parallel_kernel,
    twin_kernel,
)
from . import frames, joints, kernels, poses, trig
from .backends import (
    PARALLEL_MIN,
    Backend,
    CompiledBackend,
    EngineChoice,
    PinocchioBackend,
    parallel,
    select,
    serial,
)
from .frames import Frames
from .joints import CIRCLE_TOL, FREE_FLYER_BOX, JointInfo, JointLayout

__all__ = [
    "CIRCLE_TOL",
    "FREE_FLYER_BOX",
    "PARALLEL_LOCK",
    "PARALLEL_MIN",
    "Backend",
    "CompiledBackend",
    "EngineCacheWarning",
    "EngineChoice",
    "Frames",
    "JointInfo",
    "JointLayout",
    "PinocchioBackend",
    "Twin",
    "cache_folder",
    "compile_seconds",
    "compiler",
    "frames",
    "inline_kernel",
    "joints",
    "kernel",
    "kernels",
    "parallel",
    "parallel_kernel",
    "poses",
    "select",
    "serial",
    "trig",
    "twin_kernel",
]
