"""The paper-reproduction report (``toolkit report``).

Each section (one module per paper, :mod:`~toolkit.report.paper1` ...
:mod:`~toolkit.report.paper4`, and :mod:`~toolkit.report.benchmark`) computes its numbers
from the models, states the paper's claim next to them and says PASS or FAIL;
:mod:`~toolkit.report.render` writes ``DIR/report.md`` and ``DIR/index.html`` with PNG
figures. ``toolkit report`` exits non-zero when a check fails.
"""

from .benchmark import benchmark_section
from .checks import Check, Section
from .paper1 import backlash_section, katana_section
from .paper2 import arm5dof_section
from .paper3 import structures_section
from .paper4 import bending_section
from .render import SECTIONS, run_report

__all__ = [
    "SECTIONS",
    "Check",
    "Section",
    "arm5dof_section",
    "backlash_section",
    "benchmark_section",
    "bending_section",
    "katana_section",
    "run_report",
    "structures_section",
]
