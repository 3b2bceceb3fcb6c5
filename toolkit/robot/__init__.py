"""The :class:`Robot` users hold, and the ways to get one.

A ``Robot`` is a thin face over what the concept packages offer: its joint space, frames
and kinematics back end (:mod:`toolkit.kinematics`), its inverse kinematics
(:mod:`toolkit.ik`: :class:`~toolkit.ik.RobotIK`, :class:`~toolkit.ik.AnalyticIK`) and its
collision queries and plans (:mod:`toolkit.collision`, :mod:`toolkit.planning`, through
:mod:`~toolkit.robot.collisions`). :mod:`~toolkit.robot.loading` builds one from the
catalogue, a URDF or xacro file, or example-robot-data (:mod:`toolkit.descriptions`).
"""

from . import checkers as checkers
from . import collisions as collisions
from . import loading as loading
from . import model as model
from .checkers import checker_for as checker_for
from .loading import EXAMPLE_ROBOTS, load, load_example, load_urdf
from .model import Robot
from .model import as_robot as as_robot

Robot.__module__ = __name__  # pickles name toolkit.robot.Robot, wherever the class lives

__all__ = ["EXAMPLE_ROBOTS", "Robot", "load", "load_example", "load_urdf"]
# as_robot, checker_for and the modules: the toolkit's API between packages
