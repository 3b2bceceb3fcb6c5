"""Inverse kinematics in two rooms over shared checks.

* :mod:`toolkit.ik.numeric`: damped least squares from a start, for any arm (the pose task,
  the options, the loop of each kinematics back end, batches, paths, collision-free
  restarts);
* :mod:`toolkit.ik.analytic`: every branch of an arm whose axes allow it, by subproblem
  decomposition, compiled, through one door (``Robot.ik_all``,
  ``Robot.ik(..., method="analytic")``);
* :mod:`toolkit.ik.checks` and :mod:`toolkit.ik.targets`, which both rooms use: the compiled
  checks of targets and answers (sharing no code with either solver) and the parsing of a
  target and a mask;
* :mod:`toolkit.ik.solvers`, over both rooms: the IK a robot holds (:class:`RobotIK`, its
  ``ik``, ``ik_batch``, ``ik_path``; :class:`AnalyticIK`, its ``ik_all``,
  ``ik_all_batch``, structures and doors).

Neither room imports the other, nor the solvers. Users meet these through :meth:`toolkit.Robot.ik`,
``ik_batch``, ``ik_all`` and ``ik_path``; ``__all__`` lists what users import. The other
names here are the toolkit's own API between packages: they take inputs already checked.
"""

from . import checks as checks
from .analytic import BranchDoor as BranchDoor
from .analytic import Family, IKAllResult, Structure
from .analytic import branch_kernels as branch_kernels
from .analytic import branches as branches
from .analytic import door_kernels as door_kernels
from .analytic import families as families
from .analytic import family_kernels as family_kernels
from .analytic import nearest_turn_rows as nearest_turn_rows
from .analytic import registry as registry
from .analytic import structure as structure
from .analytic import subproblems as subproblems
from .numeric import (
    DAMPING,
    LAMBDA_MIN,
    MAX_TOL,
    STALL,
    IKBatchResult,
    IKOptions,
    IKResult,
    PathResult,
)
from .numeric import Collides as Collides
from .numeric import CompiledLoop as CompiledLoop
from .numeric import IKLoop as IKLoop
from .numeric import NumericIK as NumericIK
from .numeric import PinocchioLoop as PinocchioLoop
from .numeric import PoseTask as PoseTask
from .numeric import SolverState as SolverState
from .numeric import batch_starts as batch_starts
from .numeric import batch_targets as batch_targets
from .numeric import kernel_seed as kernel_seed
from .numeric import loop_for as loop_for
from .numeric import loops as loops
from .numeric import run_pinocchio as run_pinocchio
from .numeric import single_solver as single_solver
from .numeric import solve_batch as solve_batch
from .numeric import solve_batch_collision_free as solve_batch_collision_free
from .numeric import solve_collision_free as solve_collision_free
from .numeric import solve_ik as solve_ik
from .numeric import solve_ik_path as solve_ik_path
from .numeric import solver as solver
from .numeric import verified as verified
from .numeric import verify as verify
from .targets import nearest_rotations as nearest_rotations
from .targets import parse_mask, parse_target

from . import solvers as solvers  # isort: skip  (over both rooms: last)
from .solvers import AnalyticIK as AnalyticIK  # isort: skip
from .solvers import BranchCaches as BranchCaches  # isort: skip
from .solvers import RobotIK as RobotIK  # isort: skip

__all__ = [
    "DAMPING",
    "LAMBDA_MIN",
    "MAX_TOL",
    "STALL",
    "Family",
    "IKAllResult",
    "IKBatchResult",
    "IKOptions",
    "IKResult",
    "PathResult",
    "Structure",
    "parse_mask",
    "parse_target",
]
