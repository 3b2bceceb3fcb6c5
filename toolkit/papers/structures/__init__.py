"""The five 3-DOF positioning structures of [P3]: matrices, point motion, IK, workspaces.

[P3] gives each structure as T14 = T12 T23 T34 (eq. 1) with the adjacent matrices of
eqs. 5-9 (frame 1 = the stand, frame 4 = the end link), and a point M of the end link
with constant local coordinates rho: r_M = T14 rho, V_M = dT14/dt rho,
a_M = d2T14/dt2 rho (eqs. 2-4).

* :func:`paper_transforms` writes the paper's matrices literally (an independent route
  to the xacro models, which the tests compare with Pinocchio).
* :func:`euler_zxz` is the paper's general adjacent transform; :func:`zxz_to_origin` and
  :func:`origin_to_zxz` convert it to and from a URDF ``origin xyz/rpy``.
* :func:`closed_form_ik` returns every joint solution that puts M on a target point.
* :func:`point_history` and :func:`resolved_rate` are the forward and inverse time
  problems; :func:`workspace` and :func:`workspace_volume` the reach space.

:mod:`~toolkit.structures.models` registers the five catalogue models; each carries its
structure's name as the ``structure`` fact, which is how the functions here recognise a
[P3] model.
"""

from .inverse import closed_form_ik
from .matrices import (
    euler_zxz,
    origin_to_zxz,
    paper_T14,
    paper_transforms,
    rpy_matrix,
    zxz_to_origin,
)
from .models import STRUCTURES, default_rho
from .motion import History, RateResult, point_history, resolved_rate
from .workspace import (
    ReachSection,
    Workspace,
    analytic_volume,
    draw_sections,
    draw_workspace,
    reach_section,
    workspace,
    workspace_volume,
)

__all__ = [
    "STRUCTURES",
    "History",
    "RateResult",
    "ReachSection",
    "Workspace",
    "analytic_volume",
    "closed_form_ik",
    "default_rho",
    "draw_sections",
    "draw_workspace",
    "euler_zxz",
    "origin_to_zxz",
    "paper_T14",
    "paper_transforms",
    "point_history",
    "reach_section",
    "resolved_rate",
    "rpy_matrix",
    "workspace",
    "workspace_volume",
    "zxz_to_origin",
]
