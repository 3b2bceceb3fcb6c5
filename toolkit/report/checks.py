"""What a report section is: the papers' claims checked, tables and figures to draw.

The sections (``toolkit.report.paper1`` ... ``paper4``, ``benchmark``) compute these;
:mod:`toolkit.report.render` writes them out. Nothing here renders.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Check", "Section", "save_figure"]


@dataclass(frozen=True)
class Check:
    """One claim of a paper, the toolkit's number for it, and whether it holds."""

    claim: str
    measured: str
    passed: bool


@dataclass
class Section:
    """A titled part of the report: checks plus free Markdown (tables)."""

    title: str
    checks: list[Check] = field(default_factory=list)
    markdown: list[str] = field(default_factory=list)
    figures: list[tuple[str, Callable[[Path], None]]] = field(default_factory=list)

    def check(self, claim: str, error: float, tol: float, unit: str = "") -> None:
        """Record a numeric check ``error <= tol``."""
        self.checks.append(Check(claim, f"max error {error:.3g}{unit} (tol {tol:g})", error <= tol))


def save_figure(ax: Any, path: Path, **options: Any) -> None:
    """Save the figure that holds the matplotlib axes ``ax`` (the root figure) as ``path``."""
    figure = ax.figure
    while getattr(figure, "figure", figure) is not figure:  # a SubFigure's parent
        figure = figure.figure
    figure.savefig(path, **options)
