"""One vocabulary: the renamed keywords still work for a release, warn naming the new
name, pass their value on under it, and refuse both names at once."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import toolkit
from toolkit import maps
from toolkit.common.renames import RENAMED, renamed

UR5 = toolkit.load_example("ur5")
LAYER = toolkit.backlash.Backlash(toolkit.load("katana_6m180"))
G = np.array([0.3, -1.2, 1.0, -0.5, 0.7, 0.2])


def test_every_renamed_keyword_is_listed():
    assert sorted(RENAMED) == sorted([
        ("toolkit.robot.branches.BranchQueries.ik_all", "q_rest", "q0"),
        ("toolkit.robot.batches.BranchBatches.ik_all_batch", "q_rest", "q0"),
        ("toolkit.maps.reachability", "ik_method", "method"),
        ("toolkit.maps.backlash_accuracy", "ik_method", "method"),
        ("toolkit.maps.inverse.inverse_reachability", "ik_method", "method"),
        ("toolkit.maps.placement.placement", "structure", "reach_map"),
    ])  # fmt: skip


def _warns(new: str):
    return pytest.warns(DeprecationWarning, match=rf"is now {new}=")


def test_the_old_start_keyword_gives_the_same_rows_and_warns_at_the_users_line():
    T = UR5.fk(G)
    with _warns("q0") as caught:
        old = UR5.ik_all(T, q_rest=G)
    assert caught[0].filename == __file__  # the user's line, not the toolkit's
    np.testing.assert_array_equal(old.q, UR5.ik_all(T, q0=G).q)
    with _warns("q0"):
        batch = UR5.ik_all_batch(T[None], q_rest=G)
    np.testing.assert_array_equal(batch.q, UR5.ik_all_batch(T[None], q0=G).q)


@pytest.mark.parametrize(
    "call",
    [
        lambda **k: maps.reachability(UR5, voxel=0.5, **k),
        lambda **k: maps.inverse_reachability(UR5, **k),
        lambda **k: maps.backlash_accuracy(LAYER, voxel=0.5, **k),
    ],
    ids=["reachability", "inverse_reachability", "backlash_accuracy"],
)
def test_the_old_ik_method_keyword_reaches_the_new_one(call):
    """A bad value under the old name is refused by the new name's check: the value was
    passed on (before any work)."""
    with _warns("method"), pytest.raises(toolkit.InvalidParameterError, match="method"):
        call(ik_method="closed")
    with pytest.raises(toolkit.InvalidParameterError, match="give method= only"):
        call(ik_method="auto", method="auto")


def test_the_old_structure_keyword_of_placement_is_the_reach_map():
    tasks = UR5.fk(UR5.random_q(2, seed=1))
    with _warns("reach_map"), pytest.raises(toolkit.InvalidParameterError):
        maps.placement(UR5, tasks, [[0, 0], [1, 1]], structure="not a reach map")
    with pytest.raises(toolkit.InvalidParameterError, match="give reach_map= only"):
        maps.placement(UR5, tasks, [[0, 0], [1, 1]], structure=False, reach_map=False)


def test_the_new_names_do_not_warn_and_the_signature_shows_them():
    import inspect

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        UR5.ik_all(UR5.fk(G), q0=G)
    assert "q0" in inspect.signature(toolkit.Robot.ik_all).parameters
    assert "q_rest" not in inspect.signature(toolkit.Robot.ik_all).parameters
    assert "reach_map" in inspect.signature(maps.placement).parameters


def test_a_renamed_function_passes_every_other_argument_through():
    @renamed(old="new")
    def f(a: int, *, new: int = 0, other: int = 0) -> tuple[int, int, int]:
        return a, new, other

    assert f(1, new=2, other=3) == (1, 2, 3)
    with _warns("new"):
        assert f(1, old=2, other=3) == (1, 2, 3)
    assert f(1) == (1, 0, 0)
    RENAMED.remove((f"{__name__}.{f.__qualname__}", "old", "new"))
