"""Report section of the IK benchmark, read from the figures shipped with the package
(``toolkit/report/ik_benchmark.json``, written by ``benchmarks/ik.py --json``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from .checks import Section

__all__ = ["BENCHMARK_FILE", "benchmark_section"]

BENCHMARK_FILE = Path(__file__).resolve().parent / "ik_benchmark.json"  # installed with it
"""Where ``python benchmarks/ik.py --json`` writes its figures: the source checkout's
``benchmarks/`` folder (absent from an installed wheel, so the section is skipped)."""


def benchmark_section(path: Path | None = None) -> Section | None:
    """IK benchmark figures, if ``benchmarks/ik.py --json toolkit/report/ik_benchmark.json``
    has run.

    ``path`` defaults to :data:`BENCHMARK_FILE`."""
    path = BENCHMARK_FILE if path is None else path
    if not path.is_file():
        return None
    data = json.loads(path.read_text(encoding="utf-8"))
    if "machine" not in data:  # an older file: its figures are not comparable
        return None
    sec = Section(f"IK benchmark (TRAC-IK protocol, measured {data['date']})")
    rows = [
        "| robot | solver | success | mean | median | median, ours / theirs |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["numeric"]:
        ours = r["solvers"]["toolkit Robot.ik"]["median_ms"]
        for label, f in r["solvers"].items():
            ratio = "(ours)" if label.startswith("toolkit") else f"{ours / f['median_ms']:.2f}"
            rows.append(
                f"| {r['robot']} | {label} | {f['success_percent']:.2f} % | "
                f"{f['mean_ms']:.3f} ms | {f['median_ms']:.3f} ms | {ratio} |"
            )
        rows.append(
            f"| {r['robot']} | toolkit Robot.ik_batch | {r['batch_success_percent']:.2f} % | "
            f"{r['batch_solves_per_s']:,.0f} solves/s (throughput) | n/a | n/a |"
        )
    c = data["closed_form"]
    sec.markdown += [
        f"Measured on {data['machine']} on {data['date']} by `benchmarks/ik.py` (not "
        "recomputed by this report: a benchmark takes minutes and needs the `bench` extra). "
        f"{data['targets']} random reachable targets per robot, budget {data['budget_ms']:g} ms "
        f"per solve, tolerance {data['tol']:g}; every solver judged by the same FK check.",
        "",
        *rows,
        "",
        f"Closed forms: geometric_ik {c['geometric_ik_us']:.1f} us, katana.closed_form_ik "
        f"{c['katana_closed_form_ik_us']:.1f} us per target, batched "
        f"{c['batched_targets_per_s'] / 1e6:.2f} M targets/s.",
    ]

    sec.figures.append(("ik_benchmark.png", lambda out: _draw(data, out)))
    return sec


def _draw(data: dict[str, Any], out: Path) -> None:
    """Per robot, the fraction of solves done against the time per solve."""
    import matplotlib.pyplot as plt

    robots = data["numeric"]
    cols = min(3, len(robots))
    rows_ = (len(robots) + cols - 1) // cols
    fig, axes = plt.subplots(
        rows_, cols, figsize=(4 * cols, 3.2 * rows_), sharex=True, sharey=True, squeeze=False
    )
    for ax, r in zip(axes.flat, robots, strict=False):
        for label, f in r["solvers"].items():
            ax.plot(f["percentiles_ms"], np.arange(101) / 100, label=label)
        ax.set_title(r["robot"], fontsize=10)
        ax.set_xscale("log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
    for ax in axes.flat[len(robots) :]:
        ax.set_visible(False)
    for i, ax in enumerate(axes.flat[: len(robots)]):
        if i + cols >= len(robots):  # nothing drawn below it: it carries the time axis
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel("time per solve [ms]")
    for ax in axes[:, 0]:
        ax.set_ylabel("fraction of solves done")
    fig.tight_layout()
    fig.savefig(out, dpi=110, bbox_inches="tight")
