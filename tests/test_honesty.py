"""IK honesty, randomized: on every catalogue model and on UR5 and Panda, a solve that says
``success`` is right (independent FK, within the limits), reachable targets or not.

``benchmarks/honesty.py`` runs the same audit at 100,000 queries.
"""

from __future__ import annotations

import pytest
from helpers import audit_ik

import toolkit

ROBOTS = [*toolkit.available_models(), "ur5", "panda"]


@pytest.mark.parametrize("name", ROBOTS)
def test_no_false_success(name):
    robot = toolkit.load(name) if name in toolkit.available_models() else toolkit.load_example(name)
    result = audit_ik(robot, n=250, seed=2026)
    assert result["false_successes"] == 0, result
    # the audit is not empty: the reachable half of the targets is mostly solved
    assert result["successes"] >= 100, result
