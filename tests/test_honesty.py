"""IK honesty, randomized: on every catalogue model, UR5 and Panda (compiled engine) and the
Kinova arm (continuous joints: Pinocchio back end), a solve that says
``success`` is right (independent FK, within the limits), reachable targets or not.

``benchmarks/honesty.py`` runs the same audit at 100,000 queries.
"""

from __future__ import annotations

import pytest
from helpers import audit_ik

import toolkit
from toolkit.loaders import example_robot_data_dir

ROBOTS = [*toolkit.available_models(), "ur5", "panda", "kinova"]


def _robot(name: str) -> toolkit.Robot:
    if name == "kinova":  # continuous joints: the Pinocchio back end
        path = example_robot_data_dir() / "kinova_description/robots/kinova.urdf"
        return toolkit.load_urdf(path, tip="j2s6s200_end_effector")
    return toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)


@pytest.mark.parametrize("name", ROBOTS)
def test_no_false_success(name):
    robot = _robot(name)
    result = audit_ik(robot, n=250, seed=2026)
    assert result["false_successes"] == 0, result
    # the audit is not empty: the reachable half of the targets is mostly solved
    assert result["successes"] >= 100, result
