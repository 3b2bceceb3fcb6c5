"""Point clouds as obstacles (``Scene.add_points``): the obstacle is the union of the cells of
edge ``resolution`` that hold a point. Checked against the same cells added as boxes (the
checker's box route, which shares nothing with the octree), through the batch and single
doors, the planner and the scene file."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import toolkit
from toolkit.collision import MAX_POINTS, Scene
from toolkit.errors import InvalidParameterError

UR5 = toolkit.load_example("ur5")
RES = 0.04


def _wall(n: int = 6000, seed: int = 0) -> np.ndarray:
    """Points of a thin wall in front of the UR5 (x ~ 0.4 m)."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(0.40, 0.43, n), rng.uniform(-0.5, 0.5, n),
                            rng.uniform(0.0, 0.9, n)])  # fmt: skip


def _cells_as_boxes(points: np.ndarray, resolution: float) -> Scene:
    """Every cell of the grid of edge ``resolution`` (cells at whole multiples of it) that
    holds a point, as a box."""
    keys = np.unique(np.floor(points / resolution).astype(np.int64), axis=0)
    scene = Scene()
    for i, k in enumerate(keys):
        scene.add_box(f"cell{i}", [resolution] * 3, (k + 0.5) * resolution)
    return scene


WALL = _wall()
CLOUD = Scene().add_points("wall", WALL, RES)
CELLS = _cells_as_boxes(WALL, RES)


def test_a_point_cloud_is_the_union_of_its_cells():
    Q = UR5.random_q(400, seed=1)
    cloud = np.asarray(UR5.in_collision(Q, CLOUD), dtype=bool)
    cells = np.asarray(UR5.in_collision(Q, CELLS), dtype=bool)
    assert 40 < cloud.sum() < 360  # both answers occur
    np.testing.assert_array_equal(cloud, cells)
    single = [
        UR5.collision_checker(CLOUD).collisions(q) for q in Q[:60]
    ]  # the single door, pair named
    assert [bool(s) for s in single] == cloud[:60].tolist()
    assert any(pair == (pair[0], "wall") for s in single for pair in s)


def test_every_point_is_inside_the_obstacle():
    """A small sphere at any point collides; far from every cell, none does."""
    import coal

    shape = CLOUD.objects[0].shape()
    assert isinstance(shape, coal.OcTree)
    ball = coal.Sphere(1e-4)
    for p in WALL[::500]:
        result = coal.CollisionResult()
        where = coal.Transform3s(np.eye(3), p)
        assert coal.collide(shape, coal.Transform3s(), ball, where, coal.CollisionRequest(), result)
    far = coal.Transform3s(np.eye(3), np.array([0.40 - 1.5 * RES, 0.0, 0.45]))
    result = coal.CollisionResult()
    assert not coal.collide(shape, coal.Transform3s(), ball, far, coal.CollisionRequest(), result)


def test_the_planner_goes_around_a_point_cloud():
    """The straight line crosses the wall; the plan does not, re-checked at 0.25 degree
    steps against the cells as boxes."""
    a = np.array([-1.2, -1.0, 1.5, -1.9, -1.57, 0.0])
    b = np.array([1.2, -1.0, 1.5, -1.9, -1.57, 0.0])
    assert UR5.in_collision(np.linspace(a, b, 40), CLOUD).any()
    result = UR5.plan(a, b, scene=CLOUD, seed=2)
    assert result.success and result.verified, result.reason
    path = result.path
    steps = [path[0]]
    for p, q in itertools.pairwise(path):
        k = max(1, math.ceil(float(np.abs(q - p).max()) / math.radians(0.25)))
        steps += [p + (q - p) * t for t in np.arange(1, k + 1) / k]
    assert not np.asarray(UR5.in_collision(np.array(steps), CELLS), dtype=bool).any()


def test_a_point_cloud_round_trips_through_a_scene_file(tmp_path):
    scene = Scene().add_points("cloud", WALL[:300], 1 / 32, [0.125, 0.0, 0.0]).add_floor()
    path = tmp_path / "scene.json"
    scene.save(path)
    again = Scene.load(path)
    assert again.objects == scene.objects  # the points bit for bit
    np.testing.assert_array_equal(again.objects[0].cloud, WALL[:300])
    assert again.digest() == scene.digest()
    moved = Scene().add_points("cloud", np.add(WALL[:300], [0.125, 0.0, 0.0]), 1 / 32)
    Q = UR5.random_q(100, seed=3)
    np.testing.assert_array_equal(UR5.in_collision(Q, moved), UR5.in_collision(Q, Scene(
        objects=[again.objects[0]])))  # fmt: skip


@pytest.mark.parametrize(
    ("points", "resolution", "message"),
    [
        (np.zeros((5, 2)), 0.01, "shape"),
        (np.zeros((0, 3)), 0.01, "shape"),
        (np.array([[0.0, np.nan, 0.0]]), 0.01, "NaN"),
        (np.zeros((4, 3)), 0.0, "resolution"),
        (np.zeros((4, 3)), float("nan"), "resolution"),
        ("points", 0.01, "points"),
    ],
)
def test_bad_point_clouds_are_refused(points, resolution, message):
    with pytest.raises(InvalidParameterError, match=message):
        Scene().add_points("cloud", points, resolution)


def test_too_many_points_and_a_bad_file_entry_are_refused(monkeypatch):
    from toolkit.collision import scene as scene_module

    monkeypatch.setattr(scene_module, "MAX_POINTS", 10)
    with pytest.raises(InvalidParameterError, match="N <= 10"):
        Scene().add_points("cloud", np.zeros((11, 3)), 0.01)
    data = {"objects": [{"name": "c", "kind": "points", "size": [0.01, 0.02],
                         "points": [[0, 0, 0]]}]}  # fmt: skip
    with pytest.raises(InvalidParameterError, match=r"'c'.*resolution"):
        Scene.from_dict(data)
    assert MAX_POINTS >= 300_000  # a depth camera's frame fits
