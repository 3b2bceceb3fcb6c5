"""The :class:`Robot` users hold, and the ways to get one.

A ``Robot`` composes, above them, what the concept packages offer: kinematics queries on
its back end (:mod:`toolkit.kinematics`), inverse kinematics (:mod:`toolkit.ik`,
:mod:`~toolkit.robot.solving`) and collision queries (:mod:`toolkit.collision`,
:mod:`~toolkit.robot.collisions`). :mod:`~toolkit.robot.loading` builds one from the
catalogue, a URDF or xacro file, or example-robot-data (:mod:`toolkit.descriptions`).
"""

from . import collisions as collisions
from . import loading as loading
from . import model as model
from . import solving as solving
from .collisions import checker_for as checker_for
from .loading import EXAMPLE_ROBOTS, load, load_example, load_urdf
from .model import Robot
from .model import as_robot as as_robot
from .solving import IKRequest as IKRequest

Robot.__module__ = __name__  # pickles name toolkit.robot.Robot, wherever the class lives

__all__ = ["EXAMPLE_ROBOTS", "Robot", "load", "load_example", "load_urdf"]
# as_robot, checker_for, IKRequest and the modules: the toolkit's API between packages
