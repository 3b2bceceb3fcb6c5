"""OMPL's RRT-Connect driven from Python, as the planning benchmarks run it (the peer a
Python user reaches for): its default range and motion check, then its default
simplification, over a box of joint values, a state valid where the caller's check says
so. ``pip install ompl`` (the ``bench`` extra)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

SEEDED: list[bool] = []  # OMPL's generator seeded (once a process: later calls draw on)


def rrt_connect(
    lower: np.ndarray, upper: np.ndarray, start: np.ndarray, goal: np.ndarray,
    valid: Callable[[Any], bool], limit: float,
) -> tuple[np.ndarray | None, float]:  # fmt: skip
    """(the simplified path's values (K, n), or None where OMPL found no exact solution
    within ``limit`` [s]; the seconds it took, simplification included). ``valid`` gets
    OMPL's state (``state[i]``: value i)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    if not SEEDED:
        ou.RNG.setSeed(2026)
        SEEDED.append(True)
    ou.setLogLevel(ou.LOG_ERROR)
    n = len(start)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(lower[i]))
        bounds.setHigh(i, float(upper[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    ss.setStateValidityChecker(valid)
    s, g = space.allocState(), space.allocState()
    for i in range(n):
        s[i], g[i] = float(start[i]), float(goal[i])
    ss.setStartAndGoalStates(s, g)
    ss.setPlanner(og.RRTConnect(ss.getSpaceInformation()))
    t0 = time.perf_counter()
    solved = ss.solve(limit)
    if not solved or not ss.haveExactSolutionPath():
        return None, time.perf_counter() - t0
    ss.simplifySolution()
    seconds = time.perf_counter() - t0
    path = ss.getSolutionPath()
    states = [path.getState(k) for k in range(path.getStateCount())]
    return np.array([[st[i] for i in range(n)] for st in states]), seconds


def plain_free(checker: Any) -> Callable[[np.ndarray], bool]:
    """q -> whether plain Pinocchio (``computeCollisions`` with its default requests, what a
    user writes) finds no contact on the toolkit checker's shapes and pairs: every part of
    it (a scene of more than ``toolkit.collision.parts.PART`` objects is held in several
    models)."""
    import pinocchio as pin

    model = checker.model
    data = model.createData()
    parts = [(geom, geom.createData()) for geom in checker.parts.parts]

    def free(q: np.ndarray) -> bool:
        return not any(pin.computeCollisions(model, data, geom, gdata, q, False)
                       for geom, gdata in parts)  # fmt: skip

    return free
