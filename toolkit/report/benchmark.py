"""Report section of the IK benchmark, read from ``benchmarks/ik.json`` when present."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .checks import Section

__all__ = ["BENCHMARK_FILE", "benchmark_section"]

BENCHMARK_FILE = Path(__file__).resolve().parents[2] / "benchmarks" / "ik.json"
"""Where ``python benchmarks/ik.py --json`` writes its figures: the source checkout's
``benchmarks/`` folder (absent from an installed wheel, so the section is skipped)."""


def benchmark_section(path: Path | None = None) -> Section | None:
    """IK benchmark figures, if ``benchmarks/ik.py --json benchmarks/ik.json`` has run.

    ``path`` defaults to :data:`BENCHMARK_FILE`."""
    path = BENCHMARK_FILE if path is None else path
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
