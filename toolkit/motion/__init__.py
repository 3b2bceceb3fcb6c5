"""Motion in time: joint trajectories through waypoints and what they ask of the arm.

A :class:`Trajectory` is piecewise polynomial in time (one value per joint); it samples
(t, q, qd, qdd) at any times or at a rate, gives its peak joint speeds and accelerations,
and the joint torques along it (:func:`toolkit.dynamics.inverse_dynamics`). Made by
:func:`quintic` (rest at every waypoint, the Robotics Toolbox's ``jtraj`` per segment),
:func:`cubic` (a spline at rest at both ends) or :func:`trapezoidal` (MATLAB's
``trapveltraj``: within joint velocity and acceleration limits), or :func:`cartesian` (the
tool on a straight line, the Robotics Toolbox's ``ctraj``, through the IK along the path,
:mod:`toolkit.motion.lines`). The builders are in
:mod:`toolkit.motion.profiles`, the trajectory in :mod:`toolkit.motion.trajectory`;
:func:`write_csv` and :func:`read_trajectory` (:mod:`toolkit.motion.tables`) move one to and
from a CSV file (t, q, qd, qdd, tau). :func:`time_optimal` (:mod:`toolkit.motion.optimal`)
times a path as fast as joint velocity, acceleration and torque limits allow (TOPP-RA,
through ``toppra``: the ``motion`` extra); :func:`jerk_limited` stops at every waypoint
within jerk limits too (Ruckig, the same extra); :class:`Online` steps a controller's cycles
toward a target that may change at any cycle (Ruckig's online generation); :func:`plot`
draws one against time with the limits.
"""

from . import jerk as jerk
from . import lines as lines
from . import online as online
from . import optimal as optimal
from . import plots as plots
from . import profiles as profiles
from . import tables as tables
from . import trajectory as trajectory
from .jerk import jerk_limited
from .lines import cartesian
from .online import Online
from .optimal import time_optimal
from .plots import plot
from .profiles import cubic, quintic, trapezoidal
from .tables import hermite, read_trajectory, write_csv
from .trajectory import Samples, Trajectory

__all__ = [
    "Online",
    "Samples",
    "Trajectory",
    "cartesian",
    "cubic",
    "hermite",
    "jerk_limited",
    "plot",
    "quintic",
    "read_trajectory",
    "time_optimal",
    "trapezoidal",
    "write_csv",
]
