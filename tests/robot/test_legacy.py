"""What users wrote before the package had its concept folders still loads: a pickle and a
map store written by the landed version (tests/data/legacy/make.py, commit ba39789)."""

from __future__ import annotations

import pickle
import shutil
from pathlib import Path

import numpy as np
import pytest

import toolkit
from toolkit import maps

LEGACY = Path(__file__).resolve().parents[1] / "data" / "legacy"


def test_objects_pickled_before_the_move_load_and_work():
    objects = pickle.loads((LEGACY / "objects.pkl").read_bytes())
    robot, q = objects["robot"], objects["q"]
    today = toolkit.load("katana_6m180")
    assert isinstance(robot, toolkit.Robot) and robot.joints.names == today.joints.names
    np.testing.assert_array_equal(robot.fk(q), today.fk(q))
    np.testing.assert_allclose(robot.fk(q), objects["fk"], atol=1e-12)
    assert robot.ik(objects["fk"], mask=[1, 1, 1, 1, 1, 0]).success
    layer = objects["layer"]
    assert isinstance(layer, toolkit.backlash.Backlash) and layer.robot == robot
    assert np.all(np.isfinite(layer.fk(q)))
    options = objects["options"]
    assert isinstance(options, toolkit.IKOptions)
    assert (options.tol, options.restarts) == (1e-7, 7)
    assert isinstance(objects["result"], toolkit.IKResult) and objects["result"].success
    assert objects["batch"].success.all()
    scene = objects["scene"]
    assert isinstance(scene, toolkit.Scene) and [o.name for o in scene] == ["table"]
    assert robot.in_collision(q, scene) in (True, False)


def test_objects_pickled_before_the_ik_had_two_rooms_load_and_work():
    """IK objects named by their one-room module paths (toolkit.ik.options, toolkit.ik.chain,
    ...), a structure's family still a plain name then."""
    ur5 = toolkit.load_example("ur5")
    found = ur5.structure
    old_found = type(found)(str(found.family), found.joints, found.reason, found.exact,
                            found.deviation, found.points, found.reversed)  # fmt: skip
    result = ur5.ik(ur5.fk(np.zeros(6)))
    data = pickle.dumps([toolkit.IKOptions(tol=1e-7), result, old_found], protocol=0)
    for new, old in (
        (b"toolkit.ik.numeric.", b"toolkit.ik."),
        (b"toolkit.ik.analytic.", b"toolkit.ik."),
    ):
        data = data.replace(new, old)
    assert b"toolkit.ik.options" in data and b"toolkit.ik.chain" in data
    options, again, structure = pickle.loads(data)
    assert options == toolkit.IKOptions(tol=1e-7) and again.success
    assert structure.family == "three parallel" and type(structure.family) is str
    assert structure.compiled and not structure.places_point
    np.testing.assert_array_equal(structure.points, found.points)


def test_objects_pickled_today_name_the_public_paths():
    robot = toolkit.load("katana_6m180")
    data = pickle.dumps([robot, toolkit.IKOptions(), toolkit.Scene()])
    assert b"toolkit.robot" in data and b"toolkit.robot.model" not in data
    assert pickle.loads(data)[0] == robot


def test_a_map_store_written_before_the_move_resumes_and_reads(tmp_path):
    store = tmp_path / "map.zarr"
    shutil.copytree(LEGACY / "katana_map.zarr", store)
    pytest.importorskip("zarr")
    before = {p: p.stat().st_mtime_ns for p in store.rglob("*") if p.is_file()}
    robot = toolkit.load("katana_6m180")
    again = maps.reachability(
        robot, voxel=0.15, position_only=True, orientations=2, store=str(store),
        collision_free=False, workers=1, resume=True,
    )  # fmt: skip
    expected = np.load(LEGACY / "katana_map_index.npy")
    np.testing.assert_array_equal(again.index, expected)
    after = {p: p.stat().st_mtime_ns for p in store.rglob("*") if p.is_file()}
    assert after == before  # every chunk read back as it was written, none computed again
