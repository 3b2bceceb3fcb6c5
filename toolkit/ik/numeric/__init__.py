"""The numeric room of IK: damped least squares from a start, for any arm.

* :mod:`~toolkit.ik.numeric.task`: the pose residual (``PoseTask``);
* :mod:`~toolkit.ik.numeric.options`: :class:`IKOptions` (tol, max_iter, restarts, seed,
  time_limit);
* :mod:`~toolkit.ik.numeric.solver`: the loop on Pinocchio, the per-thread ``SolverState``,
  the results and their verification;
* :mod:`~toolkit.ik.numeric.kernels`: the compiled loop;
  :mod:`~toolkit.ik.numeric.loops`: the loop of each kinematics back end, restarts and time
  budget (``solve_ik``);
* :mod:`~toolkit.ik.numeric.batch`: many targets, and warm-started paths;
  :mod:`~toolkit.ik.numeric.collision_free`: the same starts, until a collision-free answer.

It imports nothing of the analytic room; both use :mod:`toolkit.ik.checks` and
:mod:`toolkit.ik.targets`.
"""

from . import loops as loops
from . import solver as solver
from .batch import IKBatchResult as IKBatchResult
from .batch import batch_starts as batch_starts
from .batch import batch_targets as batch_targets
from .batch import check_poses as check_poses
from .batch import solve_batch as solve_batch
from .batch import solve_ik_path as solve_ik_path
from .batch import verified as verified
from .collision_free import Collides as Collides
from .collision_free import single_solver as single_solver
from .collision_free import solve_batch_collision_free as solve_batch_collision_free
from .collision_free import solve_collision_free as solve_collision_free
from .loops import CompiledLoop as CompiledLoop
from .loops import IKLoop as IKLoop
from .loops import NumericIK as NumericIK
from .loops import PinocchioLoop as PinocchioLoop
from .loops import loop_for as loop_for
from .loops import solve_ik as solve_ik
from .options import MAX_TOL as MAX_TOL
from .options import IKOptions as IKOptions
from .solver import DAMPING as DAMPING
from .solver import LAMBDA_MIN as LAMBDA_MIN
from .solver import STALL as STALL
from .solver import IKResult as IKResult
from .solver import PathResult as PathResult
from .solver import SolverState as SolverState
from .solver import kernel_seed as kernel_seed
from .solver import run_pinocchio as run_pinocchio
from .solver import verify as verify
from .task import PoseTask as PoseTask
