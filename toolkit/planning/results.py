"""What a plan answers (:class:`PlanResult`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .edges import RESOLUTION

__all__ = ["PlanResult"]


@dataclass(frozen=True)
class PlanResult:
    """A plan: ``path`` (K, nq) from the start to ``goals[goal]``, every straight segment
    between waypoints free of collision, certified after the search (``verified``): over
    its whole motion (``swept``), else at configurations at most ``resolution`` apart.
    Without a path (``success`` False) ``path`` is empty and ``reason`` says why.
    ``search``: which collision test the search ran on: ``"covers"`` (the compiled search
    on configurations the bounds and sphere covers prove free, no coal) or ``"exact"``
    (the exact checker). ``swept``: the whole motion along every segment is certified free
    on the covers, not only the configurations checked (by conservative advancement:
    :func:`toolkit.planning.kernels.edge_swept`; covers that hold every point of the shapes
    and stay apart prove the shapes apart), and that certificate is the final check; the
    ``escapes`` segments (0, 1 or 2) aside: a start or goal the covers do not clear (a
    grasp beside its object) is left or reached by a short straight segment (at most
    :data:`~toolkit.planning.certain.ESCAPES`' longest), certified whole on the exact
    shapes. A path found on the exact checker is certified whole on the exact shapes too
    (conservative advancement on coal's distances:
    :class:`~toolkit.planning.sweep.ExactSweep`), so ``swept`` holds for every path but
    where no bound on how far the shapes' points move exists (``certificate``)."""

    success: bool
    path: np.ndarray
    goal: int  # the index in goals of the goal reached, -1 for none
    goals: np.ndarray  # (G, nq): the goal configurations the search aimed at
    time_s: float
    checks: int  # configurations checked for collision
    nodes: int  # the trees' nodes
    reason: str
    verified: bool = False
    resolution: float = RESOLUTION
    values: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    search: str = "exact"
    swept: bool = False
    escapes: int = 0
    ignored: tuple[str, ...] = ()
    """Joints a MoveIt request's start state named that the description fixes (not read)."""
    certificate: str = ""
    """How the path was certified over its whole motion: ``"covers"`` (every segment by
    the covers' certificate), ``"covers+exact"`` (the escapes' segments by the exact
    shapes' one, :class:`~toolkit.planning.sweep.ExactSweep`), ``"exact"`` (a path found on
    the exact checker: every segment on the exact shapes); ``"samples"`` where no bound on
    how far the shapes' points move exists (a slide without limits): configurations
    ``resolution`` apart only. Empty without a path."""

    @property
    def length(self) -> float:
        """The path's length in joint values (sum of the segments' Euclidean lengths)."""
        if len(self.values) < 2:
            return 0.0
        return float(np.linalg.norm(np.diff(self.values, axis=0), axis=1).sum())
