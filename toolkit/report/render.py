"""Writing the report: run the sections, then Markdown, HTML and PNG figures."""

from __future__ import annotations

import html
import time
from collections.abc import Callable
from pathlib import Path

from .._version import __version__
from .benchmark import benchmark_section
from .checks import Section
from .maps import maps_section
from .paper1 import backlash_section, katana_section
from .paper2 import arm5dof_section
from .paper3 import structures_section
from .paper4 import bending_section

__all__ = ["SECTIONS", "compute", "draw_figures", "run_report", "to_html", "to_markdown"]

SECTIONS: list[Callable[[], Section | None]] = [
    katana_section,
    backlash_section,
    arm5dof_section,
    structures_section,
    bending_section,
    maps_section,
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
    out: list[str] = []
    table: list[str] = []

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


def _first_sentence(doc: str) -> str:
    """A docstring's first sentence, whole (its lines joined; a period after "eq.",
    "eqs.", "Fig." or "e.g." ends none), in plain words (no RST markup), for the console."""
    import re

    paragraph = " ".join(line.strip() for line in doc.strip().split("\n\n")[0].splitlines())
    paragraph = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", paragraph).replace("``", "")
    for end in re.finditer(r"\. ", paragraph):
        word = paragraph[: end.start()].rsplit(" ", 1)[-1].lower()
        if word not in ("eq", "eqs", "fig", "figs", "e.g", "i.e", "cf", "vs"):
            return paragraph[: end.start() + 1]
    return paragraph


def compute(quiet: bool = False) -> list[Section]:
    """Run every section (the numbers), printing progress; sections with no data drop out."""
    done = []
    for i, make in enumerate(SECTIONS, start=1):
        start = time.perf_counter()
        if not quiet:
            title = _first_sentence(make.__doc__) if make.__doc__ else make.__name__
            print(f"[{i}/{len(SECTIONS)}] {title}", flush=True)
        sec = make()
        if sec is None:  # an optional section with nothing to show
            if not quiet:
                print("  (skipped: no data)")
            continue
        if not quiet:
            for c in sec.checks:
                print(f"  [{_verdict(c.passed)}] {c.claim}: {c.measured}")
            if sec.markdown:
                print("\n".join("  " + m for m in sec.markdown))
            print(f"  ({time.perf_counter() - start:.1f} s)", flush=True)
        done.append(sec)
    return done


def _verdict(passed: bool) -> str:
    return "PASS" if passed else "FAIL"


def draw_figures(sections: list[Section], output: Path, quiet: bool = False) -> list[str]:
    """Write every section's PNG figures into ``output``; returns the file names written."""
    if not _have_matplotlib():
        if not quiet:
            print("  (matplotlib not installed: figures skipped)")
        return []
    import matplotlib.pyplot as plt

    written = []
    for sec in sections:
        for name, draw in sec.figures:
            draw(output / name)
            plt.close("all")
            written.append(name)
    return written


def _headings(sections: list[Section]) -> list[tuple[str | None, str]]:
    """(paper heading or None, section heading) per section: consecutive sections of one
    paper ("Paper 1 - Katana 6M: ...") share one paper heading, the part after ":" heads
    each of them."""
    out: list[tuple[str | None, str]] = []
    previous = None
    for sec in sections:
        paper, sep, part = sec.title.partition(": ")
        if not sep:
            out.append((sec.title, ""))
            previous = None
            continue
        out.append((None if paper == previous else paper, part))
        previous = paper
    return out


def to_markdown(sections: list[Section], figures: list[str]) -> str:
    """The report as Markdown: a check table, the tables and the figures of each section."""
    lines = ["# Paper-reproduction report", ""]
    for sec, (paper, part) in zip(sections, _headings(sections), strict=True):
        lines += [f"## {paper}", ""] if paper else []
        lines += [f"### {part}", ""] if part else []
        if sec.checks:  # a section of figures only has no check table
            lines += ["| check | measured | result |", "|---|---|---|"]
            lines += [f"| {c.claim} | {c.measured} | {_verdict(c.passed)} |" for c in sec.checks]
        lines += ["", *sec.markdown, ""]
        lines += [f"![{n}]({n})\n" for n, _ in sec.figures if n in figures]
    return "\n".join(lines)


def to_html(sections: list[Section], figures: list[str], verdict: str) -> str:
    """The report as one HTML page (index.html)."""
    page = []
    for sec, (paper, part) in zip(sections, _headings(sections), strict=True):
        heading = f"<h2>{html.escape(paper)}</h2>" if paper else ""
        heading += f"<h3>{html.escape(part)}</h3>" if part else ""
        rows = "".join(
            f"<tr><td>{html.escape(c.claim)}</td><td>{html.escape(c.measured)}</td>"
            f'<td class="{_verdict(c.passed)}">{_verdict(c.passed)}</td></tr>'
            for c in sec.checks
        )
        images = "".join(
            f'<img src="{n}" alt="{html.escape(n)}">' for n, _ in sec.figures if n in figures
        )
        table = (
            "<table><thead><tr><th>check</th><th>measured</th><th>result</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>"
            if rows
            else ""
        )
        page.append(heading + table + _markdown_to_html(sec.markdown) + images)
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>Paper-reproduction report</title><style>{_CSS}</style></head><body>"
        f"<h1>Paper-reproduction report</h1><p><b>{verdict}</b>. Generated by "
        f"manipulator-toolkit {__version__}; every number in the paper sections is recomputed "
        "from the models by this run. The IK benchmark section says where and when its "
        "figures were measured.</p>" + "".join(page) + "</body></html>"
    )


def run_report(output: Path, quiet: bool = False) -> int:
    """Run every section; write ``output/report.md``, ``output/index.html`` and the PNG
    figures; print progress and a summary. Returns 0 if every check passes."""
    output.mkdir(parents=True, exist_ok=True)
    sections = compute(quiet)
    figures = draw_figures(sections, output, quiet)
    checks = [c for sec in sections for c in sec.checks]
    failed = sum(not c.passed for c in checks)
    verdict = f"{len(checks) - failed} of {len(checks)} checks passed"
    (output / "report.md").write_text(to_markdown(sections, figures), encoding="utf-8")
    (output / "index.html").write_text(to_html(sections, figures, verdict), encoding="utf-8")
    print(f"{verdict}; report written to {output / 'index.html'} (and report.md)")
    return 0 if failed == 0 else 1
