"""Inverse kinematics: the pose task, the options, the solvers and their independent checks.

* :mod:`~toolkit.ik.task`: the target and its residual (``PoseTask``: position error in base
  axes, orientation error in the tool's axes, six weights);
* :mod:`~toolkit.ik.options`: :class:`IKOptions` (tol, max_iter, restarts, seed, timeout);
* :mod:`~toolkit.ik.solver`: damped least squares with adaptive damping on Pinocchio, the
  per-thread ``SolverState``, the results and their verification;
* :mod:`~toolkit.ik.loops`: the loop on each kinematics back end (compiled or Pinocchio),
  restarts and time budget; ``solve_ik``;
* :mod:`~toolkit.ik.batch`: many targets at once, and warm-started paths;
* :mod:`~toolkit.ik.collision_free`: the same starts, until a collision-free solution;
* :mod:`~toolkit.ik.structure`, :mod:`~toolkit.ik.subproblems`, :mod:`~toolkit.ik.analytic`
  and :mod:`~toolkit.ik.branches`: every branch of an arm whose axes allow it, by
  subproblem decomposition (``Robot.ik_all``, ``Robot.ik(..., method="analytic")``);
* :mod:`~toolkit.ik.door` and :mod:`~toolkit.ik.door_kernels`: every verified branch of N
  targets in one compiled call, the door of ``ik_all`` and ``ik_all_batch``;
* :mod:`~toolkit.ik.kernels`: the compiled loop; :mod:`~toolkit.ik.checks`: the compiled
  checks of targets and answers, sharing no code with the solver.

Users meet these through :meth:`toolkit.Robot.ik`, ``ik_batch`` and ``ik_path``; ``__all__``
lists what users import. The other names here (``PoseTask``, ``SolverState``, the loops and
solvers) are the toolkit's own API between packages: they take inputs already checked.
"""

from . import analytic as analytic
from . import analytic_kernels as analytic_kernels
from . import branch_kernels as branch_kernels
from . import branches as branches
from . import door_kernels as door_kernels
from . import loops as loops
from . import solver as solver
from . import structure as structure
from . import subproblems as subproblems
from .batch import IKBatchResult
from .batch import batch_starts as batch_starts
from .batch import batch_targets as batch_targets
from .batch import solve_batch as solve_batch
from .batch import solve_ik_path as solve_ik_path
from .batch import verified as verified
from .branches import IKAllResult
from .collision_free import Collides as Collides
from .collision_free import single_solver as single_solver
from .collision_free import solve_batch_collision_free as solve_batch_collision_free
from .collision_free import solve_collision_free as solve_collision_free
from .door import BranchDoor as BranchDoor
from .door_kernels import nearest_turn_rows as nearest_turn_rows
from .loops import CompiledLoop as CompiledLoop
from .loops import IKLoop as IKLoop
from .loops import IKSubject as IKSubject
from .loops import PinocchioLoop as PinocchioLoop
from .loops import loop_for as loop_for
from .loops import solve_ik as solve_ik
from .options import MAX_TOL, IKOptions
from .solver import DAMPING, LAMBDA_MIN, STALL, IKResult, PathResult
from .solver import SolverState as SolverState
from .solver import kernel_seed as kernel_seed
from .solver import run_pinocchio as run_pinocchio
from .solver import verify as verify
from .structure import Structure
from .task import PoseTask as PoseTask
from .task import nearest_rotations as nearest_rotations
from .task import parse_mask, parse_target

__all__ = [
    "DAMPING",
    "LAMBDA_MIN",
    "MAX_TOL",
    "STALL",
    "IKAllResult",
    "IKBatchResult",
    "IKOptions",
    "IKResult",
    "PathResult",
    "Structure",
    "parse_mask",
    "parse_target",
]
