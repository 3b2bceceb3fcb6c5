"""The ``toolkit`` command line."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import toolkit
from toolkit import maps
from toolkit.cli import main


def test_list(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in toolkit.available_models():
        assert name in out
    assert "ur5" in out
    assert main(["list", "--names"]) == 0
    assert capsys.readouterr().out.split() == toolkit.available_models()


def test_urdf_to_stdout_and_file(capsys, tmp_path):
    assert main(["urdf", "katana_6m180", "--set", "a2=0.25"]) == 0
    assert capsys.readouterr().out == toolkit.urdf_text("katana_6m180", a2=0.25)
    out = tmp_path / "k.urdf"
    assert main(["urdf", "katana_6m90a", "-o", str(out)]) == 0
    assert out.read_text() == toolkit.urdf_text("katana_6m90a")
    assert main(["urdf", "--all", "-o", str(tmp_path / "all")]) == 0
    assert sorted(p.stem for p in (tmp_path / "all").glob("*.urdf")) == toolkit.available_models()


def test_fk_prints_tool_pose(capsys):
    assert main(["fk", "katana_6m180", "0", "0", "0", "-90", "0", "--deg"]) == 0
    out = capsys.readouterr().out
    # case (19): arm stretched horizontally, x = a2 + a3 + a4 + a5 = 0.6318 m
    assert "0.6318" in out
    assert main(["fk", "ur5", *["0.1"] * 6]) == 0
    pose = toolkit.load_example("ur5").fk(np.full(6, 0.1))
    assert f"{pose[0, 3]:.6f}".rstrip("0") in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["fk", "katana_9", "0"], "unknown model 'katana_9'"),
        (["fk", "katana_6m180", "0", "0"], "give 5 joint values (joint1, joint2"),
        (["urdf", "katana_6m180", "--set", "a2"], "NAME=VALUE"),
        (["urdf", "katana_6m180", "--set", "a2=-1"], "must be > 0"),
        (["fk", "katana_6m180", "0", "0", "0", "0", "0", "--frame", "nope"], "unknown frame"),
        (["urdf"], "give a model NAME"),
    ],
)
def test_errors_exit_2_with_message(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_console_script_help():
    result = subprocess.run(
        [sys.executable, "-m", "toolkit.cli", "--help"], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0
    for command in ("list", "urdf", "fk", "report"):
        assert command in result.stdout


@pytest.mark.slow
def test_report_katana_checks_pass(tmp_path, capsys):
    assert main(["report", "-o", str(tmp_path), "--quiet"]) == 0
    index = (tmp_path / "index.html").read_text()
    assert "FAIL</td>" not in index and index.count('class="PASS"') >= 30
    for figure in (
        "fig6_backlash.png",
        "fig3_4_arm5dof_solutions.png",
        "structures_workspaces.png",
        "fig5_bending_shapes.png",
        "fig4_bending_curl.png",
    ):
        assert (tmp_path / figure).stat().st_size > 10_000
        assert f'src="{figure}"' in index
    text = (tmp_path / "report.md").read_text()
    assert "FAIL" not in text and text.count("PASS") >= 9
    assert "Paper 2" in text
    assert "18.0306" in text  # joint 2 nominal torque, eq. 1 (47.9 W, 6400 rpm, 0.85, 371, 0.8)


def _printed_q(out: str) -> np.ndarray:
    lines = out.splitlines()
    start = next(i for i, x in enumerate(lines) if x.startswith("joint values ("))
    text = " ".join(lines[start + 1 : start + 3]).split("]")[0].strip("[ ")
    return np.array(text.split(), dtype=float)


def test_ik_position_and_pose(capsys):
    assert main(["ik", "katana_6m180", "0.3", "0.1", "0.4"]) == 0
    out = capsys.readouterr().out
    assert "solved" in out and "NOT" not in out
    robot = toolkit.load("katana_6m180")
    np.testing.assert_allclose(robot.fk(_printed_q(out))[:3, 3], [0.3, 0.1, 0.4], atol=1e-5)
    assert main(["ik", "ur5", "0.3", "0.2", "0.4", "--rpy", "180", "0", "0", "--deg"]) == 0
    out = capsys.readouterr().out
    T = toolkit.load_example("ur5").fk(np.radians(_printed_q(out)))
    np.testing.assert_allclose(T[:3, 3], [0.3, 0.2, 0.4], atol=1e-5)
    np.testing.assert_allclose(T[:3, :3], np.diag([1.0, -1.0, -1.0]), atol=1e-4)


def test_ik_unreachable_exits_1_with_residual(capsys):
    assert main(["ik", "scara", "3", "0", "0.2"]) == 1
    out = capsys.readouterr().out
    assert "NOT solved" in out and "position error" in out


@pytest.mark.parametrize("command", ["list", "urdf", "fk", "ik", "view", "report", "place"])
def test_every_subcommand_has_help(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    assert "usage: toolkit " + command in capsys.readouterr().out


def test_benchmark_section_reads_the_benchmark_json(tmp_path):
    import json

    from toolkit import report

    assert report.benchmark_section(tmp_path / "missing.json") is None
    path = tmp_path / "ik.json"
    solver = {
        "success_percent": 90.0,
        "mean_ms": 0.5,
        "median_ms": 0.25,
        "percentiles_ms": list(np.linspace(0.1, 2.0, 101)),
    }
    payload = {
        "date": "2026-11-21",
        "machine": "2 cores, x86_64, Python 3.11.7, Pinocchio 4.1.0",
        "targets": 10,
        "budget_ms": 5,
        "tol": 1e-5,
        "numeric": [
            {
                "robot": "ur5",
                "targets": 10,
                "engine": "compiled",
                "solvers": {
                    "toolkit Robot.ik": solver,
                    "rtb ik_LM (C++, ETS)": {**solver, "median_ms": 0.5},
                },
                "batch_solves_per_s": 50000.0,
                "batch_success_percent": 100.0,
            }
        ],
        "closed_form": {
            "geometric_ik_us": 8.0,
            "katana_closed_form_ik_us": 7.0,
            "batched_targets_per_s": 1.3e6,
        },
    }
    path.write_text(json.dumps(payload))
    sec = report.benchmark_section(path)
    text = "\n".join(sec.markdown)
    assert "| ur5 | toolkit Robot.ik | 90.00 % | 0.500 ms | 0.250 ms | (ours) |" in text
    assert "| ur5 | rtb ik_LM (C++, ETS) | 90.00 % | 0.500 ms | 0.500 ms | 0.50 |" in text
    assert "50,000 solves/s" in text and "2 cores" in text
    assert "1.30 M targets/s" in text
    del payload["machine"]  # an older file without the machine is not shown
    path.write_text(json.dumps(payload))
    assert report.benchmark_section(path) is None
    path.write_text(json.dumps({**payload, "machine": "m"}))
    sec = report.benchmark_section(path)
    sec.figures[0][1](tmp_path / "b.png")
    assert (tmp_path / "b.png").stat().st_size > 5_000


def test_place_reads_a_task_file_and_ranks_verified_bases(tmp_path, capsys):
    """``toolkit place``: the CSV's poses (roll, pitch, yaw) are the tasks; the printed
    best base is the API's and the PNG is written; bad files get a clear error."""

    ur5 = toolkit.load_example("ur5")
    tasks = ur5.fk(ur5.random_q(6, seed=np.random.default_rng(3)))
    tasks[:, :3, 3] += [0.5, 0.0, 0.0]
    rows = ["x,y,z,roll,pitch,yaw"]
    for T in tasks:
        import pinocchio as pin

        rows.append(",".join(repr(float(v)) for v in (*T[:3, 3], *pin.rpy.matrixToRpy(T[:3, :3]))))
    csv = tmp_path / "tasks.csv"
    csv.write_text("\n".join(rows) + "\n")
    png = tmp_path / "place.png"
    region = ["0", "-0.4", "0.8", "0.4"]
    argv = ["place", "ur5", str(csv), "--region", *region, "--step", "0.2", "--verify", "2",
            "--png", str(png), "-q", "--voxel", "0.1", "--angles", "6"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    api = maps.placement(ur5, tasks, [[0, -0.4], [0.8, 0.4]], step=0.2, verify=2, voxel=0.1,
                         angles=6)  # fmt: skip
    first = out.splitlines()[out.splitlines().index(next(x for x in out.splitlines()
                                                        if x.startswith("rank"))) + 1]  # fmt: skip
    assert f"{api.best[0]:7.3f}  {api.best[1]:7.3f}" in first
    assert f"{100 * api.reach[0]:8.1f} %" in first
    assert png.stat().st_size > 10_000
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z,roll\n0,0,0,0\n")
    assert main(["place", "ur5", str(bad), "--region", *region]) == 2
    assert "roll, pitch, yaw" in capsys.readouterr().err
    bad.write_text("x,y,z\n0,0,nan\n")
    assert main(["place", "ur5", str(bad), "--region", *region]) == 2
    assert "row 2" in capsys.readouterr().err


def test_place_prints_the_score_it_ranks_by_and_reuses_a_store(tmp_path, capsys):
    """``--score manipulability`` adds its column; ``--store`` keeps the structure, and the
    second call ranks the same bases; no negative zero is printed."""
    ur5 = toolkit.load_example("ur5")
    points = ur5.fk(ur5.random_q(4, seed=np.random.default_rng(5)))[:, :3, 3] + [0.3, 0, 0]
    csv = tmp_path / "points.csv"
    csv.write_text("x,y,z\n" + "\n".join(",".join(repr(float(v)) for v in p) for p in points))
    store = tmp_path / "reach.zarr"
    argv = ["place", "ur5", str(csv), "--region", "0", "-0.2", "0.4", "0.2", "--step", "0.2",
            "--verify", "2", "-q", "--voxel", "0.15", "--score", "manipulability",
            "--no-collisions", "--store", str(store)]  # fmt: skip
    assert main(argv) == 0
    first = capsys.readouterr().out
    assert "manipulability" in next(x for x in first.splitlines() if x.startswith("rank"))
    assert (store / "reach").is_dir() and "-0.000" not in first
    assert main(argv) == 0
    second = capsys.readouterr().out
    ranks = [x for x in first.splitlines() if x[:4].strip().isdigit()]
    assert ranks and ranks == [x for x in second.splitlines() if x[:4].strip().isdigit()]


def test_numbers_print_without_a_negative_zero():
    from toolkit.cli.place import fixed

    assert fixed(-0.0004, "7.3f") == "  0.000"
    assert fixed(-0.0, "5.1f") == "  0.0"
    assert fixed(-0.0006, "7.3f") == " -0.001"


def test_each_map_kind_has_its_own_help(capsys):
    """``map reach --help`` lists the reachability options only, ``map backlash --help``
    the backlash ones too."""
    for kind in ("reach", "backlash"):
        with pytest.raises(SystemExit):
            main(["map", kind, "--help"])
        text = capsys.readouterr().out
        assert f"toolkit map {kind}" in text
        assert ("--compensate" in text) == (kind == "backlash")
        assert ("--delta" in text) == (kind == "backlash")


def test_a_closed_pipe_ends_quietly(monkeypatch, capsys):
    """A reader that goes away (``toolkit ... | head``) ends the command with the shell's
    code for a closed pipe and nothing on standard error."""
    import importlib

    cli = importlib.import_module("toolkit.cli.main")

    def closed(args):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(cli, "_cmd_list", closed)
    assert cli.main(["list"]) == 141
    assert capsys.readouterr().err == ""


def test_a_closed_pipe_in_a_real_process_prints_no_error(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "toolkit.cli", "list"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path,
    )  # fmt: skip
    proc.stdout.close()  # gone before the command writes
    err = proc.stderr.read().decode()
    proc.wait(timeout=120)
    assert proc.returncode == 141, err
    assert "Broken pipe" not in err and "Traceback" not in err


def test_the_cli_takes_a_tip(capsys):
    assert main(["fk", "panda", *["0"] * 4, "--tip", "panda_link4"]) == 0
    out = capsys.readouterr().out
    T = toolkit.load_example("panda").fk(np.zeros(9), "panda_link4")
    assert f"{T[0, 3]:.4f}" in out
    assert main(["fk", "panda", *["0"] * 4, "--tip", "nope"]) == 2
    assert "valid frames" in capsys.readouterr().err


def test_toolkit_list_names_commands_that_exist(capsys):
    main(["list"])
    out = capsys.readouterr().out
    assert "toolkit load NAME" not in out and "toolkit.load(NAME)" in out


def test_map_backlash_compensate_prints_the_compensated_figures(capsys):
    argv = ["map", "backlash", "katana_6m180", "--voxel", "0.2", "--position-only"]
    assert main([*argv, "--orientations", "2", "--payload", "0.5", "--compensate", "-q"]) == 0
    assert "after compensation" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--orientations", "0"], "orientations"),
        (["--png", "/no/such/folder/x.png"], "--png"),
        (["--scheduler", "tcp://127.0.0.1:9"], "no Dask scheduler answers"),
    ],
)
def test_bad_map_options_fail_before_any_work(argv, message, capsys):
    assert main(["map", "reach", "ur5", "--voxel", "0.3", "-q", *argv]) == 2
    assert message in capsys.readouterr().err


def test_the_report_console_shows_whole_first_sentences():
    from toolkit.report.benchmark import benchmark_section
    from toolkit.report.render import SECTIONS, _first_sentence

    assert _first_sentence(benchmark_section.__doc__).endswith("has run.")
    for make in SECTIONS:
        title = _first_sentence(make.__doc__)
        assert title.endswith("."), title


def test_the_report_says_what_its_first_run_costs_before_paying_it(monkeypatch, capsys, tmp_path):
    from toolkit import report
    from toolkit.cli import main

    ran = []
    monkeypatch.setattr(report, "run_report", lambda out, quiet: ran.append(quiet) or 0)
    assert main(["report", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    import json
    import statistics

    from toolkit.report import benchmark

    # the estimate is the one benchmarks/first_use.py measured, in minutes
    figures = json.loads((benchmark.BENCHMARK_FILE.parent / "first_use_benchmark.json").read_text())
    minutes = round(statistics.median(figures["compile_s"]) / 60)
    assert f"compiling the toolkit's kernels (about {minutes} minutes on an idle 2-core" in out
    assert "done in" in out and ran == [False]
    assert main(["report", "-o", str(tmp_path), "--quiet"]) == 0
    assert capsys.readouterr().out == "" and ran == [False, True]


def test_the_reports_console_titles_are_whole_sentences_in_plain_words():
    """Each section's title is its docstring's first sentence, whole (a period after "eq."
    or "Fig." ends none) and without RST markup."""
    from toolkit.report.render import SECTIONS, _first_sentence

    titles = [_first_sentence(make.__doc__ or "") for make in SECTIONS]
    assert titles[1].startswith("Paper 1, eqs. 16-17 and Fig. 6: the arm sags")
    for title in titles:
        assert title.endswith(".") and "`" not in title and ":func:" not in title
    assert _first_sentence("See :func:`toolkit.fk` and ``q``. More.") == "See toolkit.fk and q."
