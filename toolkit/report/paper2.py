"""Report section of [P2]: the 5-DOF arm's geometric IK, all solutions."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..papers import arm5dof
from ..robot import load
from .checks import Check, Section, save_figure

__all__ = ["arm5dof_section"]


def arm5dof_section(n_random: int = 1000, seed: int = 0) -> Section:
    """Paper 2: every geometric solution reproduces its target on the Pinocchio model."""
    sec = Section("Paper 2 - 5-DOF arm: geometric inverse kinematics, all solutions")
    robot = load("arm5dof")
    worst, counts = 0.0, []
    for q in robot.random_q(n_random, np.random.default_rng(seed)):
        T = robot.fk(q)
        p, d = T[:3, 3], T[:3, 0]
        h = p[:2] / np.hypot(p[0], p[1])
        sols = arm5dof.geometric_ik(p, float(np.arctan2(d[2], d[:2] @ h)), arm5dof.MODEL_LENGTHS)
        counts.append(len(sols))
        for s in sols:
            Ts = robot.fk(s)
            worst = max(worst, np.abs(Ts[:3, 3] - p).max(), np.abs(Ts[:3, 0] - d).max())
    sec.check(
        f"every geometric solution reaches its target on the arm5dof model ({n_random} targets, "
        f"{sum(counts)} solutions)",
        worst,
        1e-9,
    )
    sec.checks.append(
        Check(
            "four solutions (elbow up/down, front/back) per generic target",
            f"{min(counts)}..{max(counts)} solutions",
            min(counts) == 4,
        )
    )
    target, pitch = (40.0, 10.0, 30.0), 0.2
    rows = ["| branch | theta1 | theta2 | theta3 | theta4 | theta5 |", "|---|---|---|---|---|---|"]
    for k, s in enumerate(arm5dof.geometric_ik(target, pitch)):
        rows.append(f"| {k + 1} | " + " | ".join(f"{np.degrees(a):.3f}" for a in s) + " |")

    def draw(path: Path) -> None:
        save_figure(arm5dof.draw_solutions(target, pitch)[0], path, dpi=110)

    sec.figures.append(("fig3_4_arm5dof_solutions.png", draw))
    sec.markdown += [
        f"All solutions [deg] for the gripper point {target} (paper 2's units) with pitch "
        f"phi = {pitch} rad, lengths {arm5dof.PAPER_LENGTHS}:",
        "",
        *rows,
    ]
    return sec
