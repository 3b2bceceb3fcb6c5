"""Inverse reachability and base placement: the symmetries read from the model, the
structure against IK from every branch (exactly at its cell centres), placements verified
and invariant to moving the whole problem, obstacles respected, the fallback without a
structure, the backlash score, a damaged store detected, and bad input refused."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import toolkit
from toolkit import maps
from toolkit.errors import InvalidParameterError, MapStoreError
from toolkit.maps import base_pose, scene_from_base

COARSE = {"voxel": 0.1, "angles": 6, "collision_free": False, "workers": 1}


@pytest.fixture(scope="module")
def ur5():
    return toolkit.load_example("ur5")


@pytest.fixture(scope="module")
def coarse(ur5):
    return maps.inverse_reachability(ur5, **COARSE)


def _variant(ur5, tmp_path, joint, old, new):
    """The UR5 with one attribute of one joint changed, loaded from a copy of its URDF."""
    text = ur5.urdf_path.read_text()
    block = re.search(rf'<joint name="{joint}".*?</joint>', text, re.S).group(0)
    assert old in block
    path = tmp_path / f"ur5_{joint}.urdf"
    share = ur5.urdf_path.parents[3]  # .../share/example-robot-data: meshes by absolute path
    text = text.replace(block, block.replace(old, new))
    path.write_text(text.replace("package://example-robot-data/", f"file://{share}/"))
    return toolkit.load_urdf(path)


def _rz(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_symmetries_are_read_from_the_model(ur5, tmp_path):
    sym = maps.symmetries(ur5)
    assert sym.yaw and sym.roll, sym.describe()
    full = 'lower="-6.28318530718" upper="6.28318530718"'
    half = 'lower="-1.5708" upper="1.5708"'
    limited = _variant(ur5, tmp_path, "shoulder_pan_joint", full, half)
    assert not maps.symmetries(limited).yaw
    assert "does not turn fully" in maps.symmetries(limited).yaw_reason
    tilted = _variant(ur5, tmp_path, "shoulder_pan_joint", 'rpy="0.0 0.0 0.0"', 'rpy="0.1 0 0"')
    assert not maps.symmetries(tilted).yaw
    assert "not vertical" in maps.symmetries(tilted).yaw_reason
    shifted = _variant(ur5, tmp_path, "shoulder_pan_joint", 'xyz="0.0 0.0 0.089159"',
                       'xyz="0.05 0.0 0.089159"')  # fmt: skip
    assert "base origin" in maps.symmetries(shifted).yaw_reason
    wrist = _variant(ur5, tmp_path, "wrist_3_joint", full, half)
    assert maps.symmetries(wrist).yaw and not maps.symmetries(wrist).roll
    katana = toolkit.load("katana_6m180")
    assert not maps.symmetries(katana).yaw  # joint 1 turns +-170 degrees
    # a robot without the symmetry gets no reduced structure, with the reason
    for robot in (limited, tilted):
        with pytest.raises(InvalidParameterError, match="no inverse-reachability structure"):
            maps.inverse_reachability(robot, **COARSE)
    with pytest.raises(InvalidParameterError, match="wrist_3_joint does not turn fully"):
        maps.inverse_reachability(wrist, **COARSE)
    assert maps.inverse_reachability(wrist, position_only=True, voxel=0.15, workers=1).reach.any()


def test_the_structure_equals_every_branch_ik_at_its_cell_centres_for_any_yaw_and_roll(ur5, coarse):
    """A pose built from a cell's centre, then turned about the base's z by any angle,
    rolled about the last joint by any angle and seen from any base, is reached exactly
    when the cell says so: the symmetry claims, checked by IK from every branch."""
    rng = np.random.default_rng(3)
    g = coarse.grid
    sym = coarse.symmetry
    tool = np.array(sym.tool_in_joint).reshape(4, 4)
    axis = np.array(sym.roll_axis)
    cells = np.argwhere(np.ones(coarse.reach.shape, dtype=bool))
    cells = cells[rng.choice(len(cells), 400, replace=False)]
    centre = np.array(g.lower) + (cells[:, :3] + 0.5) * g.voxel
    near = g.in_reach(centre)
    cells, centre = cells[near], centre[near]
    theta = (cells[:, 3] + 0.5) * np.pi / coarse.angles
    tasks, bases = [], []
    for c, t in zip(centre, theta, strict=True):
        a = np.array([np.sin(t), 0.0, np.cos(t)])
        R = maps.inverse.axis_frames(a[None])[0] @ maps.inverse.axis_frames(axis[None])[0].T
        roll = np.eye(4)
        roll[:3, :3] = pin.AngleAxis(rng.uniform(-np.pi, np.pi), axis).matrix()  # about the axis
        joint = np.eye(4)
        joint[:3, :3], joint[:3, 3] = R, c
        yaw, base = rng.uniform(-np.pi, np.pi), np.append(rng.uniform(-2, 2, 2), 0.3)
        turn = np.eye(4)
        turn[:3, :3] = _rz(yaw)
        world = base_pose([*base, 0.0]) @ turn @ joint @ roll @ tool
        tasks.append(world)
        bases.append(base)
    tasks, bases = np.array(tasks), np.array(bases)
    pairs = list(zip(bases, tasks, strict=True))
    claimed = np.array([coarse.reaches(b[None], t[None])[0, 0] for b, t in pairs])
    np.testing.assert_array_equal(claimed, coarse.reach[tuple(cells.T)])
    in_base = np.array([np.linalg.inv(base_pose([*b, 0.0])) @ t for b, t in pairs])
    truth = ur5.ik_all_batch(in_base).success.any(axis=1)
    assert claimed.sum() > 20 and (~claimed).sum() > 20  # both answers are exercised
    np.testing.assert_array_equal(claimed, truth)


@pytest.mark.slow
def test_the_structure_agrees_with_ik_on_random_pairs(ur5):
    s = maps.inverse_reachability(ur5, voxel=0.05, angles=12, collision_free=False)
    rng = np.random.default_rng(11)
    T = ur5.fk(ur5.random_q(1500, seed=rng))
    bases = np.column_stack([T[:, :2, 3] + rng.uniform(-0.9, 0.9, (1500, 2)),
                             rng.uniform(-0.3, 0.3, 1500)])  # fmt: skip
    claimed = np.array([s.reaches(b[None], t[None])[0, 0] for b, t in zip(bases, T, strict=True)])
    yaws = rng.uniform(-3, 3, 1500)
    in_base = np.array(
        [np.linalg.inv(base_pose([*b, y])) @ t for b, t, y in zip(bases, T, yaws, strict=True)]
    )
    truth = ur5.ik_all_batch(in_base).success.any(axis=1)
    assert 0.2 < truth.mean() < 0.8  # pairs near the edge of the reach, not trivial ones
    assert (claimed == truth).mean() >= 0.95


def _grasps(n, rng, centre=(1.0, 0.0)):
    T = np.tile(np.eye(4), (n, 1, 1))
    for i in range(n):
        T[i, :3, :3] = _rz(rng.uniform(-np.pi, np.pi)) @ np.diag([1.0, -1.0, -1.0])
    x = centre[0] + rng.uniform(-0.25, 0.25, n)
    y = centre[1] + rng.uniform(-0.2, 0.2, n)
    T[:, :3, 3] = np.column_stack([x, y, rng.uniform(0.05, 0.2, n)])
    return T


def _check_verified(robot, result, scene=None):
    """Every task a returned base claims is reached there, free of collision."""
    assert len(result.bases)
    for base, reached, q, reach in zip(result.bases, result.reached, result.q, result.reach,
                                       strict=True):  # fmt: skip
        assert reach == pytest.approx(reached.mean())
        if not reached.any():
            continue
        world = base_pose(base) @ robot.fk(q[reached])
        np.testing.assert_allclose(world[:, :3, 3], result.tasks[reached, :3, 3], atol=1e-6)
        if not result.position_only:
            np.testing.assert_allclose(world[:, :3, :3], result.tasks[reached, :3, :3], atol=1e-6)
        assert not robot.in_collision(q[reached], scene_from_base(scene, base_pose(base))).any()
        assert robot.joints.within_limits(q[reached][0])


def test_placement_verifies_its_candidates_and_moves_with_the_problem(ur5):
    rng = np.random.default_rng(5)
    tasks = _grasps(20, rng)
    s = maps.inverse_reachability(ur5, voxel=0.08, angles=8, workers=1)
    kwargs = {"step": 0.1, "verify": 4, "reach_map": s}
    first = maps.placement(ur5, tasks, [[0.0, -0.8], [1.6, 0.8]], **kwargs)
    _check_verified(ur5, first)
    assert first.reach[0] == first.reach.max() and first.reach[0] >= 0.9
    assert first.heat.shape == (17, 17) and "inverse reachability" in first.method
    # moving the tasks and the region by the same motion moves the answer with them
    shift = np.eye(4)
    shift[:3, 3] = (0.5, -0.3, 0.0)
    moved = maps.placement(ur5, shift @ tasks, [[0.5, -1.1], [2.1, 0.5]], **kwargs)
    np.testing.assert_array_equal(moved.heat, first.heat)
    np.testing.assert_allclose(moved.bases[:, :2], first.bases[:, :2] + [0.5, -0.3], atol=1e-9)
    np.testing.assert_array_equal(moved.reached, first.reached)
    turn = np.eye(4)
    turn[:3, :3] = _rz(np.pi / 2)
    turned = maps.placement(ur5, turn @ tasks, [[-0.8, 0.0], [0.8, 1.6]], **kwargs)
    np.testing.assert_array_equal(turned.heat, np.rot90(first.heat))
    assert turned.reach[0] == first.reach[0]


@pytest.mark.slow
def test_no_returned_base_collides_with_a_column_at_a_task_it_claims(ur5):
    rng = np.random.default_rng(6)
    tasks = _grasps(15, rng)
    s = maps.inverse_reachability(ur5, voxel=0.08, angles=8, workers=1)
    free = maps.placement(ur5, tasks, [[0.0, -0.8], [1.6, 0.8]], step=0.1, verify=3, reach_map=s)
    bx, by = free.best[:2]
    column = toolkit.Scene().add_cylinder("column", 0.15, 2.0, pose=(bx, by, 1.0))
    column.add_box("wall", (0.05, 3.0, 2.0), pose=(1.0, 0.0, 1.0))  # through the tasks' middle
    placed = maps.placement(ur5, tasks, [[0.0, -0.8], [1.6, 0.8]], step=0.1, verify=6,
                            reach_map=s, scene=column)  # fmt: skip
    _check_verified(ur5, placed, column)
    assert placed.reach[0] <= free.reach[0]
    on_column = np.hypot(placed.bases[:, 0] - bx, placed.bases[:, 1] - by) < 0.15
    assert (placed.reach[on_column] == 0).all()  # a base inside the column reaches nothing


@pytest.mark.slow
def test_without_a_structure_every_candidate_is_solved_by_ik(ur5):
    katana = toolkit.load("katana_6m180")
    rng = np.random.default_rng(2)
    points = katana.fk(katana.random_q(6, seed=rng))[:, :3, 3] + [0.3, 0.1, 0.0]
    result = maps.placement(katana, points, [[0.1, -0.1], [0.5, 0.3]], step=0.1, yaws=4,
                            verify=3)  # fmt: skip
    assert result.method.startswith("IK at every candidate") and "turn fully" in result.method
    assert result.position_only
    _check_verified(katana, result)
    # the structure and brute force agree on the UR5's best reach
    tasks = _grasps(8, np.random.default_rng(9))
    region = [[0.2, -0.4], [1.0, 0.4]]
    brute = maps.placement(ur5, tasks, region, step=0.2, yaws=3, verify=3, reach_map=False)
    fast = maps.placement(ur5, tasks, region, step=0.2, verify=3, voxel=0.06, angles=12)
    assert "IK at every candidate" in brute.method
    assert fast.reach[0] >= brute.reach[0] - 0.13


def test_the_backlash_score_ranks_by_the_tool_error_among_equal_reach():
    from toolkit.papers.backlash import Backlash

    layer = Backlash(toolkit.load("katana_6m180"))
    robot = layer.robot
    rng = np.random.default_rng(4)
    points = robot.fk(robot.random_q(4, seed=rng))[:, :3, 3]
    result = maps.placement(layer, points, [[-0.1, -0.1], [0.1, 0.1]], step=0.1, yaws=2,
                            verify=4, score="backlash", payload=0.5)  # fmt: skip
    _check_verified(robot, result)
    for score, q, reached in zip(result.score, result.q, result.reached,
                                        strict=True):  # fmt: skip
        if reached.any():
            loaded = Backlash(robot, layer.delta, layer.k_h, layer.nominal_torque, 0.5)
            out = loaded.solve(q[reached])
            err = np.linalg.norm(robot.fk(out.theta)[:, :3, 3] - robot.fk(q[reached])[:, :3, 3],
                                 axis=1)  # fmt: skip
            assert score == pytest.approx(err.mean(), rel=1e-9)
    order = [(-r, s) for r, s in zip(result.reach, result.score, strict=True)]
    assert order == sorted(order)


def test_a_damaged_structure_store_is_detected_and_resumed(ur5, tmp_path):
    store = tmp_path / "inverse.zarr"
    kwargs = {"voxel": 0.15, "angles": 4, "collision_free": False, "chunk": 4}
    first = maps.inverse_reachability(ur5, store=store, **kwargs)
    files = sorted(p for p in (store / "reach").rglob("*") if p.is_file() and "zarr" not in p.name
                   and not p.name.startswith("."))  # fmt: skip
    assert files
    files[len(files) // 2].write_bytes(b"\x00garbage\xff" * 9)
    with pytest.raises(MapStoreError):
        maps.inverse_reachability(ur5, store=store, **kwargs)
    again = maps.inverse_reachability(ur5, store=store, resume=True, **kwargs)
    assert again.figures["chunks"] >= 1
    np.testing.assert_array_equal(again.reach, first.reach)
    with pytest.raises(MapStoreError):  # another structure's settings: refused, never mixed
        maps.inverse_reachability(ur5, store=store, resume=True, **{**kwargs, "angles": 5})


@pytest.mark.parametrize(
    ("tasks", "region", "extra", "message"),
    [
        (np.zeros((0, 4, 4)), [[0, 0], [1, 1]], {}, "N >= 1"),
        (np.full((2, 3), np.nan), [[0, 0], [1, 1]], {}, "NaN"),
        (np.ones((2, 4)), [[0, 0], [1, 1]], {}, "shape"),
        (np.tile(2 * np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {}, "rotation"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [0, 1]], {}, "zero area"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0, 0], [1, 1, 1]], {}, "region"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"score": "speed"}, "score"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"score": "backlash"}, "Backlash"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"step": 0.0}, "step"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"yaws": 0}, "yaws"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"reach_map": 3}, "InverseReach"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"scene": "cell.json"}, "Scene"),
        (np.tile(np.eye(4), (2, 1, 1)), [[0, 0], [1, 1]], {"frame": "nowhere"}, "nowhere"),
    ],
)
def test_bad_placement_input_is_refused(ur5, tasks, region, extra, message):
    with pytest.raises(toolkit.ToolkitError, match=message):
        maps.placement(ur5, tasks, region, **extra)


def test_a_structure_for_other_tasks_is_refused(ur5, coarse):
    with pytest.raises(InvalidParameterError, match=r"tasks must be \(N, 4, 4\)"):
        coarse.reaches([[0.0, 0.0, 0.0]], [[0.5, 0.0, 0.3]])
    with pytest.raises(InvalidParameterError, match="bases"):
        coarse.reaches([[0.0, 0.0]], np.eye(4)[None])
    with pytest.raises(InvalidParameterError, match="structure is for poses"):
        maps.placement(ur5, np.zeros((2, 3)), [[0, 0], [1, 1]], reach_map=coarse)


def test_the_placement_figure_has_units_and_equal_axes(ur5, coarse, tmp_path):
    tasks = _grasps(5, np.random.default_rng(1))
    result = maps.placement(ur5, tasks, [[0.2, -0.4], [1.0, 0.4]], step=0.1, verify=2,
                            reach_map=coarse)  # fmt: skip
    ax = result.draw(tmp_path / "place.png")
    assert (tmp_path / "place.png").stat().st_size > 10_000
    assert ax.get_xlabel() == "base x [m]" and ax.get_ylabel() == "base y [m]"
    assert ax.get_aspect() == 1.0
    assert "[%]" in ax.figure.axes[-1].get_ylabel()


def test_a_region_from_which_nothing_is_reached_says_so(ur5, coarse):
    far = _grasps(3, np.random.default_rng(8), centre=(5.0, 0.0))
    with pytest.warns(toolkit.UnreachableTargetsWarning, match="no candidate base"):
        result = maps.placement(ur5, far, [[0.0, -0.2], [0.2, 0.2]], step=0.1, verify=2,
                                reach_map=coarse)  # fmt: skip
    assert (result.reach == 0).all() and not result.reached.any()


def test_a_store_folder_builds_the_structure_once_and_reads_it_back(ur5, tmp_path, monkeypatch):
    """``reach_map=FOLDER``: the first placement builds the structure into the folder, the
    next one computes no chunk (the build is replaced by a trap) and ranks the same bases;
    a store made with other settings is refused, never mixed."""
    from toolkit.maps import run

    rng = np.random.default_rng(8)
    tasks = ur5.fk(ur5.random_q(4, seed=rng))[:, :3, 3] + [0.3, 0.0, 0.0]
    store = tmp_path / "reach.zarr"
    kw = {"step": 0.2, "verify": 2, "voxel": 0.15, "collision_free": False, "reach_map": store}
    first = maps.placement(ur5, tasks, [[0.0, -0.2], [0.4, 0.2]], **kw)
    assert (store / "reach").is_dir()

    def trap(*args, **kwargs):
        raise AssertionError("a chunk was computed again")

    monkeypatch.setitem(run._KINDS, "inverse_reachability", trap)
    again = maps.placement(ur5, tasks, [[0.0, -0.2], [0.4, 0.2]], **kw)
    np.testing.assert_array_equal(again.heat, first.heat)
    np.testing.assert_array_equal(again.bases, first.bases)
    with pytest.raises(MapStoreError, match="another map"):
        maps.placement(ur5, tasks, [[0.0, -0.2], [0.4, 0.2]], **{**kw, "voxel": 0.2})
    with pytest.raises(InvalidParameterError, match="text is not taken for a folder"):
        maps.placement(ur5, tasks, [[0.0, -0.2], [0.4, 0.2]], **{**kw, "reach_map": "reach"})
    assert not (tmp_path / "reach").exists() and not Path("reach").exists()
