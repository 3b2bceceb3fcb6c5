"""Report sections of [P1]: the Katana 6M's forward kinematics, drive torques and backlash."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..papers import backlash, katana
from ..robot import load
from .checks import Check, Section, save_figure

__all__ = ["backlash_section", "katana_section"]


def katana_section(n_random: int = 1000, seed: int = 0) -> Section:
    """Paper 1: sanity cases (18)-(20), closed form vs Pinocchio vs DH product, eq. 1 torques."""
    sec = Section("Paper 1 - Katana 6M: forward kinematics and drive torques")
    L = katana.KatanaLengths()
    robot = load("katana_6m180")
    base = np.eye(4)
    base[2, 3] = L.base_height
    reach = L.a2 + L.a3 + L.a4 + L.a5
    cases = {
        "(18) theta = 0 -> p = (a2 + a3, 0, a4 + a5)": (
            np.zeros(5),
            np.array([L.a2 + L.a3, 0.0, L.a4 + L.a5]),
        ),
        "(19) theta4 = -pi/2 -> p = (a2 + a3 + a4 + a5, 0, 0)": (
            np.array([0, 0, 0, -np.pi / 2, 0]),
            np.array([reach, 0.0, 0.0]),
        ),
        "(20) theta2 = pi/2, theta4 = -pi/2 -> p = (0, 0, a2 + a3 + a4 + a5)": (
            np.array([0, np.pi / 2, 0, -np.pi / 2, 0]),
            np.array([0.0, 0.0, reach]),
        ),
    }
    for claim, (q, p) in cases.items():
        closed = katana.closed_form_fk(q)[:3, 3]
        pino = (np.linalg.inv(base) @ robot.fk(q))[:3, 3]
        err = max(np.abs(closed - p).max(), np.abs(pino - p).max())
        sec.check(f"6M180 {claim} (closed form and Pinocchio)", err, 1e-12, " m")

    rng = np.random.default_rng(seed)
    qs = robot.random_q(n_random, rng)
    closed = katana.closed_form_fk(qs)
    pino = np.linalg.inv(base) @ robot.fk(qs)
    sec.check(
        f"6M180 closed form (eqs. 12-15) = Pinocchio at {n_random} random configurations",
        float(np.abs(closed - pino).max()),
        1e-12,
    )
    for variant in katana.VARIANTS:
        model = load(f"katana_{variant}")
        qs = model.random_q(n_random, rng)
        pino = np.linalg.inv(base) @ model.fk(qs)
        dh = np.stack([katana.dh_fk(q, variant) for q in qs])
        sec.check(
            f"{variant.upper()} Pinocchio = product of eq. 2 over Table 2 at {n_random} "
            "random configurations",
            float(np.abs(dh - pino).max()),
            1e-12,
        )

    rows = [
        "| joint | P [W] | n [rpm] | eta_M | i_R | eta_R | M_H [N m] (eq. 1) |",
        "|---|---|---|---|---|---|---|",
    ]
    for i, d in enumerate(katana.DRIVES, start=1):
        rows.append(
            f"| {i} | {d.power} | {d.speed_rpm} | {d.motor_efficiency} | {d.gear_ratio} | "
            f"{d.gear_efficiency} | {d.nominal_torque:.4f} |"
        )
    sec.markdown += ["Nominal output torques of the 6M180 drives (paper 1, eq. 1):", "", *rows]
    return sec


def backlash_section() -> Section:
    """Paper 1, eqs. 16-17 and Fig. 6: the arm sags under backlash; compensation undoes it."""
    sec = Section("Paper 1 - Katana 6M: joint backlash (eqs. 16-17, Fig. 6)")
    data = backlash.figure6()
    sec.checks.append(
        Check(
            "Fig. 6: backlash (delta = 0.035 rad, 0.5 kg) visibly degrades positioning; "
            "the horizontal arm B sags",
            f"max deviation {1e3 * data.max_deviation_b:.1f} mm (A -> B), "
            f"{1e3 * data.max_deviation_b2:.1f} mm (A -> B'); sag at B "
            f"{1e3 * (data.ideal_b[-1, 2] - data.actual_b[-1, 2]):.1f} mm",
            data.max_deviation_b > 1e-3
            and data.max_deviation_b2 > 1e-3
            and data.actual_b[-1, 2] < data.ideal_b[-1, 2],
        )
    )
    robot = load("katana_6m180")
    layer = backlash.Backlash(robot, payload=0.5)
    out = layer.solve(robot.random_q(2000, seed=1))
    sec.check(
        "eq. 16 fixed point theta = q + dtheta(M(theta)), 2000 commands",
        float(np.max(out.residual)),
        1e-9,
        " rad",
    )
    worst = 0.0
    for q in robot.random_q(20, seed=2):
        target = robot.fk(q)
        res = layer.compensate(target, mask=[1, 1, 1, 1, 1, 0])
        worst = max(worst, res.position_error if res.success else np.inf)
    sec.check("compensation puts the backlash-affected tool on 20 targets", worst, 1e-6, " m")
    emap = backlash.error_map(layer, 20_000, seed=3)
    sec.markdown += [
        "Tool-position error from backlash over 20,000 random commands (6M180, 0.5 kg): "
        f"mean {1e3 * emap.mean:.2f} mm, median {1e3 * emap.median:.2f} mm, "
        f"95th percentile {1e3 * emap.p95:.2f} mm, max {1e3 * emap.max:.2f} mm.",
    ]

    def draw(path: Path) -> None:
        ax = backlash.draw_figure6(data)
        save_figure(ax, path, dpi=120, bbox_inches="tight")

    sec.figures.append(("fig6_backlash.png", draw))
    _along_a_motion(sec, layer)
    return sec


def _along_a_motion(sec: Section, layer: backlash.Backlash) -> None:
    """[P1] along a motion: the motion's torques beside gravity's, and compensation."""
    motion = backlash.pick_and_place()
    data = backlash.along(layer, motion, 200.0)
    sec.check("eq. 16 with the motion's torques (-rnea) along a 5 s pick and place, "
              f"{len(data.t)} samples", float(np.max(data.residual)), 1e-9, " rad")  # fmt: skip
    _, commands = backlash.compensate_motion(layer, motion, 200.0)
    s = motion.at_rate(layer.robot, 200.0)  # the intended outputs
    reached, _ = backlash.dynamic_outputs(layer, commands, s.qd, s.qdd)
    sec.check("compensated commands put the joint outputs on the intended motion",
              float(np.max(np.abs(reached - s.q))), 1e-9, " rad")  # fmt: skip
    gaps = backlash.parting(layer)
    sec.markdown += [
        "",
        "Along a 5 s pick and place (within the velocity limits, 0.5 kg): tool deviation "
        f"up to {1e3 * data.deviation_static.max():.1f} mm with gravity's torques alone, "
        f"{1e3 * data.deviation_dynamic.max():.1f} mm with the motion's; the two part by "
        f"{1e3 * data.parting:.1f} mm. Joints 1 and 5, which gravity leaves unloaded, rest "
        "mid-gap at a standstill and are pushed to one side by any acceleration, so the "
        f"readings part by {1e3 * gaps[1][0]:.1f} mm even at {gaps[0][0]:g} s. The same "
        "motion faster: "
        + ", ".join(f"{d:g} s ({v:.2f} of the velocity limit): {1e3 * g:.1f} mm"
                    for d, g, v in zip(*gaps, strict=True)) + ".",
    ]  # fmt: skip

    def draw(path: Path) -> None:
        import matplotlib.pyplot as plt

        fig, (left, right) = plt.subplots(1, 2, figsize=(13, 4.2))
        backlash.draw_motion_backlash(data, left)
        backlash.draw_parting(gaps, right)
        save_figure(left, path, dpi=110, bbox_inches="tight")
        plt.close(fig)

    sec.figures.append(("backlash_motion.png", draw))
