"""No silent wrong answer: joint types, threads, non-convergence, pickling, hostile files."""

from __future__ import annotations

import pickle
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit import backlash
from toolkit.cli import main
from toolkit.descriptions import example_robot_data_dir


@pytest.fixture(scope="module")
def kinova() -> toolkit.Robot:
    """A real arm with three continuous joints (stored as cos, sin by Pinocchio)."""
    path = example_robot_data_dir() / "kinova_description/robots/kinova.urdf"
    return toolkit.load_urdf(path, tip="j2s6s200_end_effector")


# ---------------------------------------------------------------------- joint types
def test_continuous_joints_are_known(kinova):
    assert kinova.nq == 9 and kinova.joints.nv == 6
    assert kinova.joints.continuous == ["j2s6s200_joint_1", "j2s6s200_joint_4", "j2s6s200_joint_6"]


def test_random_q_lies_on_the_circle_and_within_limits(kinova):
    q = kinova.random_q(500, seed=1)
    c, s = kinova.joints.cos_index, kinova.joints.sin_index
    np.testing.assert_allclose(q[:, c] ** 2 + q[:, s] ** 2, 1.0, atol=1e-12)
    assert kinova.joints.within_limits(q)
    # every pose is a proper rotation
    R = kinova.fk(q[:20])[:, :3, :3]
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)


def test_off_circle_pairs_are_refused(kinova):
    q = kinova.random_q(seed=2)
    q[0], q[1] = 2.0, 0.0  # the fk([2, 0, ...]) that returned 2 I
    for call in (kinova.fk, kinova.jacobian, kinova.joints.within_limits):
        with pytest.raises(toolkit.ConfigurationError, match="unit circle"):
            call(q)
    with pytest.raises(toolkit.ConfigurationError, match="unit circle"):
        kinova.ik(kinova.fk(kinova.random_q(seed=3)), q0=q)


def test_the_circle_check_flags_exactly_the_groups_off_their_sphere(kinova):
    """``off_manifold`` per (cos, sin) pair and per quaternion of a floating base, in batches,
    against each group's norm computed here (the check is summed group by group)."""
    floating = toolkit.load_urdf(
        example_robot_data_dir() / "kinova_description/robots/kinova.urdf",
        tip="j2s6s200_end_effector", floating=True,
    )  # fmt: skip
    rng = np.random.default_rng(5)
    for robot in (kinova, floating):
        Q = robot.random_q(400, seed=rng)
        Q[::3] *= rng.uniform(0.99, 1.01, Q[::3].shape)  # every coordinate scaled a little
        expected = np.stack([np.abs((Q[:, g] ** 2).sum(axis=1) - 1.0) > 1e-9
                             for g in robot.joints.units], axis=1)  # fmt: skip
        got = robot.joints.off_manifold(Q)
        assert got.shape == expected.shape and expected.any() and not expected.all()
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_array_equal(robot.joints.off_manifold(Q[7]), expected[7])


def test_ik_restarts_keep_continuous_joints_on_the_circle(kinova):
    """An unreachable target runs every restart: each start, and so the answer, is valid."""
    res = kinova.ik([3.0, 0.0, 0.0], restarts=5)
    assert not res.success and res.restarts == 5
    c, s = kinova.joints.cos_index, kinova.joints.sin_index
    np.testing.assert_allclose(res.q[c] ** 2 + res.q[s] ** 2, 1.0, atol=1e-12)
    kinova.fk(res.q)  # a valid configuration: no ConfigurationError


def test_wrong_length_names_the_two_number_joints(kinova):
    with pytest.raises(toolkit.ConfigurationError, match="take two numbers each") as err:
        kinova.fk(np.zeros(6))
    assert "j2s6s200_joint_1" in str(err.value) and "q_from_angles" in str(err.value)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6))
def test_one_value_per_joint_round_trip(values):
    robot = _kinova()
    v = np.array(values)  # within (-pi, pi], where continuous angles come back
    q = robot.joints.q_from_angles(v)
    np.testing.assert_allclose(robot.joints.angles(q), v, atol=1e-12)


_KINOVA: list[toolkit.Robot] = []


def _kinova() -> toolkit.Robot:
    if not _KINOVA:
        path = example_robot_data_dir() / "kinova_description/robots/kinova.urdf"
        _KINOVA.append(toolkit.load_urdf(path, tip="j2s6s200_end_effector"))
    return _KINOVA[0]


def test_one_value_per_joint_matches_yourdfpy(kinova):
    """Independent route: yourdfpy takes one value per actuated joint, continuous included."""
    urdf = yourdfpy.URDF.load(str(kinova.urdf_path), load_meshes=False, build_scene_graph=True)
    rng = np.random.default_rng(4)
    for _ in range(20):
        values = kinova.joints.angles(kinova.random_q(seed=rng))
        cfg = dict(zip(kinova.joints.names, values, strict=True))
        urdf.update_cfg(cfg)
        theirs = urdf.get_transform("j2s6s200_end_effector", urdf.base_link)
        np.testing.assert_allclose(
            kinova.fk(kinova.joints.q_from_angles(values)), theirs, atol=1e-9
        )


def test_ik_on_continuous_joints_is_honest(kinova):
    target = kinova.fk(kinova.random_q(seed=5))
    res = kinova.ik(target, tol=1e-7)
    assert res.success
    np.testing.assert_allclose(kinova.fk(res.q), target, atol=1e-6)
    c, s = kinova.joints.cos_index, kinova.joints.sin_index
    np.testing.assert_allclose(res.q[c] ** 2 + res.q[s] ** 2, 1.0, atol=1e-12)


def test_cli_deg_converts_revolute_joints_only(capsys):
    """`toolkit fk scara 30 45 0.1 --deg`: the stroke stays 0.1 m (it was read as 0.1 deg)."""
    scara = toolkit.load("scara")
    assert main(["fk", "scara", "30", "45", "0.1", "--deg"]) == 0
    printed = capsys.readouterr().out.split("frame:")[1]
    T = np.array([row.split() for row in printed.replace("[", " ").replace("]", " ").splitlines()
                  if row.strip()], dtype=float)  # fmt: skip
    np.testing.assert_allclose(T, scara.fk([np.radians(30), np.radians(45), 0.1]), atol=1e-6)
    cyl = toolkit.load("cylindrical")
    assert main(["ik", "cylindrical", *map(str, cyl.fk(cyl.random_q(seed=1))[:3, 3]), "--deg"]) == 0
    out = capsys.readouterr().out
    assert "[m]" in out and "[deg]" in out


# ---------------------------------------------------------------------- limits
def _urdf(tmp_path: Path, lower: str, upper: str, axis: str = "0 0 1", mass: str = "1") -> Path:
    text = f"""<?xml version="1.0"?>
<robot name="one">
  <link name="base"/>
  <link name="arm"><inertial><mass value="{mass}"/><origin xyz="0.1 0 0"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="{axis}"/><limit lower="{lower}" upper="{upper}" effort="1" velocity="1"/></joint>
  <joint name="fix" type="fixed"><parent link="arm"/><child link="tip"/>
    <origin xyz="0.3 0 0"/></joint>
</robot>"""
    path = tmp_path / "one.urdf"
    path.write_text(text)
    return path


def test_lower_above_upper_means_unlimited(tmp_path):
    robot = toolkit.load_urdf(_urdf(tmp_path, "0", "-1"), tip="tip")  # pybullet's "unlimited"
    assert robot.joints.lower[0] == -np.inf and robot.joints.upper[0] == np.inf
    q = robot.random_q(100, seed=0)
    assert np.all(np.abs(q) <= np.pi) and robot.joints.within_limits(q)


def test_one_dof_robot_ik_and_jacobian(tmp_path):
    robot = toolkit.load_urdf(_urdf(tmp_path, "-2", "2"), tip="tip")
    assert robot.jacobian([0.4]).shape == (6, 1)
    res = robot.ik(robot.fk([0.7])[:3, 3])
    assert res.success and abs(res.q[0] - 0.7) < 1e-6


@pytest.mark.parametrize(
    ("kw", "message"), [({"axis": "0 0 0"}, "zero axis"), ({"mass": "-2"}, "mass")]
)
def test_impossible_descriptions_are_refused(tmp_path, kw, message):
    with pytest.raises(toolkit.ModelLoadError, match=message):
        toolkit.load_urdf(_urdf(tmp_path, "-1", "1", **kw))


def test_xml_entities_are_not_expanded(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOP-SECRET")
    xxe = tmp_path / "xxe.urdf"
    xxe.write_text(
        f'<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file://{secret}">]>\n'
        '<robot name="&x;"><link name="base"/></robot>'
    )
    levels = "".join(f'<!ENTITY l{i} "{(f"&l{i - 1};" if i else "lol") * 10}">' for i in range(10))
    bomb = tmp_path / "bomb.urdf"
    body = '<robot name="&l9;"><link name="b"/></robot>'
    bomb.write_text(f'<?xml version="1.0"?>\n<!DOCTYPE r [{levels}]>\n{body}')
    for path in (xxe, bomb):
        start = time.perf_counter()
        try:
            robot = toolkit.load_urdf(path)
        except toolkit.ToolkitError:
            continue  # a clear refusal is fine
        assert "TOP-SECRET" not in robot.model.name and len(robot.model.name) < 100
        assert time.perf_counter() - start < 5.0


# ---------------------------------------------------------------------- IK options
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"tol": 1e300}, "tol"),
        ({"tol": None}, "tol"),
        ({"tol": "1e-6"}, "tol"),
        ({"max_iter": float("inf")}, "max_iter"),
        ({"seed": -1}, "seed"),
        ({"time_limit": float("nan")}, "time_limit"),
        ({"time_limit": "abc"}, "time_limit"),
        ({"mask": "abc"}, "mask"),
        ({"restarts": True}, "restarts"),
        ({"colour": 1}, "unknown IK option"),
    ],
)
def test_ik_options_are_checked(kwargs, message):
    robot = toolkit.load("katana_6m90a")
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        robot.ik([5.0, 5.0, 5.0], **kwargs)


def test_ik_path_checks_max_jump_and_takes_a_time_limit():
    robot = toolkit.load_example("ur5")
    T = robot.fk(robot.random_q(seed=1))
    with pytest.raises(toolkit.InvalidParameterError, match="max_jump"):
        robot.ik_path([T], max_jump=float("nan"))
    assert robot.ik_path([T], time_limit=1.0).all_succeeded


# ---------------------------------------------------------------------- non-convergence
def test_backlash_that_does_not_converge_says_so(monkeypatch):
    """k_H = 50, far past [P1]'s 0.05-0.4: the plain iteration diverges, and settling (Newton
    on the arm's energy) still finds every rest, eq. 17 holding at each; without settling
    (forced off), the commands it leaves are reported unconverged with their residual."""
    import toolkit.papers.backlash.layer as layer_module

    katana = toolkit.load("katana_6m180")
    layer = backlash.Backlash(katana, k_h=50, payload=0.5)
    q = katana.random_q(200, seed=1)
    settled = layer.solve(q)
    assert settled.converged.all()
    contact = ~settled.in_gap
    law = layer.offsets(settled.torque)
    np.testing.assert_allclose((settled.theta - q)[contact], law[contact], atol=1e-9)
    monkeypatch.setattr(layer_module, "SETTLE_ITERATIONS", 0)
    out = layer.solve(q)
    assert not out.converged.all() and np.max(out.residual) > 1e-3
    with pytest.raises(toolkit.ConvergenceError, match="did not converge") as err:
        layer.output_angles(q)
    assert err.value.residual == pytest.approx(float(np.max(out.residual)))
    with pytest.raises(toolkit.ConvergenceError):
        layer.fk(q)
    with pytest.raises(toolkit.InvalidParameterError, match="max_iter"):
        layer.solve(q, max_iter=0)
    with pytest.raises(toolkit.InvalidParameterError, match="chunk"):
        backlash.error_map(backlash.Backlash(katana), n=50, chunk=-1)


def test_compensate_checks_the_frame_it_was_asked_for():
    katana = toolkit.load("katana_6m180")
    layer = backlash.Backlash(katana, payload=0.5)
    target = katana.fk(katana.random_q(seed=3), "link3")[:3, 3]
    res = layer.compensate(target, frame="link3")
    assert res.success
    actual = katana.fk(layer.output_angles(res.q), "link3")[:3, 3]
    np.testing.assert_allclose(actual, target, atol=1e-6)


# ---------------------------------------------------------------------- threads
def _hammer(work, threads: int = 8) -> list:
    results: list = [None] * threads
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        pool = [
            threading.Thread(target=lambda i=i: results.__setitem__(i, work(i)))
            for i in range(threads)
        ]
        for t in pool:
            t.start()
        for t in pool:
            t.join()
    finally:
        sys.setswitchinterval(old)
    return results


@pytest.mark.parametrize("method", ["auto", "numeric"])
def test_a_robot_shared_by_eight_threads(method):
    robot = toolkit.load_example("ur5")
    qs = robot.random_q(400, seed=7)
    targets = robot.fk(qs[:24])
    ref_fk = np.stack([robot.fk(q) for q in qs])
    ref_ik = [robot.ik(T, seed=3, method=method) for T in targets]

    def work(i: int) -> tuple[np.ndarray, list]:
        fk = np.stack([robot.fk(q) for q in qs])
        iks = [robot.ik(T, seed=3, method=method) for T in targets[i::8]]
        return fk, iks

    for i, (fk, iks) in enumerate(_hammer(work)):
        np.testing.assert_array_equal(fk, ref_fk)
        for got, want in zip(iks, ref_ik[i::8], strict=True):
            assert got.success == want.success
            np.testing.assert_array_equal(got.q, want.q)


def test_a_backlash_layer_shared_by_eight_threads():
    katana = toolkit.load("katana_6m180")
    layer = backlash.Backlash(katana, payload=0.5)
    qs = katana.random_q(16, seed=2)  # fewer than the batch size: the Pinocchio path
    ref = layer.output_angles(qs)
    for got in _hammer(lambda i: layer.output_angles(qs)):
        np.testing.assert_array_equal(got, ref)


# ---------------------------------------------------------------------- pickling
def _fk_in_worker(robot: toolkit.Robot, q: np.ndarray) -> np.ndarray:
    return robot.fk(q)


def test_robots_and_layers_pickle(kinova):
    for robot in (toolkit.load("katana_6m180", a2=0.2), toolkit.load_example("panda"), kinova):
        copy = pickle.loads(pickle.dumps(robot))
        assert copy == robot and copy.params == robot.params and copy.facts == robot.facts
        q = robot.random_q(seed=1)
        np.testing.assert_array_equal(copy.fk(q), robot.fk(q))
    layer = backlash.Backlash(toolkit.load("katana_6m180"), k_h=0.3, payload=0.5)
    clone = pickle.loads(pickle.dumps(layer))
    assert clone == layer
    q = layer.robot.random_q(40, seed=2)
    np.testing.assert_array_equal(clone.output_angles(q), layer.output_angles(q))


def test_a_robot_goes_to_a_process_pool():
    robot = toolkit.load("katana_6m90b")
    qs = robot.random_q(4, seed=3)
    with ProcessPoolExecutor(max_workers=2) as pool:
        got = list(pool.map(_fk_in_worker, [robot] * 4, qs))
    np.testing.assert_array_equal(np.stack(got), robot.fk(qs))


def test_ik_all_of_one_target_shared_by_eight_threads():
    """One target's door keeps its family's raw branches in per-thread arrays: eight
    threads answering different targets at once get each target's own rows."""
    robot = toolkit.load_example("ur5")
    targets = robot.fk(robot.random_q(32, seed=5))
    ref = [robot.ik_all(T) for T in targets]

    def work(i: int) -> list:
        return [(k, robot.ik_all(targets[k])) for k in range(i, len(targets), 3)] * 2

    for rows in _hammer(work):
        for k, got in rows:
            np.testing.assert_array_equal(got.q, ref[k].q)
            assert got.labels == ref[k].labels


def test_a_kept_value_made_from_another_does_not_wait_for_its_own_lock():
    """A robot's deferred pairs, asked of a fresh robot, make its sphere covers first,
    both kept under the robot's one lock: with a lock that is not reentrant the call
    waited for ever."""
    from toolkit.robot.deferral import deferred_pairs

    robot = toolkit.load_example("ur5")  # nothing kept yet
    checker = robot.collision_checker(None)
    out: list = []
    worker = threading.Thread(target=lambda: out.append(deferred_pairs(robot, checker)),
                              daemon=True)  # fmt: skip
    worker.start()
    worker.join(300)
    assert out, "deferred_pairs waited for ever on the robot's own lock"
    assert np.isin(out[0], np.arange(len(checker.bounds.first))).all()
