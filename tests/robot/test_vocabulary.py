"""One vocabulary: the renamed keywords still work for a release, warn naming the new
name, pass their value on under it, and refuse both names at once."""

from __future__ import annotations

import inspect
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
        ("toolkit.ik.solvers.branches.BranchQueries.ik_all", "q_rest", "q0"),
        ("toolkit.ik.solvers.batches.AnalyticIK.ik_all_batch", "q_rest", "q0"),
        ("toolkit.maps.reachability", "ik_method", "method"),
        ("toolkit.maps.backlash_accuracy", "ik_method", "method"),
        ("toolkit.maps.inverse.inverse_reachability", "ik_method", "method"),
        ("toolkit.maps.placement.placement", "structure", "reach_map"),
        ("toolkit.ik.numeric.options.IKOptions", "timeout", "time_limit"),
        ("toolkit.maps.grid.spread_orientations", "count", "n"),
        ("toolkit.collision.pairs.disabled_pairs", "samples", "n"),
        ("toolkit.calibration.simulate", "link", "frame"),
        ("toolkit.calibration._select.select_poses", "link", "frame"),
        ("toolkit.calibration._arm.ArmModel.gravity", "link", "frame"),
        ("toolkit.calibration._measure.Measurements.gravity", "link", "frame"),
        ("toolkit.motion.lines.cartesian", "start", "start_pose"),
        ("toolkit.motion.lines.cartesian", "goal", "goal_pose"),
    ])  # fmt: skip


def test_the_ik_time_limit_answers_to_its_old_name_with_a_warning():
    """``timeout=`` in a call, in ``IKOptions(...)`` and as its attribute: the same
    options, a DeprecationWarning at the user's line; both names at once refused."""
    with _warns("time_limit") as caught:
        old = toolkit.IKOptions(timeout=0.5)
    assert caught[0].filename == __file__
    assert old == toolkit.IKOptions(time_limit=0.5)
    with _warns("time_limit"):
        assert old.timeout == 0.5
    with _warns("time_limit"):
        answer = UR5.ik(UR5.fk(G), timeout=1.0, method="numeric")
    assert answer.success
    with pytest.raises(toolkit.InvalidParameterError, match="time_limit= only"):
        UR5.ik(UR5.fk(G), timeout=1.0, time_limit=1.0)


def test_calibrations_frame_answers_to_its_old_name_link():
    from toolkit import calibration

    katana = toolkit.load("katana_6m180")
    Q = katana.random_q(6, seed=3)
    with _warns("frame"):
        old = calibration.simulate(katana, Q, "gravity", 1e-3, link="link3", seed=1)
    new = calibration.simulate(katana, Q, "gravity", 1e-3, frame="link3", seed=1)
    np.testing.assert_array_equal(old.blocks[0].values, new.blocks[0].values)
    with _warns("frame"):
        calibration.Measurements.gravity(link="link3", directions=[[0.0, 0.0, -1.0]])


def test_a_start_and_goal_are_configurations_and_poses_say_so():
    """``start``/``goal`` are configurations (``plan``); the tool line's poses are
    ``start_pose``/``goal_pose``, their old names warning."""
    from toolkit import motion

    T0, T1 = UR5.fk(G), UR5.fk(G + 0.05)
    new = motion.cartesian(UR5, start_pose=T0, goal_pose=T1, duration=1.0, q0=G, steps=5)
    with _warns("start_pose"):
        old = motion.cartesian(UR5, start=T0, goal_pose=T1, duration=1.0, q0=G, steps=5)
    np.testing.assert_array_equal(old.sample(UR5, [0.5]).q, new.sample(UR5, [0.5]).q)
    assert "start" in inspect.signature(UR5.plan).parameters


def test_counts_are_n_and_the_old_names_warn():
    from toolkit.collision import disabled_pairs

    with _warns("n"):
        old = maps.spread_orientations(count=5)
    np.testing.assert_array_equal(old, maps.spread_orientations(n=5))
    katana = toolkit.load("katana_6m180")
    with _warns("n"):
        pairs = disabled_pairs(katana, samples=50, seed=1)
    assert pairs == disabled_pairs(katana, n=50, seed=1)


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


# ---------------------------------------------------------------------- the Robot's face
FACE = {
    # what a robot is: its model, names, files, facts, joint space, frames, back end
    "model", "data", "name", "tip", "urdf_path", "srdf_path", "params", "facts",
    "joints", "frames", "kinematics", "nq",
    # kinematics and sampling
    "fk", "jacobian", "point_kinematics", "random_q",
    # inverse kinematics (toolkit.ik)
    "ik", "ik_batch", "ik_path", "ik_all", "ik_all_batch", "structure", "structure_of",
    # collisions (toolkit.collision)
    "in_collision", "collision_checker",
    # the SRDF's planning groups and named states
    "group", "states",
}  # fmt: skip
LATER = {"plan": "toolkit.planning", "gravity": "toolkit.dynamics"}
"""The delegations later packages added, one each."""


def test_the_robot_is_a_thin_face():
    names = {n for n in dir(UR5) if not n.startswith("_")}
    assert names == FACE | set(LATER)
    assert len(FACE) <= 27
    assert toolkit.Robot.__mro__[1:] == (toolkit.common.ByArguments, object)  # no mixins


def test_no_part_of_the_robot_declares_the_robot_for_the_type_checker():
    """The parts of a robot (its IK, analytic IK, collisions) hold what they use; none
    re-declares the robot's members under ``if TYPE_CHECKING:`` in a class body."""
    import ast
    from pathlib import Path

    folder = Path(toolkit.robot.__file__).parent
    for path in sorted(folder.glob("*.py")):
        for cls in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(cls, ast.ClassDef):
                for node in cls.body:
                    test = node.test if isinstance(node, ast.If) else None
                    assert not (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING"), (
                        f"{path.name}: class {cls.name} declares members for the type checker"
                    )


Q = np.array([0.3, -1.2, 1.0, -0.5, 0.7, 0.2])
MOVED = {
    # old name: (what it answers, what the new place answers)
    "nv": (lambda r: r.nv, lambda r: r.joints.nv),
    "lower": (lambda r: r.lower, lambda r: r.joints.lower),
    "upper": (lambda r: r.upper, lambda r: r.joints.upper),
    "joint_names": (lambda r: r.joint_names, lambda r: r.joints.names),
    "check_q": (lambda r: r.check_q(Q), lambda r: r.joints.check(Q)),
    "check_v": (lambda r: r.check_v(Q, "qd"), lambda r: r.joints.check_v(Q, "qd")),
    "within_limits": (lambda r: r.within_limits(Q), lambda r: r.joints.within_limits(Q)),
    "q_from_angles": (lambda r: r.q_from_angles(Q), lambda r: r.joints.q_from_angles(Q)),
    "angles": (lambda r: r.angles(Q), lambda r: r.joints.angles(Q)),
    "neutral": (lambda r: r.neutral(), lambda r: r.joints.neutral()),
    "frame_id": (lambda r: r.frame_id("tool0"), lambda r: r.frames.id("tool0")),
    "frame_names": (lambda r: r.frame_names, lambda r: list(r.frames)),
    "motion_rank": (lambda r: r.motion_rank(), lambda r: r.frames.rank()),
    "engine": (lambda r: r.engine, lambda r: r.kinematics.engine),
    "backend": (lambda r: r.backend, lambda r: None),  # asked for nothing: the automatic choice
    "collisions": (lambda r: r.collisions(Q), lambda r: r.collision_checker().collisions(Q)),
    "min_distance": (
        lambda r: r.min_distance(Q),
        lambda r: r.collision_checker().min_distance(Q),
    ),
    "base_collisions": (
        lambda r: r.base_collisions(None),
        lambda r: list(r.collision_checker().base_hits),
    ),
    "ik_state": (lambda r: r.ik_state.mid, lambda r: r._numeric.ik_state.mid),
    "ik_loop": (lambda r: r.ik_loop, lambda r: r._numeric.ik_loop),
}


def test_every_moved_name_is_listed():
    from toolkit.robot.model import _MOVED

    assert sorted(_MOVED) == sorted(MOVED)


@pytest.mark.parametrize("name", sorted(MOVED))
def test_a_moved_name_still_answers_for_a_release_and_warns_naming_the_new_place(name):
    old, new = MOVED[name]
    with pytest.warns(DeprecationWarning, match=rf"Robot\.{name} is now .*next release") as w:
        got = old(UR5)
    assert w[0].filename == __file__  # the user's line
    want = new(UR5)
    if isinstance(want, np.ndarray):
        np.testing.assert_array_equal(got, want)
    else:
        assert got == want


def test_an_unknown_name_is_still_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'ik_al'"):
        UR5.ik_al  # noqa: B018


# ---------------------------------------------------------------------- one word per concept
SYNONYMS = {
    "timeout": "time_limit", "deadline": "time_limit", "budget": "time_limit",
    "count": "n", "samples": "n", "num": "n", "size_n": "n",
    "q_start": "q0", "q_init": "q0", "q_rest": "q0", "q_seed": "q0",
    "rng": "seed", "random_state": "seed",
    "tolerance": "tol", "eps": "tol",
    "v": "qd", "velocities": "qd", "accelerations": "qdd",
    "ik_method": "method", "T": "pose", "link": "frame",
}  # fmt: skip
"""A second word for a concept the vocabulary (docs/conventions.md) names once."""
KEPT = {
    ("toolkit.planning.ExactSweep.rates", "a"): "a segment's two ends (a, b), not a rate",
    ("toolkit.planning.write_joint_trajectory", "accelerations"):
        "the MoveIt message's own field name",
    ("toolkit.planning.write_joint_trajectory", "velocities"): "the MoveIt message's own field",
    ("toolkit.planning.JointTrajectory", "accelerations"): "the MoveIt message's own field",
    ("toolkit.planning.JointTrajectory", "velocities"): "the MoveIt message's own field",
    ("toolkit.structures.History", "v"): "[P3]'s point velocity [m/s], a record's field",
    ("toolkit.structures.ReachSection", "v"): "a section's second coordinate [m], not a rate",
    ("toolkit.Scene.attach", "link"): "the link an object moves with: the scene file's field",
    ("toolkit.collision.Scene.attach", "link"): "the same method, from its package",
    ("toolkit.collision.SceneObject", "link"): "the scene file's field (a record)",
}  # fmt: skip
"""Parameters that keep a listed word, with the reason."""
API = ["toolkit", "toolkit.ik", "toolkit.collision", "toolkit.planning", "toolkit.motion",
       "toolkit.dynamics", "toolkit.maps", "toolkit.calibration", "toolkit.backlash",
       "toolkit.katana", "toolkit.structures", "toolkit.bending", "toolkit.arm5dof"]  # fmt: skip


def _public_parameters() -> dict[tuple[str, str], str]:
    """(callable, parameter) -> the callable's module, for every public function, class
    and public method of the modules' ``__all__`` (a renamed keyword shows its new name)."""
    import importlib
    import inspect

    found: dict[tuple[str, str], str] = {}

    def visit(obj: object, label: str) -> None:
        try:
            names = list(inspect.signature(obj).parameters)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return
        for name in names:
            found[(label, name)] = label

    for module in API:
        mod = importlib.import_module(module)
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name, None)
            if inspect.isfunction(obj):
                visit(obj, f"{module}.{name}")
            elif inspect.isclass(obj):
                visit(obj, f"{module}.{name}")
                for attr, member in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(member):
                        visit(member, f"{module}.{name}.{attr}")
    return found


def test_the_public_api_uses_one_word_per_concept():
    """No public parameter is a second word for a concept the vocabulary names once
    (``timeout`` for ``time_limit``, ``count`` for ``n``...), but those kept with a reason."""
    offenders = sorted(
        f"{where}({word}=): say {SYNONYMS[word]}"
        for where, word in _public_parameters()
        if word in SYNONYMS and (where, word) not in KEPT
    )
    assert not offenders, offenders
    found = _public_parameters()
    assert len(found) > 300  # the enumeration reaches the API
    assert set(KEPT) <= set(found), sorted(set(KEPT) - set(found))  # no stale exception
