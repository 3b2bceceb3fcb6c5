"""The paper-reproduction report (``toolkit report``).

Each section computes its numbers from the models, states the paper's claim
next to them, and says PASS or FAIL. The report is written as Markdown to
``DIR/report.md`` and ``DIR/index.html`` (with PNG figures); the command exits non-zero
when a check fails.
"""

from __future__ import annotations

import html
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import katana
from .loaders import load

__all__ = ["Check", "Section", "katana_section", "run_report"]


@dataclass(frozen=True)
class Check:
    """One claim of a paper, the toolkit's number for it, and whether it holds."""

    claim: str
    measured: str
    passed: bool


@dataclass
class Section:
    """A titled part of the report: checks plus free Markdown (tables)."""

    title: str
    checks: list[Check] = field(default_factory=list)
    markdown: list[str] = field(default_factory=list)
    figures: list[tuple[str, Callable[[Path], None]]] = field(default_factory=list)

    def check(self, claim: str, error: float, tol: float, unit: str = "") -> None:
        """Record a numeric check ``error <= tol``."""
        self.checks.append(Check(claim, f"max error {error:.3g}{unit} (tol {tol:g})", error <= tol))


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


def arm5dof_section(n_random: int = 1000, seed: int = 0) -> Section:
    """Paper 2: every geometric solution reproduces its target on the Pinocchio model."""
    from . import arm5dof

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
        arm5dof.draw_solutions(target, pitch).savefig(path, dpi=110)

    sec.figures.append(("fig3_4_arm5dof_solutions.png", draw))
    sec.markdown += [
        f"All solutions [deg] for the gripper point {target} (paper 2's units) with pitch "
        f"phi = {pitch} rad, lengths {arm5dof.PAPER_LENGTHS}:",
        "",
        *rows,
    ]
    return sec


def backlash_section() -> Section:
    """Paper 1, eqs. 16-17 and Fig. 6: the arm sags under backlash; compensation undoes it."""
    from . import backlash

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
    out = layer.output_angles(robot.random_q(2000, seed=1), full_output=True)
    sec.check(
        "eq. 16 fixed point theta = q + dtheta(M(theta)), 2000 commands",
        float(out.residual.max()),
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
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")

    sec.figures.append(("fig6_backlash.png", draw))
    return sec


def structures_section() -> Section:
    """Paper 3: eqs. 5-9 on the xacro models, point motion, closed-form IK, workspaces."""
    from . import structures

    sec = Section("Paper 3 - the five 3-DOF positioning structures")
    rows = [
        "| structure | analytic volume [m^3] | estimate [m^3] | solutions per target |",
        "|---|---|---|---|",
    ]
    robots = {}
    for name in structures.STRUCTURES:
        robot = load(name)
        robots[name] = robot
        a, b, c = (robot.params[k] for k in "abc")
        qs = robot.random_q(500, seed=0)
        err = max(np.abs(robot.fk(q) - structures.paper_T14(name, q, a, b, c)).max() for q in qs)
        sec.check(
            f"{name}: Pinocchio T14 = T12 T23 T34 of eqs. 5-9 (500 configurations)",
            float(err),
            1e-12,
        )
        rho = structures.default_rho(robot)
        worst, counts = 0.0, []
        for q in qs[:100]:
            T = robot.fk(q)
            target = T[:3, :3] @ rho + T[:3, 3]
            sols = structures.closed_form_ik(robot, target)
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
        rows.append(
            f"| {name} | {'' if exact is None else f'{exact:.4f}'} | {est.volume:.4f} | "
            f"{min(counts)}-{max(counts)} |"
        )
    sec.markdown += rows

    def draw(path: Path) -> None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(15, 3.4))
        for i, robot in enumerate(robots.values()):
            ax = fig.add_subplot(1, 5, i + 1, projection="3d")
            structures.draw_workspace(robot, n=3000, ax=ax)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)

    sec.figures.append(("structures_workspaces.png", draw))
    return sec


def bending_section() -> Section:
    """Paper 4: rolling geometry, the mimic model, cables, the inverse problem, Figs. 4-5."""
    from . import bending

    sec = Section("Paper 4 - cable-driven bending manipulator")
    R, d, h0 = 0.02, 0.016, 0.008
    geo = bending.Geometry(R, d, h0)
    rng = np.random.default_rng(0)
    worst = 0.0
    for links, n in ((1, 5), (2, 3), (3, 4), (4, 2)):
        robot = load("bending", links=links, n=n)
        for q in robot.random_q(100, seed=rng):
            a, p = bending.q_to_angles(q)
            worst = max(
                worst, float(np.abs(robot.fk(q) - bending.chain_pose(a, p, n, R, h0)).max())
            )
    sec.check("mimic-joint Pinocchio model = rolling closed form (1-4 links)", worst, 1e-12)
    g_err = 0.0
    for _ in range(500):
        a, p, n = rng.uniform(0, geo.alpha_m), rng.uniform(0, 2 * np.pi), int(rng.integers(1, 8))
        if n * a >= np.pi:
            continue
        pos = bending.link_pose(a, p, n, R, h0)[:3, 3]
        g_err = max(g_err, abs(np.arctan2(np.hypot(pos[0], pos[1]), -pos[2]) - n * a))
    sec.check("G = n alpha (the chord's angle), 500 random links", g_err, 1e-9, " rad")
    sign = float(
        np.abs(
            bending.paper_eq5_centre(0.2, 0.5, R, h0)[:2]
            + bending.element_transform(0.2, 0.5, R, h0)[:2, 3]
        ).max()
    )
    sec.check(
        "erratum: printed eq. 5 has x, y of O1 negated (|printed + rolling|)", sign, 1e-15, " m"
    )
    cab = 0.0
    for _ in range(300):
        a, p, n = rng.uniform(0, geo.alpha_m), rng.uniform(0, 2 * np.pi), int(rng.integers(1, 11))
        a2, p2 = bending.angles_from_cables(bending.cables_from_angles(a, p, n, R, d), n, R, d)
        cab = max(cab, abs(a2 - a), abs(np.angle(np.exp(1j * (p2 - p)))) if a > 1e-6 else 0.0)
    sec.check("cables -> angles round trip, all quadrants (psi = atan2(a2, a1))", cab, 1e-9, " rad")
    inv = 0.0
    for L_t in (0.0, 0.03):
        for _ in range(100):
            a, p, n = (
                rng.uniform(0, geo.alpha_m),
                rng.uniform(0, 2 * np.pi),
                int(rng.integers(1, 11)),
            )
            target = bending.chain_pose([a], [p], n, R, h0, L_t)[:3, 3]
            res = bending.inverse(target, n, R, d, h0, L_t)
            inv = max(inv, res.residual if res.success else np.inf)
    sec.check("inverse problem, both regimes, L_t = 0 and 30 mm (200 targets)", inv, 1e-9, " m")
    rows = [
        "| n | L_t [mm] | eq. 9 miss, hanging (n alpha <= 90 deg) | miss, curled |",
        "|---|---|---|---|",
    ]
    for n in (5, 10):
        for L_t in (0.02, 0.05, 0.1):
            hang = curl = 0.0
            for a in np.linspace(0.005, geo.alpha_m, 200):
                t = bending.chain_pose([a], [0.3], n, R, h0, L_t=L_t)[:3, 3]
                e = abs(bending.paper_inverse(t, n, L_t=L_t)[0] - a)
                if n * a <= np.pi / 2:
                    hang = max(hang, e)
                else:
                    curl = max(curl, e)
            rows.append(
                f"| {n} | {1e3 * L_t:.0f} | {np.degrees(hang):.1e} deg | "
                f"{np.degrees(curl):.2f} deg |"
            )
    sec.markdown += ["Paper's eqs. 9-10 against the exact inverse (alpha error):", "", *rows]

    def draw5(path: Path) -> None:
        fig = bending.draw_figure5()
        fig.savefig(path, dpi=110)

    def draw4(path: Path) -> None:
        fig = bending.draw_figure4()
        fig.savefig(path, dpi=110)

    sec.figures += [("fig5_bending_shapes.png", draw5), ("fig4_bending_curl.png", draw4)]
    return sec


BENCHMARK_FILE = Path("benchmarks") / "ik.json"


def benchmark_section(path: Path = BENCHMARK_FILE) -> Section | None:
    """IK benchmark figures, if ``benchmarks/ik.py --json benchmarks/ik.json`` has run."""
    import json

    if not path.is_file():
        return None
    data = json.loads(path.read_text(encoding="utf-8"))
    sec = Section(f"IK benchmark (TRAC-IK protocol, measured {data['date']})")
    rows = [
        "| robot | targets | success | mean | median | roboticstoolbox ik_LM (C++): "
        "success, median |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["numeric"]:
        other = r.get("roboticstoolbox")
        theirs = (
            f"{other['success_percent']:.2f} %, {other['median_ms']:.3f} ms"
            if other
            else "not installed"
        )
        rows.append(
            f"| {r['robot']} | {r['targets']} | {r['success_percent']:.2f} % | "
            f"{r['mean_ms']:.3f} ms | {r['median_ms']:.3f} ms | {theirs} |"
        )
    c = data["closed_form"]
    sec.markdown += [
        f"Budget {data['budget_ms']:g} ms per solve, tolerance {data['tol']:g}; figures from "
        f"{path} (rerun `python benchmarks/ik.py --json {path}` to refresh).",
        "",
        *rows,
        "",
        f"Closed forms: geometric_ik {c['geometric_ik_us']:.1f} us, katana.closed_form_ik "
        f"{c['katana_closed_form_ik_us']:.1f} us per target, batched "
        f"{c['batched_targets_per_s'] / 1e6:.2f} M targets/s.",
    ]

    def draw(out: Path) -> None:
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4))
        for r in data["numeric"]:
            ax.plot(r["percentiles_ms"], np.arange(101) / 100, label=r["robot"])
        ax.set_xscale("log")
        ax.set_xlabel("time per solve [ms]")
        ax.set_ylabel("fraction of solves finished")
        ax.grid(True, alpha=0.3)
        ax.legend()
        fig.savefig(out, dpi=110, bbox_inches="tight")

    sec.figures.append(("ik_benchmark.png", draw))
    return sec


SECTIONS: list[Callable[[], Section | None]] = [
    katana_section,
    arm5dof_section,
    backlash_section,
    structures_section,
    bending_section,
    benchmark_section,
]


def _have_matplotlib() -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
    except ImportError:
        return False
    return True


def _markdown_to_html(lines: list[str]) -> str:
    """The small Markdown subset the sections emit: paragraphs and pipe tables."""
    out, table = [], []

    def flush() -> None:
        if table:
            rows = [r for r in table if not set(r.replace("|", "").strip()) <= {"-", ":"}]
            cells = [
                [html.escape(c.strip()) for c in r.strip().strip("|").split("|")] for r in rows
            ]
            head = "".join(f"<th>{c}</th>" for c in cells[0])
            body = "".join(
                "<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in cells[1:]
            )
            out.append(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
            table.clear()

    for line in lines:
        if line.strip().startswith("|"):
            table.append(line)
            continue
        flush()
        if line.strip():
            out.append(f"<p>{html.escape(line)}</p>")
    flush()
    return "\n".join(out)


_CSS = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 4px 8px; text-align: left; }
.PASS { color: #13795b; font-weight: bold; } .FAIL { color: #b00020; font-weight: bold; }
img { max-width: 100%; border: 1px solid #eee; margin: 0.5em 0; }
"""


def run_report(output: Path, quiet: bool = False) -> int:
    """Run every section; write ``output/report.md``, ``output/index.html`` and the PNG
    figures; print progress and a summary. Returns 0 if every check passes."""
    output.mkdir(parents=True, exist_ok=True)
    lines = ["# Paper-reproduction report", ""]
    page = []
    failed = total = 0
    plots = _have_matplotlib()
    for i, make in enumerate(SECTIONS, start=1):
        start = time.perf_counter()
        if not quiet:
            print(
                f"[{i}/{len(SECTIONS)}] {make.__doc__.splitlines()[0] if make.__doc__ else ''}",
                flush=True,
            )
        sec = make()
        if sec is None:  # an optional section with nothing to show
            if not quiet:
                print("  (skipped: no data)")
            continue
        rows = []
        lines += [f"## {sec.title}", "", "| check | measured | result |", "|---|---|---|"]
        for c in sec.checks:
            total += 1
            failed += not c.passed
            verdict = "PASS" if c.passed else "FAIL"
            lines.append(f"| {c.claim} | {c.measured} | {verdict} |")
            rows.append(
                f"<tr><td>{html.escape(c.claim)}</td><td>{html.escape(c.measured)}</td>"
                f'<td class="{verdict}">{verdict}</td></tr>'
            )
            if not quiet:
                print(f"  [{verdict}] {c.claim}: {c.measured}")
        lines += ["", *sec.markdown, ""]
        figures = []
        for name, draw in sec.figures:
            if plots:
                import matplotlib.pyplot as plt

                draw(output / name)
                plt.close("all")
                lines += [f"![{name}]({name})", ""]
                figures.append(f'<img src="{name}" alt="{html.escape(name)}">')
            elif not quiet:
                print(f"  (matplotlib not installed: figure {name} skipped)")
        page.append(
            f"<h2>{html.escape(sec.title)}</h2>"
            "<table><thead><tr><th>check</th><th>measured</th><th>result</th></tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table>"
            + _markdown_to_html(sec.markdown)
            + "".join(figures)
        )
        if not quiet:
            if sec.markdown:
                print("\n".join("  " + m for m in sec.markdown))
            print(f"  ({time.perf_counter() - start:.1f} s)", flush=True)
    (output / "report.md").write_text("\n".join(lines), encoding="utf-8")
    verdict = f"{total - failed} of {total} checks passed"
    (output / "index.html").write_text(
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>Paper-reproduction report</title><style>{_CSS}</style></head><body>"
        f"<h1>Paper-reproduction report</h1><p><b>{verdict}</b>. Generated by "
        f"manipulator-toolkit; every number below is recomputed from the models.</p>"
        + "".join(page)
        + "</body></html>",
        encoding="utf-8",
    )
    print(f"{verdict}; report written to {output / 'index.html'} (and report.md)")
    return 0 if failed == 0 else 1
