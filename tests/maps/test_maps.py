"""Workspace maps: reachability against brute force and independent FK, backlash errors
against Backlash directly, the distributed path, kill-and-resume, store refusals."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pinocchio as pin
import pytest

import toolkit
from toolkit import backlash, maps, structures
from toolkit.errors import InvalidParameterError, MapStoreError
from toolkit.maps import compute

zarr = pytest.importorskip("zarr", reason="the maps extra is in the test extra")


@pytest.mark.parametrize("name", ["cylindrical", "scara", "cartesian"])
def test_position_only_index_is_the_closed_form_membership(name):
    """Brute force on [P3]'s structures: a voxel centre is reachable exactly when the
    closed-form IK has a solution within the limits."""
    robot = toolkit.load(name)
    result = maps.reachability(robot, voxel=0.1, position_only=True, chunk=4)
    assert result.orientations.shape == (1, 3, 3)
    centres = result.centers.reshape(-1, 3)
    # the map solves for the tool frame origin: rho = 0 (not [P3]'s point M)
    truth = np.array([bool(structures.closed_form_ik(robot, c, np.zeros(3))) for c in centres])
    index = result.index.reshape(-1)
    assert truth.sum() > 50 and (~truth).sum() > 50
    np.testing.assert_array_equal(index == 1.0, truth)
    assert set(np.unique(index)) <= {0.0, 1.0}


def _pose_in(robot, q, frame=None):
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.frames.id(frame)]


def test_reachable_voxels_carry_a_q_that_lands_there_in_that_orientation():
    robot = toolkit.load_example("ur5")
    bounds = [[0.2, -0.3, 0.0], [0.6, 0.1, 0.4]]
    result = maps.reachability(robot, voxel=0.2, orientations=6, bounds=bounds, chunk=1)
    assert result.index.shape == (2, 2, 2) and result.orientations.shape == (6, 3, 3)
    R = result.orientations
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.tile(np.eye(3), (6, 1, 1)), atol=1e-12)
    reached = result.index > 0
    assert reached.sum() >= 6
    for ijk in np.argwhere(reached):
        i = tuple(ijk)
        pose = _pose_in(robot, result.best_q[i])  # Pinocchio directly, not the engine
        np.testing.assert_allclose(pose.translation, result.centers[i], atol=1e-6)
        np.testing.assert_allclose(pose.rotation, result.best_rotation[i], atol=1e-6)
        assert any(np.allclose(result.best_rotation[i], R) for R in result.orientations)
        assert robot.joints.within_limits(result.best_q[i])
    assert np.isnan(result.best_q[~reached]).all()
    # brute force: single solves from the same voxel solution count at least as many
    # orientations (the map's budget gives a lower bound)
    for ijk in np.argwhere(reached)[:3]:
        i = tuple(ijk)
        count = 0
        for R in result.orientations:
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = R, result.centers[i]
            count += robot.ik(T, result.best_q[i], restarts=30, method="numeric").success
        assert count >= round(result.index[i] * 6)


def test_backlash_map_values_are_backlash_fk_errors_recomputed_directly():
    layer = backlash.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    bounds = [[0.2, -0.1, 0.1], [0.5, 0.2, 0.4]]
    result = maps.backlash_accuracy(
        layer, voxel=0.15, orientations=4, position_only=True, payloads=(0.0, 0.5),
        k_h=[3.0, 8.0], compensate=True, bounds=bounds, chunk=2,
    )  # fmt: skip
    assert result.mean.shape == (2, 2, 2, 2, 2)
    grid = result.grid
    settings = compute.ReachSettings(
        np.eye(3)[None], True, None, None, maps.MAP_OPTIONS, 0, starts=4, collision_free=True
    )  # the map's default: only self-collision-free solutions count
    checked = 0
    for idx in grid.chunk_ids():
        _, _, success, qs, _ = compute._solutions(layer.robot, grid, idx, settings)
        s = grid.slices(idx)
        cells = np.argwhere(np.ones(grid.chunk_centers(idx).shape[:3], dtype=bool))
        for flat, (a, b, c) in enumerate(cells):
            voxel = (s[0].start + a, s[1].start + b, s[2].start + c)
            q = qs[flat][success[flat]]
            if not len(q):
                assert np.isnan(result.mean[(0, 0, *voxel)])
                continue
            for p, payload in enumerate((0.0, 0.5)):
                for h, k_h in enumerate((3.0, 8.0)):
                    direct = backlash.Backlash(
                        layer.robot, layer.delta, k_h, layer.nominal_torque, payload
                    )
                    errors = np.linalg.norm(
                        direct.fk(q)[:, :3, 3] - layer.robot.fk(q)[:, :3, 3], axis=1
                    )
                    at = (p, h, *voxel)
                    assert result.mean[at] == pytest.approx(errors.mean(), abs=1e-12)
                    assert result.p95[at] == pytest.approx(np.percentile(errors, 95), abs=1e-12)
                    assert result.max[at] == pytest.approx(errors.max(), abs=1e-12)
                    checked += 1
    assert checked >= 8
    # heavier payload, larger error; compensation puts the tool back (where it can)
    assert np.nanmean(result.mean[1]) > np.nanmean(result.mean[0])
    assert np.nanmax(result.compensated_max) < 1e-9
    assert np.nanmin(result.mean[1]) > 1e-4


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as c,
        distributed.Client(c) as client,
    ):
        yield client


@pytest.mark.slow
def test_the_distributed_path_writes_the_same_store(cluster, tmp_path):
    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.25, "orientations": 5, "chunk": 2}
    here = maps.reachability(robot, store=tmp_path / "here.zarr", **kwargs)
    there = maps.reachability(robot, store=tmp_path / "there.zarr", client=cluster, **kwargs)
    for name in ("index", "best_q", "best_rotation"):
        a = zarr.open_group(str(tmp_path / "here.zarr"))[name][...]
        b = zarr.open_group(str(tmp_path / "there.zarr"))[name][...]
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(here.index, there.index)
    assert here.index.max() > 0.5


@pytest.mark.slow
def test_an_inverse_reachability_structure_is_the_same_on_a_cluster(cluster, tmp_path):
    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.15, "angles": 4, "chunk": 3}
    here = maps.inverse_reachability(robot, workers=1, **kwargs)
    there = maps.inverse_reachability(robot, client=cluster, store=tmp_path / "s.zarr", **kwargs)
    np.testing.assert_array_equal(here.reach, there.reach)
    assert here.reach.any() and there.figures["workers"] == 2
    again = maps.inverse_reachability(robot, store=tmp_path / "s.zarr", resume=True, **kwargs)
    assert again.figures["chunks"] == 0  # a finished structure is read back, not recomputed
    np.testing.assert_array_equal(again.reach, here.reach)


_KILLED = """
import sys, toolkit
from toolkit import maps
maps.reachability(toolkit.load_example("ur5"), voxel=0.12, orientations=8, chunk=3,
                  store=sys.argv[1], progress=True)
"""


def _children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return [int(p) for p in fh.read().split()]
    except OSError:
        return []


@pytest.mark.slow
def test_a_killed_run_resumes_to_the_uninterrupted_result(tmp_path):
    store = tmp_path / "killed.zarr"
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED, str(store)], stderr=subprocess.PIPE, text=True
    )
    deadline = time.time() + 120
    done = 0
    while time.time() < deadline and proc.poll() is None:
        try:
            done = int(np.asarray(zarr.open_group(str(store), mode="r")["done"][...]).sum())
        except Exception:
            done = 0
        if done >= 4:
            break
        time.sleep(0.05)
    assert proc.poll() is None, f"the run ended before it could be killed: {proc.stderr.read()}"
    assert not _children(proc.pid), "the local pool is threads: no process to outlive the run"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    total = int(np.prod(zarr.open_group(str(store), mode="r")["done"].shape))
    assert 4 <= done < total
    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.12, "orientations": 8, "chunk": 3}
    with pytest.raises(MapStoreError, match="resume"):
        maps.reachability(robot, store=store, **kwargs)
    resumed = maps.reachability(robot, store=store, resume=True, **kwargs)
    assert resumed.figures["chunks"] < total  # the written chunks were kept
    whole = maps.reachability(robot, **kwargs)
    np.testing.assert_array_equal(resumed.index, whole.index)
    np.testing.assert_array_equal(resumed.best_q, whole.best_q)
    np.testing.assert_array_equal(resumed.best_rotation, whole.best_rotation)


def test_a_store_of_another_map_is_refused(tmp_path):
    robot = toolkit.load_example("ur5")
    store = tmp_path / "one.zarr"
    maps.reachability(robot, voxel=0.4, orientations=3, store=store)
    for other, word in (
        ({"seed": 1}, "seed"),
        ({"orientations": 4}, "orientations"),
        ({"voxel": 0.3}, r"grid.voxel: the store was made with 0.4, this run asks 0.3"),
    ):
        kwargs = {"voxel": 0.4, "orientations": 3, **other}
        with pytest.raises(MapStoreError, match=word):
            maps.reachability(robot, store=store, resume=True, **kwargs)
    with pytest.raises(MapStoreError, match="robot"):
        maps.reachability(
            toolkit.load_example("ur3"), voxel=0.4, orientations=3, store=store, resume=True
        )
    again = maps.reachability(robot, voxel=0.4, orientations=3, store=store, resume=True)
    assert again.figures["chunks"] == 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"voxel": 0}, "voxel"),
        ({"voxel": 0.1, "orientations": 0}, "orientations"),
        ({"voxel": 0.1, "bounds": [[0, 0, 0], [0, 1, 1]]}, "upper corner"),
        ({"voxel": 0.0005}, "voxels"),
        ({"voxel": 0.1, "resume": True}, "resume needs the store"),
        ({"voxel": 0.1, "client": "tcp://x"}, "dask.distributed.Client"),
        ({"voxel": 0.1, "frame": "nope"}, "unknown frame"),
    ],
)
def test_bad_map_input_is_refused(kwargs, message):
    with pytest.raises(toolkit.ToolkitError, match=message):
        maps.reachability(toolkit.load_example("ur5"), **kwargs)


def test_bad_accuracy_input_is_refused():
    layer = backlash.Backlash(toolkit.load("katana_6m180"))
    with pytest.raises(InvalidParameterError, match="Backlash layer"):
        maps.backlash_accuracy(toolkit.load("katana_6m180"), voxel=0.1)
    with pytest.raises(InvalidParameterError, match="payloads"):
        maps.backlash_accuracy(layer, voxel=0.1, payloads=(-1.0,))
    with pytest.raises(InvalidParameterError, match="k_h"):
        maps.backlash_accuracy(layer, voxel=0.1, k_h=[])


def test_orientations_are_spread_evenly():
    R = maps.spread_orientations(200)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    approach = R[:, :, 2]
    assert abs(approach.mean(axis=0)).max() < 0.02  # balanced over the sphere
    nearest = np.sort(approach @ approach.T, axis=1)[:, -2]  # cos to the nearest other
    assert np.degrees(np.arccos(nearest.max())) > 8  # no two nearly equal


def test_slices_have_units_equal_scales_and_a_colour_bar():
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    robot = toolkit.load("scara")
    result = maps.reachability(robot, voxel=0.1, position_only=True)
    axes = maps.draw_slices(result, heights=[0.1, 0.2])
    assert len(axes) == 3 and all(ax.get_aspect() == 1.0 for ax in axes)
    assert [ax.get_xlabel() for ax in axes] == ["x [m]"] * 3
    assert axes[0].get_ylabel() == "z [m]" and axes[1].get_ylabel() == "y [m]"
    bar = axes[0].figure.axes[-1]
    assert "reachability index" in bar.get_ylabel()


_PLAIN_SCRIPT = """
import numpy as np, toolkit
from toolkit import maps
m = maps.reachability(toolkit.load_example("ur5"), voxel=0.15, orientations=4, chunk=2)
print("RESULT", m.figures["workers"], m.figures["chunks"], int(m.figures["solves"]),
      int((m.index > 0).sum()))
"""


@pytest.mark.slow
@pytest.mark.parametrize("how", ["stdin", "script"])
def test_a_map_from_a_plain_script_without_a_main_guard(tmp_path, how):
    """The audit's case: the local pool spawned processes that re-imported the script.
    The local pool is threads now: stdin and a script without a main guard both work, on
    every core, and give the same map as one thread."""
    if how == "stdin":
        out = subprocess.run(
            [sys.executable, "-"], input=_PLAIN_SCRIPT, capture_output=True, text=True,
            timeout=600,
        )  # fmt: skip
    else:
        script = tmp_path / "plain.py"
        script.write_text(_PLAIN_SCRIPT)
        out = subprocess.run(
            [sys.executable, str(script)], capture_output=True, text=True, timeout=600
        )
    assert out.returncode == 0, out.stderr[-3000:]
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT")][-1].split()
    workers, chunks, solves, reached = float(line[1]), float(line[2]), int(line[3]), int(line[4])
    assert workers == min(os.cpu_count() or 1, chunks) or workers == (os.cpu_count() or 1)
    robot = toolkit.load_example("ur5")
    alone = maps.reachability(robot, voxel=0.15, orientations=4, chunk=2, workers=1)
    assert reached == int((alone.index > 0).sum()) and solves == alone.figures["solves"]


def test_the_solves_reported_are_the_solves_run():
    """A voxel whose position is not reached runs no orientation solve: the figures count
    the ik_batch targets actually solved, checked against a count made here."""
    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.2, "orientations": 5, "chunk": 2, "method": "numeric"}
    m = maps.reachability(robot, workers=2, **kwargs)
    alone = maps.reachability(robot, workers=1, **kwargs)
    np.testing.assert_array_equal(m.index, alone.index)
    np.testing.assert_array_equal(m.best_q, alone.best_q)
    centres = m.grid.centers().reshape(-1, 3)
    near = int(m.grid.in_reach(centres).sum())
    positions = maps.reachability(robot, position_only=True, voxel=0.2, chunk=2)
    reached = int((positions.index > 0).sum())  # same first stage (same seeds, same budget)
    assert m.figures["solves"] == near + reached * 5
    assert m.figures["solves"] < near * 6  # not the upper bound the old figure claimed
    exact = maps.reachability(robot, workers=1, **{**kwargs, "method": "auto"})
    assert exact.figures["solves"] == near * 5  # every orientation of every voxel in reach


def _chunk_files(store, name: str) -> list:
    return sorted(p for p in (store / name / "c").rglob("*") if p.is_file())


@pytest.mark.slow
def test_a_damaged_store_is_detected_and_resume_recomputes_it(tmp_path):
    """A deleted chunk (read back as fill values), a chunk copied from another map and
    corrupt bytes: never read as data; resume recomputes exactly those chunks."""
    from toolkit.maps.store import Store

    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.25, "orientations": 3, "chunk": 2}
    store, other = tmp_path / "map.zarr", tmp_path / "other.zarr"
    first = maps.reachability(robot, store=store, **kwargs)
    maps.reachability(robot, store=other, seed=5, **kwargs)
    files = _chunk_files(store, "index")
    assert len(files) >= 4
    files[0].unlink()  # deleted
    copied = _chunk_files(other, "best_q")
    target = store / "best_q" / copied[1].relative_to(other / "best_q")
    differs = target.read_bytes() != copied[1].read_bytes()
    target.write_bytes(copied[1].read_bytes())  # copied from another map
    files[2].write_bytes(b"\x00garbage\xff" * 7)  # corrupt bytes
    group = zarr.open_group(str(store), mode="a")
    saved = object.__new__(Store)
    saved.group, saved.grid = group, first.grid
    damaged = saved.damaged()
    assert len(damaged) == 2 + differs
    with pytest.raises(MapStoreError, match=r"damaged: \d chunk\(s\)"):
        saved.check()
    with pytest.raises(MapStoreError, match=r"damaged: \d chunk\(s\)"):
        saved.read_checked()  # what a run reads at its end: the same chunks are named
    again = maps.reachability(robot, store=store, resume=True, **kwargs)
    assert again.figures["chunks"] == len(damaged)
    np.testing.assert_array_equal(again.index, first.index)
    np.testing.assert_array_equal(again.best_q, first.best_q)
    assert not saved.damaged()


def test_every_input_that_changes_a_map_is_part_of_its_identity(tmp_path):
    """The audit's two misses: a position-only map ignored its mask, and a position-only
    accuracy map resumed with other ``orientations`` returned the old map."""
    robot = toolkit.load_example("ur5")
    kwargs = {"voxel": 0.3, "position_only": True}
    full = maps.reachability(robot, **kwargs)
    planar = maps.reachability(robot, mask=[1, 1, 0, 0, 0, 0], **kwargs)
    centres = full.grid.centers().reshape(-1, 3)
    near = full.grid.in_reach(centres)
    direct = robot.ik_batch(centres[near], mask=[1, 1, 0, 0, 0, 0], seed=0, restarts=8)
    assert planar.index.sum() > full.index.sum()  # x, y alone reach more voxels
    assert planar.index.ravel()[near].astype(bool).sum() >= direct.success.sum() * 0.95
    store = tmp_path / "m.zarr"
    maps.reachability(robot, store=store, **kwargs)
    with pytest.raises(MapStoreError, match="mask"):
        maps.reachability(robot, store=store, resume=True, mask=[1, 1, 0, 0, 0, 0], **kwargs)
    layer = backlash.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    acc = tmp_path / "acc.zarr"
    args = {"voxel": 0.25, "position_only": True, "store": acc}
    maps.backlash_accuracy(layer, orientations=2, **args)
    with pytest.raises(MapStoreError, match="starts"):
        maps.backlash_accuracy(layer, orientations=3, resume=True, **args)


@pytest.mark.slow
def test_the_floor_removes_every_below_floor_voxel_from_the_katana_map(tmp_path):
    """The collision issue's case: the Katana's map counted voxels 35 cm below the floor it
    stands on. By default (self-collision, with the floor of its template) no voxel below
    it is reached; ``collision_free=False`` maps the arm alone in space."""
    robot = toolkit.load("katana_6m180")
    kwargs = {"voxel": 0.1, "position_only": True, "chunk": 4}
    bare = maps.reachability(robot, collision_free=False, **kwargs)
    store = tmp_path / "floor.zarr"
    on_floor = maps.reachability(robot, store=store, **kwargs)
    below = on_floor.grid.centers()[..., 2] < 0.0
    assert (bare.index[below] > 0).sum() > 10
    assert not (on_floor.index[below] > 0).any()
    assert (on_floor.index[~below] > 0).sum() > 0.5 * (bare.index[~below] > 0).sum()
    with pytest.raises(MapStoreError, match="collision_free"):
        maps.reachability(robot, store=store, resume=True, collision_free=False, **kwargs)
    cell = toolkit.Scene().add_box("wall", (0.05, 1.0, 1.0), np.eye(4))
    with pytest.raises(MapStoreError, match="scene"):
        maps.reachability(robot, store=store, resume=True, scene=cell, **kwargs)


def test_an_empty_store_path_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(toolkit.MapStoreError, match="empty path"):
        maps.reachability(toolkit.load_example("ur5"), voxel=0.4, orientations=2, store="")
    assert not list(tmp_path.iterdir()), "the working folder was made a store"


def test_a_map_that_could_reach_nothing_is_refused_with_the_advice():
    layer = backlash.Backlash(toolkit.load("katana_6m180"))
    with pytest.raises(toolkit.InvalidParameterError, match="position_only=True") as info:
        maps.backlash_accuracy(layer, voxel=0.12, orientations=6)
    assert "5 independent directions, fewer than the 6" in str(info.value)
    with pytest.raises(toolkit.InvalidParameterError, match="mask"):
        maps.reachability(toolkit.load("katana_6m180"), voxel=0.2, orientations=2)
    # five directions fixed, five moved, but not the same five (the Katana cannot roll its
    # approach out of the vertical plane): the map is empty, and says so
    with pytest.warns(toolkit.UnreachableTargetsWarning, match="no voxel of the map"):
        freed = maps.reachability(
            toolkit.load("katana_6m180"), voxel=0.2, orientations=2, mask=[1, 1, 1, 1, 1, 0],
            collision_free=False, workers=1,
        )  # fmt: skip
    assert np.nanmax(freed.index) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the arm's reach, as docs/maps.md says: no warning
        reach = maps.reachability(
            toolkit.load("katana_6m180"), voxel=0.2, position_only=True, collision_free=False,
            workers=1,
        )  # fmt: skip
    assert np.nanmax(reach.index) == 1


def test_progress_in_a_log_is_a_line_at_every_tenth_and_at_the_end(capsys):
    """Standard error that is not a terminal (a log, CI): no carriage returns, a line at each
    tenth of the work and one at its end, so a build of minutes is not silent."""
    from toolkit.maps.run import Progress

    bar = Progress(20, True, "place", "yaws")
    for _ in range(20):
        bar.step(5)
    bar.close()
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "\r" not in err and len(lines) == 10
    assert lines[-1].startswith("place: 20/20 yaws, 100 IK solves")
    quiet = Progress(20, False)
    quiet.step(1)
    assert capsys.readouterr().err == ""
