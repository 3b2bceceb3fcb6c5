"""Plans whose answer is known: a block slid in the plane by two prismatic joints, through
the one gap of a wall, out of a cage by its one exit, and not at all to a goal shut in a
box. Every path is checked again densely by coal on every pair, and where it crosses the
wall or the cage's side it must be inside the opening."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import toolkit

from .test_planning import dense

HALF = 0.05  # [m] the block's half side

URDF = f"""<robot name="slider">
  <link name="base"/>
  <link name="carriage"/>
  <link name="block">
    <collision><geometry><box size="{2 * HALF} {2 * HALF} {2 * HALF}"/></geometry></collision>
  </link>
  <joint name="x" type="prismatic"><parent link="base"/><child link="carriage"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="y" type="prismatic"><parent link="carriage"/><child link="block"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""

SLIDER = toolkit.load_urdf(URDF, tip="block")
GAP = (0.3, 0.6)  # [m] the opening's y range


def _wall(scene: toolkit.Scene, name: str, x: float, y0: float, y1: float) -> toolkit.Scene:
    """A wall 4 cm thick at x from y0 to y1, 0.4 m high about the plane of motion."""
    return scene.add_box(name, [0.04, y1 - y0, 0.4], [x, (y0 + y1) / 2, 0.0])


def _free_densely(scene: toolkit.Scene, path: np.ndarray) -> bool:
    return all(not SLIDER.collision_checker(scene).collisions(q) for q in dense(path, 0.002))


def _crossings(path: np.ndarray, x: float) -> list[float]:
    """The block's y where the path crosses the line x (its centre's)."""
    out = []
    for a, b in itertools.pairwise(path):
        if (a[0] - x) * (b[0] - x) < 0:
            t = (x - a[0]) / (b[0] - a[0])
            out.append(float(a[1] + t * (b[1] - a[1])))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_path_goes_through_the_one_gap_in_the_wall(seed):
    wall = _wall(toolkit.Scene(), "below", 0.0, -1.2, GAP[0])
    wall = _wall(wall, "above", 0.0, GAP[1], 1.2)
    start, goal = np.array([-0.5, -0.5]), np.array([0.5, -0.5])
    result = SLIDER.plan(start, goal, scene=wall, seed=seed)
    assert result.success and result.swept, result.reason
    assert _free_densely(wall, result.path)
    crossings = _crossings(result.path, 0.0)
    assert len(crossings) % 2 == 1
    for y in crossings:
        assert GAP[0] + HALF <= y <= GAP[1] - HALF


def test_the_path_leaves_the_cage_by_its_one_exit():
    # a square cage about the origin, 0.8 m wide, open on its right side between GAP
    cage = _wall(toolkit.Scene(), "left", -0.4, -0.42, 0.42)
    cage = cage.add_box("bottom", [0.84, 0.04, 0.4], [0.0, -0.4, 0.0])
    cage = cage.add_box("top", [0.84, 0.04, 0.4], [0.0, 0.4, 0.0])
    cage = _wall(cage, "right low", 0.4, -0.42, 0.1)
    cage = _wall(cage, "right high", 0.4, 0.3, 0.42)
    start, goal = np.array([0.0, -0.2]), np.array([0.8, -0.8])
    result = SLIDER.plan(start, goal, scene=cage, seed=4)
    assert result.success, result.reason
    assert _free_densely(cage, result.path)
    for y in _crossings(result.path, 0.4):
        assert 0.1 + HALF <= y <= 0.3 - HALF


def test_a_goal_shut_in_a_box_is_not_reached_and_the_plan_says_so_in_time():
    box = _wall(toolkit.Scene(), "west", 0.4, 0.3, 0.9)
    box = _wall(box, "east", 0.8, 0.3, 0.9)
    box = box.add_box("south", [0.44, 0.04, 0.4], [0.6, 0.3, 0.0])
    box = box.add_box("north", [0.44, 0.04, 0.4], [0.6, 0.9, 0.0])
    start, goal = np.array([-0.5, -0.5]), np.array([0.6, 0.6])
    limit = 1.0
    result = SLIDER.plan(start, goal, scene=box, seed=0, time_limit=limit)
    assert not result.success and result.goal == -1 and result.path.shape == (0, 2)
    assert "no path found within" in result.reason
    assert result.time_s < limit + 0.5 and result.nodes > 10
    assert math.isfinite(result.time_s)
