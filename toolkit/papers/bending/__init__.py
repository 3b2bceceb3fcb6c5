"""Cable-driven bending manipulator of rigid elements rolling on spherical surfaces ([P4]).

A link is a stack of n identical elements. Element 0 is fixed; each next element hangs
below and rolls without slipping on the one above; the contact surfaces are spheres of
radius R. Four cables (XP, YP, XN, YN) run through holes on a circle of diameter d.
Each pair of neighbours is described by the contact angle ``alpha`` and the bending-plane
angle ``psi`` (psi = 0 bends towards +X, the side of the XP cable).

Geometry (derived from rolling, see docs/bending.md): with k = R - h0 and
u = (sin a cos psi, sin a sin psi, -cos a), element i in the frame of element i-1 is

    R_i = Rot(l, 2 alpha),  l = (sin psi, -cos psi, 0)                (eq. 5, rotation)
    O_i = (0, 0, k) + 2R u + R_i (0, 0, k) = (2R - 2k cos alpha) u       (eq. 5, corrected)

so every segment O_{i-1} O_i makes the angle alpha with the axis of element i-1, and
the chord of n elements makes n alpha with the base axis (the paper's G = n alpha).

Conventions: lengths in metres, angles in radians; cable changes are positive for
shortening (the paper's sign); psi is returned in [0, 2 pi). The element geometry is a
:class:`Geometry` (validated once); :mod:`~toolkit.bending.geometry` also registers the
``bending`` catalogue model, whose arguments are checked by the same class.
"""

from .cables import CABLES, angles_from_cables, cable_lengths_exact, cables_from_angles
from .figures import draw_figure4, draw_figure5, figure4, figure5
from .geometry import (
    MAX_ELEMENTS,
    Geometry,
    angles_to_q,
    chain_pose,
    element_transform,
    link_pose,
    paper_eq5_centre,
    q_to_angles,
    shape,
)
from .inverse import InverseResult, inverse, paper_inverse

__all__ = [
    "CABLES",
    "MAX_ELEMENTS",
    "Geometry",
    "InverseResult",
    "angles_from_cables",
    "angles_to_q",
    "cable_lengths_exact",
    "cables_from_angles",
    "chain_pose",
    "draw_figure4",
    "draw_figure5",
    "element_transform",
    "figure4",
    "figure5",
    "inverse",
    "link_pose",
    "paper_eq5_centre",
    "paper_inverse",
    "q_to_angles",
    "shape",
]
