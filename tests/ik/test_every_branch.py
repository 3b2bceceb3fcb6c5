"""Every branch where the arm has one: singular poses answered with a representative of each
family of solutions, degenerate geometries named, arms exact to less than ``tol`` polished,
every turn of a joint seen in batches as in ``ik_all``, float targets projected, the base's
own shapes checked against the scene (a support declared), sizes and files refused, and
branches counted as branches. Each is checked against an independent route: Pinocchio's own
forward kinematics, trimesh's inside test on the base mesh, the generating configuration."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from helpers import chain_urdf, same_up_to_turns, unit
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import maps
from toolkit.collision import SUPPORT_SLACK, Scene
from toolkit.errors import (
    InvalidParameterError,
    MapStoreError,
    UnreachableTargetsWarning,
    UnsupportedModelError,
)
from toolkit.maps import scene_from_base

HOME = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])


def pin_pose(robot, q, frame=None):
    """The frame's pose by Pinocchio's own forward kinematics (not the toolkit's back end)."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.asarray(q, dtype=float))
    return data.oMf[robot.frames.id(frame)].homogeneous


def assert_rows_reach(robot, result, T, atol=1e-9):
    assert result.success.any()
    for q in result.q[result.success]:
        np.testing.assert_allclose(pin_pose(robot, q), T, atol=atol)


def has_row(robot, result, q, close=1e-6):
    """Whether a successful row of ``result`` equals q up to whole turns of its joints."""
    want = robot.joints.angles(q)
    return any(same_up_to_turns(robot.joints.angles(row), want, close)
               for row in result.q[result.success])  # fmt: skip


@pytest.fixture(scope="module")
def ur5():
    return toolkit.load_example("ur5")


# ---------------------------------------------------------------- singular poses
def test_the_ur5_home_pose_has_its_branches_with_the_free_joint_named(ur5):
    T = ur5.fk(HOME)
    result = ur5.ik_all(T)
    assert_rows_reach(ur5, result, T)
    assert result.singular.any()
    assert {f for f in result.free if f} == {("wrist_3_joint",)}
    assert has_row(ur5, result, HOME)  # q_rest (mid-range: 0) is the home pose's q6
    assert ur5.ik(T, method="analytic").success


def test_the_ur5_wrist_singularity_keeps_its_generating_configuration(ur5):
    """q5 = 0 (axes 4 and 6 parallel): with the generator as q_rest, the representative of
    its family is the generator itself; with the default, a row of the same shoulder,
    elbow and q5 reaches the target (20 of 20)."""
    for seed in range(20):
        g = ur5.random_q(seed=seed)
        g[4] = 0.0
        T = ur5.fk(g)
        here = ur5.ik_all(T, q0=g)
        assert_rows_reach(ur5, here, T)
        assert has_row(ur5, here, g), seed
        rows = here.q[here.success & here.singular]
        assert len(rows)
        assert np.abs(np.remainder(rows[:, 4] + np.pi, 2 * np.pi) - np.pi).max() < 1e-6
        default = ur5.ik_all(T)
        assert_rows_reach(ur5, default, T)
        assert default.singular[default.success].any()


def test_a_spherical_wrist_singularity_keeps_its_generating_configuration():
    """The Kinova (spherical wrist) with q5 at its aligned angle, axes 4 and 6 on one
    line: q4 is free (its name given), the generator is the representative at q0=g."""
    arm = toolkit.load_example("kinova")
    chain_names = arm.structure.joints
    found = 0
    for seed in range(10):
        g = arm.random_q(seed=seed)
        a = arm.joints.angles(g)
        col = list(arm.structure.joints).index(chain_names[4])
        a[col] = np.pi  # axes 4 and 6 on one line (at q5 = 0 or pi on this arm; 0 is outside)
        g = arm.joints.q_from_angles(a)
        T = arm.fk(g)
        result = arm.ik_all(T, q0=g)
        assert_rows_reach(arm, result, T)
        if result.singular[result.success].any():
            found += 1
            assert has_row(arm, result, g)
            assert chain_names[3] in {j for f in result.free for j in f}
    assert found == 10


def _spherical_wrist_arm(seed: int) -> toolkit.Robot:
    rng = np.random.default_rng(seed)
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[2] = h[1]  # axes 2, 3 parallel
    h[5] = h[3]  # axes 4 and 6 on one line at zero: the wrist is singular at q5 = 0
    o = [rng.normal(size=3) * 0.3 for _ in range(3)]
    w = rng.normal(size=3) * 0.3
    o += [w, w + 0.1 * h[4], w - 0.1 * h[5]]
    return toolkit.load_urdf(chain_urdf(h, o, w + rng.normal(size=3) * 0.1))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_random_spherical_wrist_arm_is_answered_at_its_singularity(seed):
    arm = _spherical_wrist_arm(seed)
    assert arm.structure.family == "spherical wrist" and arm.structure.exact
    for k in range(5):
        g = arm.random_q(seed=k)
        g[4] = 0.0
        T = arm.fk(g)
        result = arm.ik_all(T, q0=g)
        assert_rows_reach(arm, result, T)
        assert has_row(arm, result, g)
        assert ("j4",) in result.free
        batch = arm.ik_all_batch(T[None], q0=g)
        assert batch.success[0].any() and (batch.free[0] == 1 << 3).any()


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda h: h.__setitem__(0, h[1]), "four parallel axes (1-4)"),
        (lambda h: h.__setitem__(4, -h[1]), "four parallel axes (2-5)"),
        (lambda h: h.__setitem__(5, h[4]), "axes 5 and 6 on one line"),
    ],
)  # fmt: skip
def test_degenerate_three_parallel_arms_are_named_not_solved(change, words):
    rng = np.random.default_rng(4)
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[2], h[3] = h[1], -h[1]
    change(h)
    o = [rng.normal(size=3) * 0.3 for _ in range(5)]
    o.append(o[4] - 0.12 * h[4])
    arm = toolkit.load_urdf(chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1))
    found = arm.structure
    assert found.family is None
    assert words in found.reason and "infinitely many solutions" in found.reason
    with pytest.raises(UnsupportedModelError, match="degenerate"):
        arm.ik_all(arm.fk(arm.random_q(seed=1)))
    assert arm.ik(arm.fk(arm.random_q(seed=1)), method="numeric").success  # numeric: one


def test_a_spherical_wrist_with_axis_1_parallel_to_axis_2_is_named():
    rng = np.random.default_rng(6)
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[2] = h[1]
    h[0] = h[1]
    o = [rng.normal(size=3) * 0.3 for _ in range(3)]
    w = rng.normal(size=3) * 0.3
    o += [w, w + 0.2 * h[4], w - 0.1 * h[5]]
    arm = toolkit.load_urdf(chain_urdf(h, o, w + 0.1))
    assert arm.structure.family is None
    assert "axis 1 parallel to axis 2" in arm.structure.reason


# ---------------------------------------------------------------- one tolerance story
def test_an_arm_exact_to_5e_11_is_polished_to_tol():
    """Axis 3 tilted by 5e-11 rad: within the 1e-9 of an exact family, but its branches
    would miss by ~1e-10 m; every reachable target gets its generating configuration."""
    rng = np.random.default_rng(11)
    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[2], h[3] = h[1], -h[1]
    tilt = unit(np.cross(h[1], rng.normal(size=3)))
    h[2] = unit(h[1] + 5e-11 * tilt)
    o = [rng.normal(size=3) * 0.4 for _ in range(5)]
    o.append(o[4] - 0.12 * h[4])
    arm = toolkit.load_urdf(chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1))
    assert arm.structure.exact and 1e-12 < arm.structure.deviation < 1e-9
    missing = 0
    for seed in range(60):
        g = arm.random_q(seed=seed)
        T = arm.fk(g)
        result = arm.ik_all(T)
        assert result.polished
        assert_rows_reach(arm, result, T, atol=1e-9)
        missing += not has_row(arm, result, g)
    assert missing == 0
    Ts = arm.fk(arm.random_q(60, seed=99))
    batch = arm.ik_all_batch(Ts)
    assert batch.success.any(axis=1).all()


# ---------------------------------------------------------------- turns in batches
def _one_sided_ur5(ur5) -> toolkit.Robot:
    """The UR5 with joint 1 in -210 deg .. 65 deg and joint 4 in -60 deg .. 300 deg."""
    text = Path(ur5.urdf_path).read_text()

    def limit(joint: str, lo: float, hi: float, text: str) -> str:
        at = text.index(f'<joint name="{joint}"')
        end = text.index("</joint>", at)
        part = re.sub(r'lower="[^"]*" upper="[^"]*"',
                      f'lower="{math.radians(lo)!r}" upper="{math.radians(hi)!r}"',
                      text[at:end])  # fmt: skip
        return text[:at] + part + text[end:]

    text = limit("shoulder_pan_joint", -210, 65, text)
    text = limit("wrist_1_joint", -60, 300, text)
    return toolkit.load_urdf(text, tip="tool0")


def test_ik_all_batch_sees_the_turns_ik_all_lists(ur5):
    arm = _one_sided_ur5(ur5)
    Q = arm.random_q(400, seed=3)
    assert (Q[:, 0] < -np.pi).sum() > 20  # these targets need the turn below -pi
    Ts = arm.fk(Q)
    batch = arm.ik_all_batch(Ts)
    assert batch.success.any(axis=1).all()  # every target from its own q: some branch
    for i in range(0, 400, 20):
        single = arm.ik_all(Ts[i])
        assert batch.success[i].sum() == single.solved
        for q in batch.q[i][batch.success[i]]:  # each verified batch row is an ik_all row
            assert np.abs(single.q[single.success] - q).max(axis=1).min() < 1e-9


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(seed=st.integers(0, 2**31 - 1), singular=st.booleans())
def test_every_verified_batch_row_is_an_ik_all_row(ur5, seed, singular):
    arm = _one_sided_ur5(ur5) if seed % 2 else ur5
    q = arm.random_q(seed=seed)
    if singular:
        q[4] = 0.0
    T = arm.fk(q)
    batch = arm.ik_all_batch(T[None])
    single = arm.ik_all(T)
    assert batch.success[0].sum() == single.solved
    for row in batch.q[0][batch.success[0]]:
        assert np.abs(single.q[single.success] - row).max(axis=1).min() < 1e-9


def test_placement_reaches_a_task_that_needs_a_turn(ur5):
    arm = _one_sided_ur5(ur5)
    q = arm.random_q(seed=5)
    q[0] = -3.4  # beyond -pi: wrapped, it would be outside the limits
    T = arm.fk(q)
    assert arm.ik_all(T).solved
    p = maps.placement(arm, T[None], [[-0.001, -0.001], [0.001, 0.001]], step=0.002, yaws=1,
                       yaw_range=(0, 0), reach_map=False, collision_free=False)  # fmt: skip
    assert p.reach[0] == 1.0


# ---------------------------------------------------------------- targets as users have them
@pytest.mark.parametrize("name", ["ur5", "kinova"])
def test_float32_targets_are_projected_and_solved(name):
    arm = toolkit.load_example(name)
    Q = arm.random_q(100, seed=21)
    solved = 0
    for q in Q:
        T32 = arm.fk(q).astype(np.float32)
        result = arm.ik_all(T32, tol=1e-5)
        assert 0 < result.target_moved < 1e-6
        solved += bool(result.solved)
        R = T32[:3, :3].astype(float)
        for row in result.q[result.success]:  # against the projection: a rotation near R
            P = pin_pose(arm, row)
            assert np.abs(P[:3, :3] - R).max() < 1e-6
            assert np.abs(P[:3, 3] - T32[:3, 3]).max() < 1e-5
    assert solved == 100
    batch = arm.ik_all_batch(arm.fk(Q).astype(np.float32), tol=1e-5)
    assert batch.success.any(axis=1).all() and (batch.target_moved > 0).all()


def test_a_rotation_rounded_beyond_the_check_is_still_refused(ur5):
    T = ur5.fk(ur5.random_q(seed=1))
    T[0, 0] += 1e-3
    with pytest.raises(InvalidParameterError, match="rotation"):
        ur5.ik_all(T)


# ---------------------------------------------------------------- counting
def test_solved_counts_branches_not_rows(ur5):
    T = ur5.fk(ur5.random_q(seed=1))
    result = ur5.ik_all(T, turns=True)
    assert result.solved == len(set(np.asarray(result.labels)[result.success]))
    assert result.rows_solved == int(result.success.sum()) > result.solved
    for b in set(result.branch.tolist()):  # the rows of one branch differ by whole turns
        rows = ur5.joints.angles(result.q[result.branch == b])
        assert all(same_up_to_turns(r, rows[0], 1e-9) for r in rows)
        assert len({result.labels[i] for i in np.flatnonzero(result.branch == b)}) == 1


# ---------------------------------------------------------------- the base in the scene
TABLE = ("table", (0.8, 0.6, 0.4), (0.75, 0.0, 0.2))


def _table_scene(**kw) -> Scene:
    name, size, at = TABLE
    return Scene().add_box(name, size, pose=at, **kw)


def _table_points_in_base(ur5, base) -> int:
    """How many points of a 1 mm grid of the table near the base lie inside the UR5's base
    collision mesh (trimesh's ray test on the STL file: not coal, not Pinocchio), the base
    at ``base`` (x, y, z, yaw)."""
    import trimesh

    mesh = trimesh.load(Path(ur5.urdf_path).parent.parent / "meshes/ur5/collision/base.stl")
    B = maps.base_pose(base)
    _, size, at = TABLE
    lo, hi = np.array(at) - np.array(size) / 2, np.array(at) + np.array(size) / 2
    axes = [np.arange(max(lo[i], B[i, 3] - 0.12), min(hi[i], B[i, 3] + 0.12), 1e-3)
            for i in range(2)]  # fmt: skip
    axes.append(np.arange(max(lo[2], 0.0), min(hi[2], 0.03), 1e-3))
    if min(len(a) for a in axes) == 0:
        return 0
    P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    local = (P - B[:3, 3]) @ B[:3, :3]  # into the base frame
    return int(mesh.contains(local).sum())


def test_the_base_inside_a_table_collides_everywhere(ur5):
    base = np.array([0.30, -0.35, 0.0, 0.0])
    assert _table_points_in_base(ur5, base) > 0  # the independent check: it is inside
    seen = scene_from_base(_table_scene(), base)
    assert list(ur5.collision_checker(seen).base_hits) == [("base_link", "table")]
    assert ur5.in_collision(ur5.joints.neutral(), seen)
    assert ur5.in_collision(ur5.random_q(20, seed=1), seen).all()
    assert ("base_link", "table") in ur5.collision_checker(seen).collisions(ur5.joints.neutral())
    far = scene_from_base(_table_scene(), np.array([-0.5, -0.35, 0.0, 0.0]))
    assert _table_points_in_base(ur5, np.array([-0.5, -0.35, 0.0, 0.0])) == 0
    assert list(ur5.collision_checker(far).base_hits) == []


def test_placement_never_returns_a_base_inside_an_obstacle(ur5):
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (0.6, -0.1, 0.55)
    scene = _table_scene()
    with pytest.warns(UnreachableTargetsWarning):
        p = maps.placement(ur5, T[None], [[0.30, -0.35], [0.301, -0.349]], step=0.01,
                           yaws=1, yaw_range=(0, 0), scene=scene, reach_map=False)  # fmt: skip
    assert (p.reach == 0).all()
    p = maps.placement(ur5, T[None], [[-0.2, -0.45], [0.4, 0.1]], step=0.05, yaws=1,
                       yaw_range=(0, 0), scene=scene, reach_map=False)  # fmt: skip
    assert p.reach[0] == 1.0
    for base, reach in zip(p.bases, p.reach, strict=True):
        if reach > 0:
            assert list(ur5.collision_checker(scene_from_base(scene, base)).base_hits) == []
            assert _table_points_in_base(ur5, base) == 0


def test_a_support_may_be_touched_but_not_entered_deeply(ur5):
    # the UR5's base mesh reaches 3 mm below its frame: a floor at 0 is touched, allowed
    assert list(ur5.collision_checker(Scene().add_floor(0.0)).base_hits) == []
    assert list(ur5.collision_checker(Scene().add_floor(SUPPORT_SLACK + 0.002)).base_hits) == [
        ("base_link", "floor")
    ]
    # standing on a table declared as a support, the top at the base frame
    on_top = Scene().add_box("bench", (1.0, 1.0, 0.5), pose=(0.0, 0.0, -0.25), support=True)
    assert list(ur5.collision_checker(on_top).base_hits) == []
    assert not ur5.in_collision(ur5.joints.neutral(), on_top)
    down = HOME.copy()
    down[1] = 0.9  # the upper arm pointing down into the bench: the moving links still hit it
    assert ur5.in_collision(down, on_top)
    plain = Scene().add_box("bench", (1.0, 1.0, 0.5), pose=(0.0, 0.0, -0.25))
    assert list(ur5.collision_checker(plain).base_hits) == [
        ("base_link", "bench")
    ]  # not declared: a collision
    again = Scene.from_dict(on_top.to_dict())
    assert again == on_top and again.objects[0].support
    with pytest.raises(InvalidParameterError, match="support"):
        Scene().add_box("b", (0.1, 0.1, 0.1), support="yes")


# ---------------------------------------------------------------- sizes and files
def test_inverse_reachability_refuses_sizes_beyond_its_cap(ur5, tmp_path):
    for voxel, angles in ((0.01, 720), (0.0011, 24)):
        with pytest.raises(InvalidParameterError, match="cells"):
            maps.inverse_reachability(ur5, voxel=voxel, angles=angles, store=tmp_path / "s")
    assert not (tmp_path / "s").exists()


def test_a_scene_file_must_be_a_regular_file_of_bounded_size(tmp_path):
    with pytest.raises(InvalidParameterError, match="regular file"):
        Scene.load("/dev/zero")
    from toolkit.collision.scene import MAX_SCENE_BYTES

    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(MAX_SCENE_BYTES + 10)  # sparse: no disk
    with pytest.raises(InvalidParameterError, match="larger than"):
        Scene.load(big)
    good = tmp_path / "s.json"
    good.write_bytes(b"\xef\xbb\xbf" + json_text(_table_scene()).encode())
    assert Scene.load(good) == _table_scene()


def json_text(scene: Scene) -> str:
    import json

    return json.dumps(scene.to_dict())


def test_a_store_is_never_made_among_unrelated_files(ur5, tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("keep me")
    (folder / "zarr.json").write_text('{"zarr_format": 3, "node_type": "group", "attributes": {}}')
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    with pytest.raises(MapStoreError, match="not a toolkit map store"):
        maps.reachability(ur5, voxel=0.3, position_only=True, store=folder, workers=1)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    fresh = tmp_path / "fresh"
    maps.reachability(ur5, voxel=0.3, position_only=True, store=fresh, workers=1)
    again = maps.reachability(ur5, voxel=0.3, position_only=True, store=fresh, workers=1,
                              resume=True)  # fmt: skip
    assert again.index.max() > 0
    empty = tmp_path / "empty"
    empty.mkdir()
    maps.reachability(ur5, voxel=0.3, position_only=True, store=empty, workers=1)


def test_the_tasks_csv_takes_a_bom_and_blank_lines_and_refuses_extra_cells(tmp_path):
    from toolkit.cli.inputs import read_csv

    path = tmp_path / "tasks.csv"
    path.write_bytes(b"\xef\xbb\xbfx,y,z\n0.4,0.1,0.3\n0.5,0.0,0.3\n\n\n")
    header, rows = read_csv(str(path))
    assert header == ["x", "y", "z"] and len(rows) == 2
    path.write_text("x,y,z\n0.4,0.1,0.3\n0.5,0.0,0.3,9\n")
    with pytest.raises(InvalidParameterError, match="row 3"):
        read_csv(str(path))
    path.write_text("x,y,z\n0.4,0.1,0.3,\n")  # a trailing comma: an empty cell, not data
    assert read_csv(str(path))[1] == [["0.4", "0.1", "0.3", ""]]
    os.chmod(path, 0o644)


# ---------------------------------------------------------------- near-singular calibrated arms
def test_the_smallest_singular_pair_kernel_equals_numpy():
    from toolkit.ik import branch_kernels

    rng = np.random.default_rng(3)
    J = rng.normal(size=(400, 6, 6))
    J[:50, :, 5] = J[:50, :, 4] * 0.5 + 1e-7 * rng.normal(size=(50, 6))  # nearly singular
    for spread in (False, True):
        sigma, vec = branch_kernels.smallest_singular(spread, J)
        _, S, Vt = np.linalg.svd(J)
        # through J^T J: sigma^2 to ~1e-15 of the largest, so a sigma ~1e-7 to ~5e-8
        np.testing.assert_allclose(sigma[50:], S[50:, -1], atol=1e-11)
        np.testing.assert_allclose(sigma[:50], S[:50, -1], atol=1e-7)
        assert np.abs(np.abs(np.einsum("bi,bi->b", vec, Vt[:, -1])) - 1).max() < 1e-6
    small, _ = branch_kernels.smallest_singular(False, rng.normal(size=(20, 3, 3)))
    assert small.shape == (20,)


def test_a_calibrated_ur5_near_its_wrist_singularity_keeps_every_branch(ur5):
    """q5 within 0.07 rad of +-pi on perturbed UR5s: every solution the numeric IK finds
    from 30 random starts is among ik_all's branches, and ik_all_batch lists them too."""
    from toolkit import calibration as cal

    arm = toolkit.load_urdf(cal.perturb(ur5, seed=5).urdf_text, mimic=False, tip=ur5.tip)
    rng = np.random.default_rng(5)
    Q = arm.random_q(8, seed=105)
    Q[:, 4] = np.sign(rng.normal(size=8)) * np.pi + rng.uniform(-0.07, 0.07, 8)
    batch = arm.ik_all_batch(arm.fk(Q))
    for i, q in enumerate(Q):
        T = arm.fk(q)
        result = arm.ik_all(T)
        assert result.polished
        ours = [arm.joints.angles(r) for r in result.q]
        for start in arm.random_q(30, seed=i):
            res = arm.ik(T, q0=start, restarts=0, tol=1e-10, method="numeric")
            if not res.success:
                continue
            sigma = np.linalg.svd(arm.jacobian(res.q), compute_uv=False)[-1]
            close = max(1e-6, 10 * 1e-10 / sigma)
            assert any(same_up_to_turns(arm.joints.angles(res.q), o, close) for o in ours), (
                i,
                start,
            )
        rows = [arm.joints.angles(x) for x in batch.q[i, : batch.found[i]]]
        for b in set(result.branch.tolist()):
            first = arm.joints.angles(result.q[np.flatnonzero(result.branch == b)[0]])
            assert any(same_up_to_turns(first, x, 1e-5) for x in rows)


def test_placement_counts_a_singular_task_as_reached(ur5):
    T = ur5.fk(HOME)  # stretched upright: 1 mm away the arm no longer reaches it
    p = maps.placement(ur5, T[None], [[0.0, 0.0], [0.002, 0.002]], step=0.002, yaws=1,
                       yaw_range=(0, 0), reach_map=False, collision_free=False)  # fmt: skip
    assert p.reach[0] == 1.0 and np.allclose(p.bases[0], 0.0)
    q5 = p.q[0, 0, 4]  # the wrist singular: q5 = 0 (a whole turn of it, within the limits)
    assert abs(np.remainder(q5 + np.pi, 2 * np.pi) - np.pi) < 1e-6


def test_the_cli_refuses_a_device_as_a_scene(tmp_path, capsys):
    from toolkit.cli import main

    tasks = tmp_path / "tasks.csv"
    tasks.write_text("x,y,z\n0.4,0.1,0.3\n")
    argv = ["place", "ur5", str(tasks), "--region", "0", "-0.4", "0.8", "0.4", "--scene"]
    assert main([*argv, "/dev/zero"]) == 2
    assert "regular file" in capsys.readouterr().err


def test_an_answer_without_a_successful_row_says_why(ur5):
    """``reason`` is "" where a row succeeds and otherwise names the cause, with figures
    that are true of the answer: out of reach (the numeric IK's nearest pose stays as far
    as said), an orientation the 5-joint Katana cannot hold (the nearest row named), the
    joint limits (the joint named is outside in a row that holds the target)."""
    target = ur5.fk(ur5.random_q(1, seed=4)[0])
    assert ur5.ik_all(target).reason == ""
    far = np.eye(4)
    far[:3, 3] = [2.0, 0.0, 0.0]
    out = ur5.ik_all(far)
    assert len(out.q) == 0 and out.reason.startswith("no branch: the target is out of reach")
    stated = float(re.search(r"is ([\d.e+-]+) m", out.reason).group(1))
    best = ur5.ik(far, restarts=20, method="numeric")
    assert stated == pytest.approx(best.position_error, rel=1e-2) and stated > 0.5

    katana = toolkit.load("katana_6m180")
    T = katana.fk(katana.random_q(1, seed=3)[0])
    T[:3, :3] = T[:3, :3] @ pin.exp3(np.array([0.05, 0.02, 0.0]))
    off = katana.ik_all(T)
    assert not off.success.any() and "5-joint arm cannot hold every orientation" in off.reason
    row = int(re.search(r"row (\d+)", off.reason).group(1))
    assert off.orientation_error[row] == off.orientation_error.min() > 1e-3


def test_an_answer_outside_the_limits_names_the_joints(ur5, tmp_path):
    """A UR5 whose base joint may turn only within [0.5, 0.6] rad, given a target that
    needs it near -2 (or its other branch near 1.1): every branch holds the target, none
    within the limits, and the reason names the base joint."""
    text = ur5.urdf_path.read_text()
    share = ur5.urdf_path.parents[3]  # .../share/example-robot-data: meshes by absolute path
    text = text.replace("package://example-robot-data/", f"file://{share}/")
    block = re.search(r'<joint name="shoulder_pan_joint".*?</joint>', text, re.S).group(0)
    narrow = block.replace('lower="-6.28318530718" upper="6.28318530718"',
                           'lower="0.5" upper="0.6"')  # fmt: skip
    assert narrow != block
    path = tmp_path / "ur5_narrow.urdf"
    path.write_text(text.replace(block, narrow))
    robot = toolkit.load_urdf(path)
    q = ur5.random_q(1, seed=5)[0]
    q[0] = -2.0
    answer = robot.ik_all(ur5.fk(q))
    assert len(answer.q) and not answer.success.any()
    assert (np.maximum(answer.position_error, answer.orientation_error) < 1e-9).any()
    assert "outside the joint limits (of shoulder_pan_joint" in answer.reason


def test_the_singular_value_screen_agrees_with_the_exact_value():
    """``singular_at_least`` (a Cholesky of J^T J - s^2 I) says True exactly where the
    smallest singular value is at least s (numpy's SVD as the referee), on random 6x6 and
    6x5 Jacobians pushed near rank loss (rows within rounding of s may go either way)."""
    from toolkit.ik import branch_kernels

    rng = np.random.default_rng(11)
    for n in (6, 5):
        U, _ = np.linalg.qr(rng.normal(size=(400, 6, 6)))
        V, _ = np.linalg.qr(rng.normal(size=(400, n, n)))
        S = np.sort(rng.uniform(0.2, 2.0, (400, n)), axis=1)[:, ::-1]
        S[:, -1] = 10.0 ** rng.uniform(-6, 0, 400)  # the smallest across six decades
        J = np.einsum("bij,bj,bkj->bik", U[:, :, :n], S, V)
        exact = np.linalg.svd(J, compute_uv=False)[:, -1]
        for s in (1e-3, 0.005, 0.1):
            says = np.asarray(branch_kernels.singular_at_least(False, np.ascontiguousarray(J), s))
            clear = np.abs(exact - s) > 1e-9 * max(1.0, s)  # rows not within rounding of s
            np.testing.assert_array_equal(says[clear], exact[clear] >= s)


@pytest.mark.parametrize("name", ["ur5", "kinova", "panda"])
def test_the_screen_that_makes_its_own_jacobians_agrees_with_the_one_given_them(name):
    """``singular_at_least_at`` (each Jacobian made in the kernel from q) answers as
    ``singular_at_least`` on the kinematics back end's Jacobians, on random configurations
    and on configurations pushed to a singularity (the wrist's middle joint at 0 or near
    it), for every chain column and for a subset of them and of the rows."""
    from toolkit.ik import branch_kernels

    robot = toolkit.load_example(name)
    fid = robot.frames.id(None)
    backend = robot.kinematics
    A = robot.joints.angles(robot.random_q(300, seed=3))
    A[:100, 4] = 10.0 ** np.random.default_rng(1).uniform(-7, -1, 100)  # near the wrist's
    Q = np.ascontiguousarray(robot.joints.q_from_angles(A))
    chain = (*backend.chain(fid), int(backend.nv))
    seen = set()
    for rows, cols in ((6, np.arange(min(6, robot.model.nv))), (3, np.array([0, 1, 2]))):
        J = np.ascontiguousarray(backend.jacobian(Q, fid)[:, :rows, cols])
        for s in (1e-4, 0.005, 0.05):
            given = np.asarray(branch_kernels.singular_at_least(False, J, s))
            made = np.asarray(branch_kernels.singular_at_least_at(False, Q, chain, rows, cols, s))
            np.testing.assert_array_equal(made, given)
            seen |= set(given.tolist())
    assert seen == {False, True}  # both answers occur


def test_the_joints_outside_their_limits_are_named_on_an_arm_with_continuous_joints():
    """The reason's joint names come from the limits of each joint's own coordinates in q:
    on the Kinova (q has 9 coordinates for 6 joints) a row with joint 3 above its upper
    limit names joint 3 alone (before, the names were read against per-joint values)."""
    from toolkit.ik.solvers.reasons import _outside

    kinova = toolkit.load_example("kinova")
    inside = kinova.random_q(seed=2)
    assert kinova.joints.within_limits(inside) and _outside(kinova, inside[None]) == []
    j3 = kinova.model.joints[kinova.model.getJointId(kinova.joints.names[2])]
    q = inside.copy()
    q[j3.idx_q] = kinova.joints.upper[j3.idx_q] + 0.1
    assert _outside(kinova, q[None]) == [kinova.joints.names[2]]
