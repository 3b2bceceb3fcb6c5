"""The planner's tunables in one record (toolkit.planning.PlannerSettings): checked when
made, taken by Robot.plan and plan_values, and acting on the search."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import toolkit
from toolkit.planning import PlannerSettings, plan_values

from .test_planning import UR5, WALL, A, B, free_everywhere


@pytest.mark.parametrize(
    ("field", "value"),
    [("max_edge", 0.0), ("max_edge", float("nan")), ("chunk", 1.5), ("chunk", 0),
     ("search_share", 1.5), ("certain_share", -0.1), ("tries", -1), ("corners", True),
     ("escapes", (0.2, 0.1)), ("escapes", [0.1]), ("directions", ()), ("directions", (16.5,)),
     ("domain", (1.0, 2.0, 0.1)), ("domain", (4.0, 1.0)), ("domain", (4.0, 1.0, 1.0))],
)  # fmt: skip
def test_a_bad_setting_is_refused_naming_its_field(field, value):
    with pytest.raises(toolkit.InvalidParameterError, match=f"PlannerSettings.{field} must be"):
        PlannerSettings(**{field: value})


def test_settings_hold_plain_numbers_and_allow_what_means_none():
    """numpy numbers become Python's (the kernels compile once for them); no escapes, no
    corner cuts and no random shortcut tries are settings too."""
    made = PlannerSettings(chunk=np.int64(4), domain=(4, 1, np.float32(0.5)), escapes=())
    assert type(made.chunk) is int and all(type(x) is float for x in made.domain)
    assert PlannerSettings(corners=0, tries=0).corners == 0


def test_max_edge_bounds_every_edge_the_search_grows():
    """Without shortcuts, consecutive waypoints are at most ``max_edge`` apart (in the
    Euclidean norm of the joint values), and the path is still free."""
    short = PlannerSettings(max_edge=0.2)
    result = UR5.plan(A, B, scene=WALL, seed=1, simplify=False, settings=short)
    assert result.success, result.reason
    steps = [np.linalg.norm(b - a) for a, b in itertools.pairwise(result.values)]
    assert max(steps) <= 0.2 + 1e-12
    assert free_everywhere(UR5, result.path, WALL)
    default = UR5.plan(A, B, scene=WALL, seed=1, simplify=False)
    assert max(np.linalg.norm(b - a) for a, b in itertools.pairwise(default.values)) > 0.2


def test_settings_that_are_not_a_record_are_refused_and_step_warns():
    with pytest.raises(toolkit.InvalidParameterError, match="settings must be a PlannerSettings"):
        UR5.plan(A, B, scene=WALL, settings={"max_edge": 0.2})  # type: ignore[arg-type]
    free = lambda Q: np.zeros(len(Q), dtype=bool)  # noqa: E731
    bounds = (np.full(2, -1.0), np.full(2, 1.0))
    with pytest.warns(DeprecationWarning, match=r"step= is now settings=PlannerSettings\(max_edge"):
        path, _, _ = plan_values(free, np.zeros(2), np.ones((1, 2)) * 0.5, bounds, time_limit=1.0,
                                 seed=0, step=0.1)  # fmt: skip
    assert path is not None


PANDA_BOX = (np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]),
             np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]))  # fmt: skip


def test_the_dynamic_domain_takes_its_radii_from_the_box():
    """On the Panda's joint box the domain's radii are VAMP's 4 and 1 rad; on a box of two
    or three Panda arms (14 and 21 joints, as MBM's two-armed Baxter) the share of uniform
    samples within the first radius of the box's middle holds (a node there is not starved of
    samples), where 4 rad took 4 % of them at 14 joints and 0.03 % at 21."""
    settings = PlannerSettings()
    radius, least, factor = settings.radii(PANDA_BOX)
    assert radius == pytest.approx(4.0, abs=0.01) and least == pytest.approx(1.0, abs=0.02)
    assert factor == settings.domain[2]
    rng = np.random.default_rng(7)
    shares = []
    for arms in (1, 2, 3):
        lo, hi = np.tile(PANDA_BOX[0], arms), np.tile(PANDA_BOX[1], arms)
        samples = lo + (hi - lo) * rng.random((20_000, len(lo)))
        far = np.linalg.norm(samples - (lo + hi) / 2, axis=1)
        shares.append(float(np.mean(far < settings.radii((lo, hi))[0])))
        fixed = float(np.mean(far < 4.0))
        assert arms == 1 or fixed < 0.05  # what radii fixed in radians gave
    assert min(shares) > 0.6, shares
