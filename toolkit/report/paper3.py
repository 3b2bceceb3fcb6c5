"""Report section of [P3]: the five 3-DOF positioning structures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..papers import structures
from ..robot import Robot, load
from .checks import Section

__all__ = ["structures_section"]


def structures_section() -> Section:
    """Paper 3: eqs. 5-9 on the xacro models, point motion, closed-form IK, workspaces."""
    sec = Section("Paper 3 - the five 3-DOF positioning structures")
    rows = [
        "| structure | analytic volume [m^3] | estimate [m^3] | solutions per target |",
        "|---|---|---|---|",
    ]
    robots = [load(name) for name in structures.STRUCTURES]
    rows += [_check_structure(sec, robot) for robot in robots]
    sec.markdown += rows

    def draw(path: Path) -> None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(12, 4.0 * len(robots)))
        for i, robot in enumerate(robots):
            flat = [fig.add_subplot(len(robots), 3, 3 * i + k + 1) for k in range(2)]
            structures.draw_sections(robot, axes=flat, n=90)
            ax = fig.add_subplot(len(robots), 3, 3 * i + 3, projection="3d")
            structures.draw_workspace(robot, n=3000, ax=ax)
        fig.suptitle(
            "[P3] reach space of M: exact sections (closed-form IK on a grid; + marks the "
            "base axis) and a sampled 3-D view, equal scales",
            fontsize=10,
        )
        fig.tight_layout(rect=(0, 0, 1, 0.98))
        fig.savefig(path, dpi=90, bbox_inches="tight")
        plt.close(fig)

    sec.figures.append(("structures_workspaces.png", draw))
    return sec


def _check_structure(sec: Section, robot: Robot) -> str:
    """Checks of one structure (matrices, closed-form IK, volume); returns its table row."""
    name = robot.name
    a, b, c = (float(robot.params[k]) for k in "abc")
    qs = robot.random_q(500, seed=0)
    err = max(np.abs(robot.fk(q) - structures.paper_T14(name, q, a, b, c)).max() for q in qs)
    sec.check(
        f"{name}: Pinocchio T14 = T12 T23 T34 of eqs. 5-9 (500 configurations)", float(err), 1e-12
    )
    rho = structures.default_rho(robot)
    worst, counts = 0.0, []
    for q in qs[:100]:
        T = robot.fk(q)
        sols = structures.closed_form_ik(robot, T[:3, :3] @ rho + T[:3, 3])
        counts.append(len(sols))
        worst = max(worst, min((np.abs(s - q).max() for s in sols), default=np.inf))
    sec.check(
        f"{name}: closed-form IK recovers the joint values (100 targets)",
        float(worst),
        1e-8,
        " (rad or m)",
    )
    est = structures.workspace_volume(robot, n=100_000)
    exact = structures.analytic_volume(robot)
    if exact is not None:
        sec.check(
            f"{name}: workspace volume vs analytic",
            abs(est.volume / exact - 1),
            0.03,
            " (relative)",
        )
    shown = "none (no closed form)" if exact is None else f"{exact:.4f}"
    return f"| {name} | {shown} | {est.volume:.4f} | {min(counts)}-{max(counts)} |"
