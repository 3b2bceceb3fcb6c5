"""Scenes of thousands of objects: ``Robot.plan``'s ``time_limit`` bounds the building of
the scene's checker too (held in parts, 20,000 boxes within the Panda's reach take about
2 s to build; in one Pinocchio ``GeometryModel`` 5,000 took 77 s)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import toolkit
from toolkit.collision import Checker, CheckerTimeout
from toolkit.robot import plans

# the scenes benchmarks/scene_scale.py measures: 1 cm boxes 0.6-1.1 m from the arm's axis
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from scene_scale import boxes

PANDA = toolkit.load_example("panda")
START = PANDA.states["default"]


def test_a_5000_box_scene_is_stopped_at_the_time_limit(monkeypatch):
    """The build asks the plan's clock between objects: a clock that passes the limit at
    its 400th reading stops it there; the plan fails saying so, and keeps no checker."""
    scene = boxes(5000)
    readings = iter(np.arange(100_000) * 0.0025)  # 1 s passed at the 400th
    monkeypatch.setattr(plans, "_spent", lambda clock: float(next(readings)))
    result = PANDA.plan(START, START + 0.1, scene=scene, time_limit=1.0)
    assert not result.success and result.path.shape == (0, PANDA.nq)
    assert "the scene's checker was stopped at its time limit" in result.reason
    done = int(result.reason.split("limit, ")[1].split(" of 5000")[0])
    assert 300 < done < 420, result.reason  # a few readings go to the start's checks
    assert scene.digest() not in PANDA._caches.checkers


def test_a_20000_box_scene_on_the_real_clock_returns_at_its_limit():
    """Without a stand-in clock: the plan returns, failing, naming how far the build got
    (building all 20,000 takes seconds; the limit is a fifth of one)."""
    result = PANDA.plan(START, START + 0.1, scene=boxes(20_000), time_limit=0.2)
    assert not result.success
    assert "objects in" in result.reason and "of 20000" in result.reason


def test_a_checker_asked_to_stop_keeps_nothing():
    """``until`` True at once: no object added; the error says which robot and how many."""
    with pytest.raises(CheckerTimeout, match=r"panda: .* 0 of 3 objects in"):
        Checker(PANDA, boxes(3), until=lambda: True)
    assert isinstance(CheckerTimeout("x"), TimeoutError)
