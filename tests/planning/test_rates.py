"""How fast a pair of shapes can close along an edge (toolkit.planning.kernels.pair_rates):
per joint that moves one shape and not the other, the lesser of the two shapes' distances
from its axis. The other shape's distance counts where it rides that axis (the joint's
parent body: the base under the first joint); the distances hold at every configuration
and the rate bounds how fast coal's distance of every pair changes."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import toolkit
from toolkit.planning import kernels, reach, value_bounds
from toolkit.robot import checker_for

from .test_certain import KINOVA, PANDA, TILTED
from .test_planning import UR5

UR10 = toolkit.load_example("ur10")
CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


def _corners(checker, g: int, data: pin.Data) -> np.ndarray:
    """The corners of shape g's box, placed at the configuration ``data`` holds."""
    box = checker.bounds.box[g]
    local = box[:3] + (CORNERS * box[12:15]) @ box[3:12].reshape(3, 3).T
    M = data.oMi[int(checker.parts.objects[g].parentJoint)]
    return local @ M.rotation.T + M.translation


def _axis(model: pin.Model, data: pin.Data, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Joint j's axis in the world at the configuration ``data`` holds: (a point, unit)."""
    joint = model.joints[j]
    motion = joint.extract().axis if hasattr(joint.extract(), "axis") else None
    if motion is None:  # RX / RY / RZ (and their unbounded forms)
        motion = np.eye(3)["XYZ".index(joint.shortname()[-1])]
    M = data.oMi[j]
    return M.translation, M.rotation @ (np.asarray(motion) / np.linalg.norm(motion))


@pytest.mark.parametrize("robot", [UR5, UR10, PANDA, KINOVA, TILTED],
                         ids=["ur5", "ur10", "panda", "kinova", "tilted"])  # fmt: skip
@settings(max_examples=20, deadline=None)
@given(data=st.data())
def test_a_shape_lies_within_its_reach_of_an_axis_it_rides_with_at_every_configuration(
    robot, data
):  # fmt: skip
    """Where a revolute joint does not move a shape, the reach is finite exactly where the
    shape rides the joint's parent body, and every corner of its box lies within it of the
    axis."""
    lo, hi = value_bounds(robot)
    shares = st.lists(st.floats(0, 1), min_size=len(lo), max_size=len(lo))
    x = lo + np.array(data.draw(shares)) * (hi - lo)
    checker = checker_for(robot, toolkit.Scene())
    far, moves = reach(robot, checker)
    model = robot.model
    pdata = model.createData()
    pin.forwardKinematics(model, pdata, robot.joints.q_from_angles(x))
    for g in range(checker.robot_count):
        corners = _corners(checker, g, pdata)
        for j in range(1, model.njoints):
            c = model.joints[j].idx_v
            if moves[g, c]:
                continue
            turns = "JointModelP" not in model.joints[j].shortname()  # a slide: 1 per step
            rides = int(checker.parts.objects[g].parentJoint) == model.parents[j] and turns
            assert np.isfinite(far[g, c]) == rides
            if rides:
                point, unit = _axis(model, pdata, j)
                off = corners - point
                distance = np.linalg.norm(off - np.outer(off @ unit, unit), axis=1)
                assert distance.max() <= far[g, c] + 1e-12


def _rates(robot, checker, a, b) -> np.ndarray:
    far, moves = reach(robot, checker)
    rate = np.empty(len(checker.bounds.first))
    kernels.pair_rates(a, b, checker.bounds.first, checker.bounds.second, far, moves, rate)
    return rate


@pytest.mark.parametrize("robot", [UR10, PANDA], ids=["ur10", "panda"])
def test_no_pair_of_shapes_closes_faster_than_its_rate_along_an_edge(robot):
    """Coal's distance of every checked pair (the robot's own and against a box beside it),
    apart at both ends of a step, changes between configurations 1/400 of an edge apart by
    no more than its rate times that share, on 12 random edges."""
    scene = toolkit.Scene().add_box("box", [0.2, 0.2, 0.2], [0.45, 0.1, 0.3])
    checker = checker_for(robot, scene)
    geom, gdata = checker.geom, pin.GeometryData(checker.geom)
    lo, hi = value_bounds(robot)
    rng = np.random.default_rng(3)
    tight = 0
    for _ in range(12):
        a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
        rate = _rates(robot, checker, a, b)
        t = np.linspace(0.0, 1.0, 401)
        D = np.empty((len(t), len(geom.collisionPairs)))
        for i, s in enumerate(t):
            pin.computeDistances(robot.model, robot.model.createData(), geom, gdata,
                                 robot.joints.q_from_angles(a + s * (b - a)))  # fmt: skip
            D[i] = [r.min_distance for r in gdata.distanceResults]
        apart = (D[:-1] > 0) & (D[1:] > 0)  # in contact coal answers a depth, not a distance
        change = np.where(apart, np.abs(np.diff(D, axis=0)), 0.0).max(axis=0) / (t[1] - t[0])
        assert (change <= rate * (1 + 1e-6) + 1e-5).all()
        tight += int((change > 0.5 * rate).sum())
    assert tight > 0  # the bound is approached, not loose everywhere


def test_the_base_and_the_upper_arm_close_no_faster_than_the_base_lies_from_the_pan_axis():
    """The UR10's base and upper arm (a pair the covers leave to coal): turning only the
    first joint, they close at most at the base's 0.12 m from its axis per radian, not
    the upper arm's 0.9 m (the arm sweeps far; the base turns on the spot under it)."""
    checker = checker_for(UR10, toolkit.Scene())
    names = [o.name for o in checker.geom.geometryObjects]
    first, second = checker.bounds.first, checker.bounds.second
    wanted = {"base_link_0", "upper_arm_link_0"}
    k = next(i for i in range(len(first)) if {names[first[i]], names[second[i]]} == wanted)
    a = np.zeros(6)
    b = a.copy()
    b[0] = 1.0
    far, _ = reach(UR10, checker)
    base = names.index("base_link_0")
    arm = names.index("upper_arm_link_0")
    rate = _rates(UR10, checker, a, b)[k]
    assert rate == pytest.approx(far[base, 0]) and rate < 0.15 < 0.9 < far[arm, 0]
