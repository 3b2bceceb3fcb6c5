"""The IK a robot holds, over both rooms: its calls (:class:`RobotIK`: ``ik``, ``ik_batch``,
``ik_path``, by branches where an exact compiled family answers, numerically elsewhere) and
its analytic IK (:class:`AnalyticIK`: structures, doors, ``ik_all``, ``ik_all_batch``, the
polish of an arm near its family, the branches near a singularity, why a target has none),
with what it keeps (:class:`BranchCaches`). Bound to a robot's model, joint space, frames,
kinematics back end and numeric IK (:class:`toolkit.ik.NumericIK`); the
:class:`~toolkit.robot.Robot`'s methods are theirs.
"""

from .batches import AnalyticIK
from .calls import BRANCH_TOL, IKRequest, RobotIK
from .kept import LOCKED_KEPT, BranchCaches

__all__ = ["BRANCH_TOL", "LOCKED_KEPT", "AnalyticIK", "BranchCaches", "IKRequest", "RobotIK"]
