"""The records the planner's kernels take (:mod:`toolkit.planning.kernels`), made in one
place (:class:`~toolkit.planning.certain.CertainTest`) and read by name outside the
kernels: :class:`Space` (what is free, and how edges are checked), :class:`Work` (scratch
and counts, one per thread) and :class:`Trees` (the two trees of the compiled search).
The kernels read them by position, in the order of their fields."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

__all__ = ["Space", "Trees", "Work"]


class Space(NamedTuple):
    """What the search's kernels take as free, and how they check an edge."""

    qcol: np.ndarray
    """(n,) per joint value its column in q."""
    circle: np.ndarray
    """(n,) per joint value whether it is a (cos, sin) pair (a continuous joint)."""
    packed: Any
    """The pre-filter's arrays (:class:`toolkit.collision.bounds.Packed`)."""
    reach: np.ndarray
    """(S, n) how far [m] each shape's points lie from each joint value's axis (1 for a
    slide; where the joint does not move the shape, from the axis it rides with, else inf:
    :func:`~toolkit.planning.reach`)."""
    moves: np.ndarray
    """(S, n) whether each joint value moves each shape."""
    swept: bool
    """Edges checked over their whole motion (:func:`edge_swept`), else at configurations
    ``resolution`` apart (:func:`edge_free`)."""
    runs: np.ndarray
    """The pairs' runs (:func:`~toolkit.collision.bound_kernels.pair_runs`)."""


class Work(NamedTuple):
    """The pre-filter's scratch and the search's counts (one per thread)."""

    q: np.ndarray
    """(nq,) the configuration tested."""
    W: np.ndarray
    """(joints + 1, 15) the frames' placements."""
    P: np.ndarray
    """(S, 12) the shapes' placed boxes."""
    tested: np.ndarray
    """(2,) the configurations tested, and the pair that refused the last one."""
    until: np.ndarray
    """(K,) per pair how far along the edge its last gap keeps it apart (the whole-motion
    certificate: :func:`~toolkit.collision.gap_kernels.pair_gaps`)."""
    rate: np.ndarray
    """(K,) per pair how fast the gap may close [m per unit of motion]."""
    near: np.ndarray
    """(K,) per pair whether it was left to the next test."""


class Trees(NamedTuple):
    """The two trees of :func:`grow` (tree 0 from the start, tree 1 from the goals)."""

    nodes: np.ndarray
    """(2, capacity, n) the nodes' joint values."""
    parent: np.ndarray
    """(2, capacity) each node's parent (-1: a root)."""
    root: np.ndarray
    """(2, capacity) each node's root (the goal it grew from, on tree 1)."""
    near: np.ndarray
    """(2, n, capacity) float32 the nodes' copy joint by joint, for the nearest scans."""
    radius: np.ndarray
    """(2, capacity) each node's domain radius [rad] (inf until blocked)."""
