"""Report section of [P4]: the cable-driven bending manipulator."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..papers import bending
from ..robot import load
from .checks import Section, save_figure

__all__ = ["bending_section"]


R, D, H0 = 0.02, 0.016, 0.008  # the element of the figures [m]


def bending_section() -> Section:
    """Paper 4: rolling geometry, the mimic model, cables, the inverse problem, Figs. 4-5."""
    sec = Section("Paper 4 - cable-driven bending manipulator")
    rng = np.random.default_rng(0)
    geo = bending.Geometry(R, D, H0)
    _model_checks(sec, rng)
    _geometry_checks(sec, rng, geo)
    sec.markdown += ["Paper's eqs. 9-10 against the exact inverse (alpha error):", "", *_eq9(geo)]

    def draw5(path: Path) -> None:
        save_figure(bending.draw_figure5()[0], path, dpi=110, bbox_inches="tight")

    def draw4(path: Path) -> None:
        save_figure(bending.draw_figure4(), path, dpi=110, bbox_inches="tight")

    sec.figures += [("fig5_bending_shapes.png", draw5), ("fig4_bending_curl.png", draw4)]
    return sec


def _model_checks(sec: Section, rng: np.random.Generator) -> None:
    """The mimic-joint xacro model against the rolling closed form."""
    worst = 0.0
    for links, n in ((1, 5), (2, 3), (3, 4), (4, 2)):
        robot = load("bending", links=links, n=n)
        for q in robot.random_q(100, seed=rng):
            a, p = bending.q_to_angles(q)
            closed = bending.chain_pose(list(a), list(p), n, R, H0)
            worst = max(worst, float(np.abs(robot.fk(q) - closed).max()))
    sec.check("mimic-joint Pinocchio model = rolling closed form (1-4 links)", worst, 1e-12)


def _geometry_checks(sec: Section, rng: np.random.Generator, geo: bending.Geometry) -> None:
    """G = n alpha, the eq. 5 erratum, the cable round trip and the inverse problem."""
    g_err = 0.0
    for _ in range(500):
        a, p, n = rng.uniform(0, geo.alpha_m), rng.uniform(0, 2 * np.pi), int(rng.integers(1, 8))
        if n * a >= np.pi:
            continue
        pos = bending.link_pose(a, p, n, R, H0)[:3, 3]
        g_err = max(g_err, abs(np.arctan2(np.hypot(pos[0], pos[1]), -pos[2]) - n * a))
    sec.check("G = n alpha (the chord's angle), 500 random links", g_err, 1e-9, " rad")
    printed = bending.paper_eq5_centre(0.2, 0.5, R, H0)[:2]
    sign = float(np.abs(printed + bending.element_transform(0.2, 0.5, R, H0)[:2, 3]).max())
    sec.check(
        "erratum: printed eq. 5 has x, y of O1 negated (|printed + rolling|)", sign, 1e-15, " m"
    )
    cab = 0.0
    for _ in range(300):
        a, p, n = rng.uniform(0, geo.alpha_m), rng.uniform(0, 2 * np.pi), int(rng.integers(1, 11))
        a2, p2 = bending.angles_from_cables(bending.cables_from_angles(a, p, n, R, D), n, R, D)
        cab = max(cab, abs(a2 - a), abs(np.angle(np.exp(1j * (p2 - p)))) if a > 1e-6 else 0.0)
    sec.check("cables -> angles round trip, all quadrants (psi = atan2(a2, a1))", cab, 1e-9, " rad")
    inv = 0.0
    for L_t in (0.0, 0.03):
        for _ in range(100):
            a, p = rng.uniform(0, geo.alpha_m), rng.uniform(0, 2 * np.pi)
            n = int(rng.integers(1, 11))
            target = bending.chain_pose([a], [p], n, R, H0, L_t)[:3, 3]
            res = bending.inverse(target, n, R, D, H0, L_t)
            inv = max(inv, res.residual if res.success else np.inf)
    sec.check("inverse problem, both regimes, L_t = 0 and 30 mm (200 targets)", inv, 1e-9, " m")


def _eq9(geo: bending.Geometry) -> list[str]:
    """Table rows: how far the paper's eqs. 9-10 miss alpha, hanging and curled."""
    rows = [
        "| n | L_t [mm] | eq. 9 miss, hanging (n alpha <= 90 deg) | miss, curled |",
        "|---|---|---|---|",
    ]
    for n in (5, 10):
        for L_t in (0.02, 0.05, 0.1):
            hang = curl = 0.0
            for a in np.linspace(0.005, geo.alpha_m, 200):
                t = bending.chain_pose([a], [0.3], n, R, H0, L_t=L_t)[:3, 3]
                e = abs(bending.paper_inverse(t, n, L_t=L_t)[0] - a)
                if n * a <= np.pi / 2:
                    hang = max(hang, e)
                else:
                    curl = max(curl, e)
            rows.append(
                f"| {n} | {1e3 * L_t:.0f} | {np.degrees(hang):.1e} deg | "
                f"{np.degrees(curl):.2f} deg |"
            )
    return rows
