"""The documentation runs: code blocks of README.md and docs/*.md, doctests, the API page."""

from __future__ import annotations

import doctest
import re
from pathlib import Path

import numpy as np
import pytest

import toolkit
from toolkit.cli import apidoc as _apidoc

ROOT = Path(__file__).resolve().parents[2]
BLOCK = re.compile(r"```python\n(.*?)```", re.S)
PAGES = [
    p
    for p in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    if BLOCK.search(p.read_text(encoding="utf-8"))
]


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_python_blocks_run(page, tmp_path, monkeypatch):
    blocks = BLOCK.findall(page.read_text(encoding="utf-8"))
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": f"docs_{page.stem}"}
    for i, code in enumerate(blocks):
        exec(compile(code, f"{page.name}[block {i}]", "exec"), namespace)


def test_pages_with_examples_exist():
    have = {p.name for p in PAGES}
    assert {"README.md", "backlash.md", "structures.md", "bending.md", "katana.md"} <= have


@pytest.mark.parametrize("module", ["toolkit", "toolkit.robot.loading"])
def test_docstring_examples(module):
    import importlib

    result = doctest.testmod(importlib.import_module(module), verbose=False)
    assert result.attempted > 0 and result.failed == 0


def test_api_reference_is_current():
    committed = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert committed == _apidoc.render(), "regenerate: python -m toolkit.cli.apidoc > docs/api.md"
    for name in toolkit.__all__:
        if not name[0].isupper() or name in ("EXAMPLE_ROBOTS",):
            continue
        assert name in committed


def test_api_reference_lists_every_public_name():
    """Every name each package's ``__all__`` lists, the facade's own, and every public
    method of a class built from parts (``Robot``'s from its mixins) has its line."""
    import importlib
    import inspect

    committed = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    missing = []
    for module in _apidoc.MODULES:
        mod = importlib.import_module(module)
        for name in getattr(mod, "__all__", []):
            if not re.search(rf"[*`]{re.escape(name)}[`(]", committed):
                missing.append(f"{module}.{name}")
            obj = getattr(mod, name)
            if inspect.isclass(obj) and module != "toolkit":
                missing += [f"{module}.{name}.{m}" for m in _apidoc.members(obj)
                            if f"`{m}" not in committed]  # fmt: skip
    assert not missing, missing
    robot = set(_apidoc.members(toolkit.Robot))
    assert {"ik", "ik_all", "ik_all_batch", "ik_path", "in_collision", "fk"} <= robot
    assert "toolkit.calibration" in committed and "`warmup(" in committed


def test_notebooks_are_stored_without_outputs():
    import json

    books = sorted((ROOT / "notebooks").glob("*.ipynb"))
    assert len(books) >= 6
    for book in books:
        cells = json.loads(book.read_text(encoding="utf-8"))["cells"]
        for cell in cells:
            if cell["cell_type"] == "code":
                assert not cell.get("outputs") and cell.get("execution_count") is None, book.name


def test_ik_page_quotes_the_solver_constants():
    """docs/ik.md states the damping and the stall rule; they must be the code's."""
    from toolkit import ik

    page = (ROOT / "docs" / "ik.md").read_text(encoding="utf-8")
    damping = re.findall(r"lambda = ([0-9.e+-]+) E \+ ([0-9.e+-]+)", page)
    assert damping, "docs/ik.md no longer states the damping"
    for factor, floor in damping:
        assert (float(factor), float(floor)) == (ik.DAMPING, ik.LAMBDA_MIN)
    stall = re.findall(r"less than 0\.1 % in (\d+) iterations", page)
    assert stall and all(int(k) == ik.STALL for k in stall)


def test_references_cover_every_citation():
    """Every [Pn] cited in the docs or docstrings is listed in docs/references.md, and no
    page points at a docs file that does not exist."""
    refs = (ROOT / "docs" / "references.md").read_text(encoding="utf-8")
    texts = [p.read_text(encoding="utf-8") for p in ROOT.glob("docs/*.md")]
    texts += [p.read_text(encoding="utf-8") for p in (ROOT / "toolkit").rglob("*.py")]
    texts += [p.read_text(encoding="utf-8") for p in (ROOT / "urdf").glob("*.xacro")]
    cited = set().union(*(re.findall(r"\[P\d\]", t) for t in texts))
    assert cited == {"[P1]", "[P2]", "[P3]", "[P4]"}
    for key in cited:
        assert f"**{key}**" in refs
    for text in texts:
        for page in re.findall(r"docs/([a-z0-9_]+\.md)", text):
            assert (ROOT / "docs" / page).is_file(), f"dangling reference docs/{page}"


def test_reliability_page_quotes_the_code_ranges():
    from toolkit import bending, ik
    from toolkit.common import validate as _validate

    page = (ROOT / "docs" / "reliability.md").read_text(encoding="utf-8")
    assert f"(0, {ik.MAX_TOL:g}]" in page
    assert f"at most 10^{len(str(_validate.MAX_COUNT)) - 1}" in page
    assert f"1 ... {bending.MAX_ELEMENTS} in the functions" in page
    with pytest.raises(toolkit.GeometryError, match="at most 40 elements"):
        toolkit.urdf_text("bending", n=41)
    toolkit.urdf_text("bending", n=40, links=1)  # the documented largest model renders


def test_every_notebook_is_listed_and_its_extra_installs_what_it_needs():
    """A user runs ``pip install ".[notebooks]"`` and opens any notebook (the audit: notebook
    07 failed with "a map store needs zarr", and was listed nowhere)."""
    import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    notebooks_extra = " ".join(extras["optional-dependencies"]["notebooks"])
    listed = (ROOT / "notebooks" / "README.md").read_text()
    for book in sorted((ROOT / "notebooks").glob("*.ipynb")):
        assert book.name in listed, f"{book.name} is not listed in notebooks/README.md"
        text = book.read_text()
        if "store=" in text or "client=" in text:
            for package in extras["optional-dependencies"]["maps"]:
                name = package.split(">")[0].split("[")[0]
                assert name in notebooks_extra, f"{book.name} needs {name}: not in the extra"
        for package in ("matplotlib", "meshcat"):
            if f"import {package}" in text or "toolkit.viz" in text:
                assert package in notebooks_extra
        if "time_optimal" in text:  # the motion extra
            assert "toppra" in notebooks_extra, f"{book.name} needs toppra"


def test_the_fast_tier_the_readme_names_leaves_out_only_marked_tests(pytestconfig):
    """README's fast tier is ``pytest -m "not slow"``: the marker is registered (with
    --strict-markers a typo fails), and the notebooks, which no decorator can mark, are
    marked by tests/conftest.py."""
    import conftest

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert '.venv/bin/pytest -m "not slow"' in readme
    assert any(m.startswith("slow:") for m in pytestconfig.getini("markers"))
    assert "--strict-markers" in pytestconfig.getini("addopts")

    class Item:
        def __init__(self, name: str) -> None:
            self.path, self.marks = Path(name), []

        def add_marker(self, mark: pytest.MarkDecorator) -> None:
            self.marks.append(mark.name)

    items = [Item("notebooks/01_quickstart.ipynb"), Item("tests/ik/test_ik.py")]
    conftest.pytest_collection_modifyitems(pytestconfig, items)  # type: ignore[arg-type]
    assert [i.marks for i in items] == [["slow"], []]


_HASH = re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b")
"""A commit hash as the docs quoted them (7 to 40 hex digits, letters and digits both)."""


USER_PAGES = sorted(
    p.name for p in (ROOT / "docs").glob("*.md") if p.name not in ("benchmarks.md", "api.md")
)
"""Every docs page but the benchmarks' (their history) and api.md (generated)."""


@pytest.mark.parametrize("page", USER_PAGES)
def test_a_users_page_is_short_and_quotes_no_commit(page):
    """The user pages read as guides: under 300 lines, no commit hashes. The measured
    history, the peers and the commits belong to docs/benchmarks.md."""
    text = (ROOT / "docs" / page).read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 300, f"docs/{page}: {len(text.splitlines())} lines"
    assert not _HASH.findall(text), f"docs/{page} quotes commits {_HASH.findall(text)[:5]}"


def test_the_readme_quotes_no_commit():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert not _HASH.findall(text), _HASH.findall(text)[:5]


_FIRST = re.compile(r"first `(\w+)`[^.;]*? about (\d+) s")
_COMPILED = re.compile(
    r"first `(\w+)`[^.;(]*?\s+about\s+\d+\s+s\s+\(compiled\s+after\s+about\s+(\d+)\s+s\)"
)


@pytest.mark.parametrize("page", ["README.md", "docs/ik.md", "docs/reliability.md"])
def test_the_first_call_figures_quoted_are_the_benchmarks(page):
    """ "The first `ik` ... about 16 s": each first-call figure a page quotes is the one
    ``benchmarks/first_use.py`` wrote to toolkit/report/first_calls_benchmark.json,
    rounded to the second (a re-run that changes it fails here until the page follows)."""
    import json

    figures = json.loads((ROOT / "toolkit" / "report" / "first_calls_benchmark.json").read_text())
    text = (ROOT / page).read_text(encoding="utf-8")
    quoted = _FIRST.findall(text)
    assert quoted, f"{page} quotes no first-call figure"
    for call, seconds in quoted:
        measured = float(np.median(figures[f"first_{call}_s"]))
        assert int(seconds) == round(measured), (
            f"{page}: first {call} {seconds} s, JSON {measured:.1f} s"
        )
    compiled = _COMPILED.findall(text)
    assert compiled, f"{page} quotes no time until the first call's kernels run compiled"
    for call, seconds in compiled:  # "(compiled after about 20 s)"
        measured = float(np.median(figures[f"first_{call}_compiled_after_s"]))
        assert int(seconds) == round(measured), (
            f"{page}: first {call} compiled after {seconds} s, JSON {measured:.1f} s"
        )


def test_the_first_calls_table_quotes_its_json():
    """docs/benchmarks.md's first-calls table: each call's medians (background, compiled
    after, wait) are first_calls_benchmark.json's, to the tenth of a second."""
    import json

    figures = json.loads((ROOT / "toolkit" / "report" / "first_calls_benchmark.json").read_text())
    text = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    row = r"^\| `(\w+)` +\| ([\d.]+) s +\| (?:([\d.]+) s|\(nothing[^|]*) *\| ([\d.]+) s"
    rows = re.findall(row, text, flags=re.M)
    assert {r[0] for r in rows} == {"fk", "ik", "ik_all", "in_collision", "plan"}
    for call, background, after, wait in rows:
        median = {k: float(np.median(figures[f"first_{call}{k}"]))
                  for k in ("_s", "_compiled_after_s", "_wait_s")}  # fmt: skip
        assert float(background) == round(median["_s"], 1), call
        assert float(wait) == round(median["_wait_s"], 1), call
        if after:
            assert float(after) == round(median["_compiled_after_s"], 1), call
        else:  # nothing compiled: its kernels ran compiled as soon as it answered
            assert median["_compiled_after_s"] - median["_s"] < 0.05, call


def test_the_fine_corpus_paragraph_quotes_its_json():
    """docs/benchmarks.md's 0.05-degree corpus paragraph: each robot's solved count, its
    median and the paths rejected are those of planning_corpus_fine_benchmark.json."""
    import json

    figures = json.loads(
        (ROOT / "toolkit" / "report" / "planning_corpus_fine_benchmark.json").read_text()
    )
    text = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    part = " ".join(text[text.index("**Re-checked at 0.05 degree**") :].split("\n\n")[0].split())
    for robot in ("panda", "ur5", "fetch", "baxter"):
        row = figures[robot]
        name = {"ur5": "UR5"}.get(robot, robot.capitalize())
        found = re.search(rf"{name} (\d+) of (\d+) \((?:median )?([\d.]+) ms\)", part)
        assert found, f"{name} is not quoted"
        assert (int(found[1]), int(found[2])) == (row["solved"], row["problems"])
        assert float(found[3]) == round(row["median_ms"], 1)
        assert row["solved"] == row["problems"] - row["invalid"]  # every valid one solved
        assert row["refused_valid"] == 0
    solved = sum(figures[r]["solved"] for r in ("panda", "ur5", "fetch", "baxter"))
    rejected = sum(figures[r]["rejected"] for r in ("panda", "ur5", "fetch", "baxter"))
    assert f"{rejected} of {solved} paths rejected" in part and figures["step_degrees"] == 0.05
    invalid = sum(figures[r]["invalid"] for r in ("panda", "ur5", "fetch", "baxter"))
    assert f"The {invalid} problems not solved were refused" in part
    example = figures["panda_example"]  # the same problems, example-robot-data's Panda
    assert f"{example['solved']} of {example['problems']} solved, {example['rejected']} " in part
    assert example["rejected"] == 0 and example["refused_valid"] == 0
    assert f"the other {example['problems'] - example['solved']} refused" in part
    own = {(r["scenario"], r["problem"]): r["seconds"] for r in row_list(figures["panda"])}
    theirs = {(r["scenario"], r["problem"]): r["seconds"] for r in row_list(example)}
    both = [k for k in theirs if k in own]
    a, b = (1e3 * float(np.median([d[k] for k in both])) for d in (own, theirs))
    assert f"over the {len(both)} both solved the medians are {a:.1f} ms" in part
    assert f"{b:.1f} ms with example-robot-data's, {b / a:.2f}x apart" in part
    assert b / a <= 2.0


def row_list(figures: dict) -> list[dict]:
    """A planner's solved rows."""
    return [r for r in figures["rows"] if r["success"]]


def _solved_cell(row: dict) -> str:
    """A planning table's cell of one planner's summary: "14 of 14 (15.9 ms)"."""
    head = f"{row['solved']} of {row['problems']}"
    return f"{head} ({row['median_ms']:.1f} ms)" if row["solved"] else head


def test_the_peers_table_quotes_its_json():
    """docs/benchmarks.md's peers table: per robot, the toolkit's, OMPL's, VAMP's and
    mplib's solved counts and medians, the peers' rejected paths and per-problem ratios are
    those of planning_corpus_peers_benchmark.json."""
    import json

    figures = json.loads(
        (ROOT / "toolkit" / "report" / "planning_corpus_peers_benchmark.json").read_text()
    )
    text = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    part = text[text.index("**OMPL, VAMP and mplib in the same run**") :].split("\n\n")[1]
    assert figures["peers"] and figures["vamp"] and figures["mplib"]
    assert figures["step_degrees"] == 0.05

    def cell(row: dict) -> str:
        return "-" if "error" in row else _solved_cell(row)

    def ratio(row: dict, name: str) -> str:
        value = row.get(f"median_ratio_{name}_to_toolkit")
        return "-" if value is None else f"{value:.{2 if name == 'vamp' else 1}f}x"

    def peer(row: dict, name: str) -> str:
        rejected = "-" if "error" in row else row["rejected"]
        return f"{cell(row)} | {rejected} | {ratio(row, name)}"

    robots = ("panda", "ur5", "fetch", "baxter")
    for robot in robots:
        ours = figures[robot]
        name = {"ur5": "UR5"}.get(robot, robot.capitalize())
        row = (f"| {name} | {cell(ours)} | {peer(ours['ompl'], 'ompl')} | "
               f"{peer(ours['vamp'], 'vamp')} | {peer(ours['mplib'], 'mplib')} |")  # fmt: skip
        assert row in part, f"{row} is not the table's row"
        assert ours["rejected"] == 0
    words = " ".join(text.split())
    for name in ("vamp", "mplib", "ompl"):
        rejected = sum(figures[r][name]["rejected"] for r in robots)
        solved = sum(figures[r][name]["solved"] for r in robots)
        assert f"{rejected} of its {solved} paths" in words, name


def test_the_scene_scale_paragraph_quotes_its_json():
    """docs/planning.md's scenes at scale: the checker's seconds for 1,000, 2,000 and 5,000
    boxes, the 20,000 boxes' adding and plan, the mesh's load and checker and the cloud's
    checker are those of scene_scale_benchmark.json."""
    import json

    f = json.loads((ROOT / "toolkit" / "report" / "scene_scale_benchmark.json").read_text())
    text = " ".join((ROOT / "docs" / "planning.md").read_text(encoding="utf-8").split())
    many = f["boxes_20000"]
    quoted = [
        f"1,000 boxes within reach builds in {f['boxes_1000']['checker_s']:.2f} s",
        f"of 2,000 in {f['boxes_2000']['checker_s']:.2f} s",
        f"of 5,000 in {f['boxes_5000']['checker_s']:.2f} s",
        f"20,000 boxes are added to a scene in {many['add_s']:.2f} s",
        f"given 3 s returns in {many['plan_s']:.2f} s",
        f"loaded once, when added ({f['mesh']['add_s']:.2f} s)",
        f"its checker then built in {f['mesh']['checker_s']:.2f} s",
        f"its checker built in {f['cloud']['checker_s']:.2f} s",
    ]
    for phrase in quoted:
        assert phrase in text, phrase
    assert not many["success"] and many["time_limit"] == 3.0
    assert many["plan_s"] <= 1.2 * 3.0 + 0.1  # the bound on a call's lateness
    assert all(f[f"boxes_{n}"]["success"] for n in (500, 1000, 2000, 5000))
    assert f["mesh"]["triangles"] >= 1_990_000 and f["cloud"]["points"] == 100_000


def _rate(per_s: float) -> str:
    """A rate as the pages write it: 2.45 M/s, 514 k/s."""
    return f"{per_s / 1e6:.2f} M/s" if per_s >= 1e6 else f"{per_s / 1e3:.0f} k/s"


@pytest.mark.parametrize(
    ("name", "arms", "unit", "page"),
    [
        ("dynamics_benchmark", {"ur5": "UR5", "panda": "Panda", "kinova": "Kinova Jaco 2"},
         " N m", "benchmarks.md"),
        ("dynamics_mass_benchmark", {"ur10": "UR10", "panda": "Panda", "kinova": "Kinova Jaco 2",
                                     "z1": "Z1"}, "", "dynamics.md"),
    ],
)  # fmt: skip
def test_the_dynamics_tables_quote_their_json(name, arms, unit, page):
    """The dynamics tables (docs/dynamics.md's mass matrix, docs/benchmarks.md's inverse
    dynamics): per arm, the batch's and the loop's rates, their ratio and the largest
    difference are those of the benchmark's JSON."""
    import json

    figures = json.loads((ROOT / "toolkit" / "report" / f"{name}.json").read_text())
    rows = figures["mass_matrix"] if name == "dynamics_mass_benchmark" else figures
    text = (ROOT / "docs" / page).read_text(encoding="utf-8")
    for key, arm in arms.items():
        row = rows[key]
        diff = row.get("max_difference_Nm", row.get("max_difference"))
        quoted = (f"| {arm} | {_rate(row['toolkit_per_s'])} | {_rate(row['pinocchio_loop_per_s'])}"
                  f" | {row['ratio']:.1f}x | {diff:.1e}{unit} |")  # fmt: skip
        assert quoted in text, quoted


def test_the_outer_parallel_paragraph_quotes_its_json():
    """docs/ik-families.md's outer-parallel figures: the same branch sets as EAIK, the
    kernel's, EAIK's, ``ik_all``'s, ``ik``'s and the numeric call's median times and their
    ratios are those of analytic_outer_benchmark.json."""
    import json

    f = json.loads((ROOT / "toolkit" / "report" / "analytic_outer_benchmark.json").read_text())
    run = f["outer_parallel"]
    us = {name.split(" (")[0]: row["median_us"] for name, row in run["solvers"].items()}
    kernel, eaik = us["toolkit compiled family kernel"], us["EAIK 1.2 IK"]
    every, one = us["toolkit Robot.ik_all"], us["toolkit Robot.ik"]
    numeric = us["toolkit Robot.ik(method='numeric')"]
    text = " ".join((ROOT / "docs" / "ik-families.md").read_text(encoding="utf-8").split())
    same = run["solvers"]["EAIK 1.2 IK (C++)"]["same_sets"]
    for phrase in (
        f"**the same branch sets as EAIK on {same:,} of {run['targets']:,}**",
        f"the compiled kernel {kernel:.1f} us against EAIK's {eaik:.1f} us ({eaik / kernel:.1f}x)",
        f"`ik_all` {every:.1f} us ({eaik / every:.2f}x EAIK's call)",
        f"`ik(T)` {one:.1f} us against the numeric {numeric:.1f} us ({one / numeric:.2f}x)",
    ):
        assert phrase in text, phrase


def _as_printed(text: str, value: float) -> bool:
    """Whether ``text`` ("0.050", "38.7") is ``value`` rounded to the decimals it shows."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return float(text) == round(value, decimals)


def test_the_backlash_page_quotes_what_the_code_computes_and_its_json():
    """docs/backlash.md's figures along the pick and place: the deviations and the gaps
    between the readings at each duration, computed here by the toolkit as the page says
    (``backlash.along``, ``backlash.parting``), and the simulation table, read from
    backlash_simulation_benchmark.json."""
    import json

    from toolkit import backlash

    text = " ".join((ROOT / "docs" / "backlash.md").read_text(encoding="utf-8").split())
    layer = backlash.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    data = backlash.along(layer, backlash.pick_and_place(), rate=200.0)
    found = re.search(r"deviates up to ([\d.]+) mm with gravity's torques and ([\d.]+) mm", text)
    assert found, "the pick and place's deviations are not quoted"
    assert _as_printed(found[1], 1e3 * data.deviation_static.max())
    assert _as_printed(found[2], 1e3 * data.deviation_dynamic.max())
    durations, gaps, speed = backlash.parting(layer, [10.0, 5.0, 3.0, 2.0, 1.0, 0.5])
    quoted = {s: mm for mm, s in re.findall(r"([\d.]+) mm at ([\d.]+) s", text)}
    found = re.search(r"even at 10 s the two differ by ([\d.]+) mm", text)
    assert found
    quoted["10"] = found[1]
    assert set(quoted) == {"10", "5", "3", "2", "1", "0.5"}, quoted
    for duration, gap in zip(durations, gaps, strict=True):
        assert _as_printed(quoted[f"{duration:g}"], 1e3 * gap), duration
    found = re.search(r"at 5 s \(([\d.]+) of the velocity limit\)", text)
    assert found and _as_printed(found[1], speed[1])

    figures = json.loads(
        (ROOT / "toolkit" / "report" / "backlash_simulation_benchmark.json").read_text()
    )["figures"]
    rows = re.findall(r"\| (\d+) s \| ([\d.]+) \(([\d.]+) rms\) \| ([\d.]+) \(([\d.]+) rms\) "
                      r"\| ([\d.]+) \| ([\d.]+) / ([\d.]+) / ([\d.]+) mm \|", text)  # fmt: skip
    assert {r[0] for r in rows} == {k.split()[0] for k in figures}
    for duration, *values in rows:
        row = figures[f"{duration} s"]
        tool = row["tool_mm"]
        expected = [row["loaded_max_mrad"], row["loaded_rms_mrad"], row["static_loaded_max_mrad"],
                    row["static_loaded_rms_mrad"], row["unloaded_max_mrad"],
                    tool["simulated"], tool["dynamic"], tool["static"]]  # fmt: skip
        for shown, value in zip(values, expected, strict=True):
            assert _as_printed(shown, value), (duration, shown, value)


BUILT = {"panda": "Panda", "ur5": "UR5", "ur10": "UR10", "kinova": "Kinova", "z1": "Z1",
         "xarm7": "xArm7"}  # fmt: skip


def test_the_built_scenes_table_quotes_its_json():
    """docs/benchmarks.md's table of example-robot-data's arms in built scenes: per robot,
    the toolkit's, OMPL's and mplib's solved counts and medians, the paths rejected, the
    problems missed and the ratios are planning_built_benchmark.json's ("not run" where
    mplib could not take the robot); no toolkit path rejected."""
    import json

    figures = json.loads(
        (ROOT / "toolkit" / "report" / "planning_built_benchmark.json").read_text()
    )
    text = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    part = text[text.index("**example-robot-data's arms in built scenes**") :].split("\n\n")[1]
    assert figures["peers"] and figures["mplib"] and figures["step_degrees"] == 0.05

    cell = _solved_cell
    for robot, name in BUILT.items():
        ours, theirs, mplib = figures[robot], figures[robot]["ompl"], figures[robot]["mplib"]
        ratio = theirs["median_ratio_ompl_to_toolkit"]
        last = ("not run | - | -" if "error" in mplib else
                f"{cell(mplib)} | {mplib['rejected']} | "
                f"{mplib['median_ratio_mplib_to_toolkit']:.1f}x")  # fmt: skip
        row = (f"| {name} | {cell(ours)} | {ours['missed']} | {ours['rejected']} | "
               f"{cell(theirs)} | {theirs['rejected']} | {ratio:.1f}x | {last} |")  # fmt: skip
        assert row in part, f"{row} is not the table's row"
        assert ours["rejected"] == 0


def test_the_calibration_page_quotes_its_json():
    """docs/calibration.md's measured figures are calibration_benchmark.json's, each to the
    decimals the page shows."""
    import json

    f = json.loads((ROOT / "toolkit" / "report" / "calibration_benchmark.json").read_text())
    text = " ".join((ROOT / "docs" / "calibration.md").read_text(encoding="utf-8").split())
    text = text[text.index("## Measured") :]
    k5 = f["backlash_parameters"]["backlash.k_h.joint5"]
    quoted = [  # (pattern with one number, its value)
        (r"held-out poses ([\d.]+) -> [\d.]+ mm", 1e3 * f["ur5_selected_before_mean_m"]),
        (r"held-out poses [\d.]+ -> ([\d.]+) mm", 1e3 * f["ur5_selected_after_mean_m"]),
        (r"\*\*([\d.]+) % lower\*\* \(goal", 100 * f["ur5_selected_reduction"]),
        (r"50 random poses ([\d.]+) %", 100 * f["ur5_random_reduction"]),
        (r"50 random poses [\d.]+ % \(([\d.]+) mm\)", 1e3 * f["ur5_random_after_mean_m"]),
        (r"truth on the (\d+) identifiable", f["ur5_selected_identifiable"]),
        (r"(\d+) % of them identified within 3", 100 * f["ur5_selected_within_3_sigma"]),
        (r"3 standard deviations \(largest ([\d.]+)\)", f["ur5_selected_largest_sigma"]),
        (r"Identification ([\d.]+) s", f["ur5_selected_fit_s"]),
        (r"same errors: ([\d.]+) ->", 1e3 * f["katana_6m180_selected_before_mean_m"]),
        (r"same errors: [\d.]+ -> ([\d.]+) mm", 1e3 * f["katana_6m180_selected_after_mean_m"]),
        (r"\*\*([\d.]+) % lower\*\* \(random", 100 * f["katana_6m180_selected_reduction"]),
        (r"\(random poses ([\d.]+) %", 100 * f["katana_6m180_random_reduction"]),
        (r"\(random poses [\d.]+ %, ([\d.]+) mm\)", 1e3 * f["katana_6m180_random_after_mean_m"]),
        (r"(\d+) % of the \d+ identifiable", 100 * f["katana_6m180_selected_within_3_sigma"]),
        (r"% of the (\d+) identifiable", f["katana_6m180_selected_identifiable"]),
        (r"within 3 sigma \(largest ([\d.]+)\)", f["katana_6m180_selected_largest_sigma"]),
        (r"\(largest [\d.]+\); ([\d.]+) s\.", f["katana_6m180_selected_fit_s"]),
        (r"40 poses\): (\d+) of \d+ identifiable", f["backlash_identified"]),
        (r"40 poses\): \d+ of (\d+) identifiable", f["backlash_identifiable"]),
        (r"loosely \(([\d.]+) \+-", k5[0]),
        (r"loosely \([\d.]+ \+- ([\d.]+):", k5[1]),
        (r"tool too, (\d+) iterations", f["with_tracker_iterations"]),
        (r"\*\*([\d.]+)x the noise\*\*", f["with_tracker_after_over_noise"]),
        (r"the mean is ([\d.]+) mm", 1e3 * f["with_tracker_random_mean_m"]),
        (r"and the max ([\d.]+) mm", 1e3 * f["with_tracker_random_max_m"]),
        (r"\(([\d.]+) vs [\d.]+ mm on the UR5", 1e3 * f["ur5_selected_after_mean_m"]),
        (r"vs ([\d.]+) mm on the UR5", 1e3 * f["ur5_random_after_mean_m"]),
        (r"condition number ([\d.]+) vs", f["ur5_selected_condition"]),
        (r"condition number [\d.]+ vs ([\d.]+)\)", f["ur5_random_condition"]),
    ]
    for pattern, value in quoted:
        found = re.search(pattern, text)
        assert found, f"not quoted: {pattern}"
        assert _as_printed(found[1], value), (pattern, found[1], value)


def test_the_maps_page_quotes_its_json():
    """docs/maps.md's numeric-against-analytic paragraph is maps_methods_benchmark.json's:
    each run's seconds, the mean index over the reached voxels, the voxels reached."""
    import json

    runs = json.loads((ROOT / "toolkit" / "report" / "maps_methods_benchmark.json").read_text())
    text = " ".join((ROOT / "docs" / "maps.md").read_text(encoding="utf-8").split())
    found = re.search(
        r"numeric ([\d.]+) s and ([\d.]+) s, mean index over the reached voxels ([\d.]+); "
        r"analytic ([\d.]+) s and ([\d.]+) s, mean index \*\*([\d.]+)\*\* and (\d+) more voxels "
        r"reached \(([\d,]+) against ([\d,]+)\)\. The numeric budget found ([\d.]+) % of what is "
        r"there \(the index summed",
        text,
    )
    assert found, "the paragraph is not quoted as the test reads it"
    numeric, analytic = runs["methods"]["numeric"], runs["methods"]["auto"]
    expected = [numeric[0]["wall_s"], numeric[1]["wall_s"], numeric[0]["mean_index_reached"],
                analytic[0]["wall_s"], analytic[1]["wall_s"], analytic[0]["mean_index_reached"],
                analytic[0]["voxels_reached"] - numeric[0]["voxels_reached"],
                analytic[0]["voxels_reached"], numeric[0]["voxels_reached"],
                100 * numeric[0]["index_digest"] / analytic[0]["index_digest"]]  # fmt: skip
    for shown, value in zip(found.groups(), expected, strict=True):
        assert _as_printed(shown.replace(",", ""), value), (shown, value)


def test_the_recompile_figures_quote_their_json():
    """docs/reliability.md's warm-up after a one-file change: each file's wall and compiling
    seconds are first_use_changes_benchmark.json's; a change to the compiler's set-up
    compiles nothing, one to the kinematics kernels most of the package."""
    import json

    figures = json.loads(
        (ROOT / "toolkit" / "report" / "first_use_changes_benchmark.json").read_text()
    )["after_a_change"]
    text = " ".join((ROOT / "docs" / "reliability.md").read_text(encoding="utf-8").split())
    text = text[text.index("--changes-only") :]
    for name, row in figures.items():
        quoted = f"`{name}`"
        at = text.index(quoted)
        part = text[at : at + 200]
        assert f"{row['wall_s']:.1f} s" in part and f"{row['compiling_s']:.1f} s" in part, name
    assert figures["common/compiler.py"]["compiling_s"] < 1.0
    assert (
        figures["kinematics/kernels.py"]["compiling_s"]
        > 5 * figures["planning/kernels.py"]["compiling_s"]
    )
