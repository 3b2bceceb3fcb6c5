"""The analytic room of IK: every branch of an arm whose axes allow it, in closed form.

* :mod:`~toolkit.ik.analytic.chain` and :mod:`~toolkit.ik.analytic.structure`: an arm's
  joint axes read as a chain, and the family that solves it (``Structure``);
* :mod:`~toolkit.ik.analytic.subproblems` and
  :mod:`~toolkit.ik.analytic.subproblem_kernels`: Paden-Kahan's subproblems 1-6;
* :mod:`~toolkit.ik.analytic.family` (the families' keys) and
  :mod:`~toolkit.ik.analytic.registry` (one record per family, :func:`solve`);
* :mod:`~toolkit.ik.analytic.families` (with :mod:`~toolkit.ik.analytic.prismatic` and
  :mod:`~toolkit.ik.analytic.search`) and their compiled forms
  :mod:`~toolkit.ik.analytic.family_kernels`, :mod:`~toolkit.ik.analytic.wrist_kernels`;
* :mod:`~toolkit.ik.analytic.branches` and :mod:`~toolkit.ik.analytic.branch_kernels`: the
  bookkeeping of branches (turns within the limits, distinct rows, ``IKAllResult``);
* :mod:`~toolkit.ik.analytic.door` and :mod:`~toolkit.ik.analytic.door_kernels`: every
  verified branch of N targets in one compiled call, the door of ``Robot.ik_all``.

It imports nothing of the numeric room; both use :mod:`toolkit.ik.checks` and
:mod:`toolkit.ik.targets`.
"""

from . import branch_kernels as branch_kernels
from . import branches as branches
from . import door_kernels as door_kernels
from . import families as families
from . import family_kernels as family_kernels
from . import registry as registry
from . import structure as structure
from . import subproblems as subproblems
from .branches import IKAllResult as IKAllResult
from .door import BranchDoor as BranchDoor
from .door import chain_angles as chain_angles
from .door_kernels import nearest_turn_rows as nearest_turn_rows
from .family import Family as Family
from .structure import Structure as Structure
