"""The four papers' models, built on the core (:mod:`toolkit.robot`, :mod:`toolkit.ik`, ...).

* :mod:`~toolkit.katana` and :mod:`~toolkit.backlash`: [P1], the Katana 6M and its joint
  backlash;
* :mod:`~toolkit.arm5dof`: [P2], the 5-DOF arm's geometric IK;
* :mod:`~toolkit.structures`: [P3], the five 3-DOF positioning structures;
* :mod:`~toolkit.bending`: [P4], the cable-driven bending manipulator.

Importing this package registers the papers' catalogue models. The references are in
docs/references.md. Each module is also reachable as ``toolkit.<name>``.
"""

from . import arm5dof, backlash, bending, katana, structures

__all__ = ["arm5dof", "backlash", "bending", "katana", "structures"]
