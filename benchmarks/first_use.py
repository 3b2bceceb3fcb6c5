"""What a new user waits for on first use: ``toolkit.warmup()`` compiling every kernel into
an empty cache, and then loading them from that cache, each in a fresh process, ``--runs``
times (default 3); then each first call a user makes (``fk``, ``ik``, ``ik_all``,
``in_collision``, ``plan`` on the UR5, each in a fresh process with its own empty cache,
the import and the load included; and ``toolkit --help``), with the seconds the call spent
compiling and the seconds until its kernels ran compiled: by default (a kernel not compiled
yet runs as Python while a background process compiles it) and with
``TOOLKIT_COMPILE=wait`` (the call compiles what it needs first). ``--changes-only``: the
warm-up in a copy of the package after one line is added to one file (an upgrade that
touched it), every kernel compiled before. Prints the range the README, docs/ik.md and
``toolkit report`` quote. Nothing is asserted.

    python benchmarks/first_use.py [--runs 3] [--calls-only | --changes-only] [--json out.json]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

try:  # run as a script (python benchmarks/first_use.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def warmup_seconds(cache: str, root: str | None = None) -> float:
    """Wall time of ``toolkit.warmup()`` in a fresh process with the cache folder ``cache``
    (the import of the toolkit included: a user's first call pays it too); ``root``: a
    folder holding a copy of the package to import instead."""
    return warmup(cache, root)[0]


def warmup(cache: str, root: str | None = None) -> tuple[float, float]:
    """:func:`warmup_seconds`, and of them the seconds spent compiling."""
    env = {**os.environ, "TOOLKIT_CACHE_DIR": cache}
    env.pop("NUMBA_CACHE_DIR", None)
    if root is not None:
        env["PYTHONPATH"] = root
    code = (
        "import time; t = time.perf_counter(); import toolkit; toolkit.warmup(); "
        "from toolkit.kinematics import compile_seconds; "
        "print(time.perf_counter() - t, compile_seconds())"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, cwd=root)  # fmt: skip
    wall, compiling = out.stdout.split()[-2:]
    return float(wall), float(compiling)


CHANGED = ("common/compiler.py", "planning/kernels.py", "kinematics/kernels.py")
"""The package files :func:`after_a_change` changes, one at a time."""


def after_a_change() -> dict[str, object]:
    """Per file of :data:`CHANGED`: the warm-up's wall and compiling seconds after a line is
    added to that file alone, in a copy of the package whose kernels were all compiled
    before (an upgrade that touched one file): what is compiled anew is what reaches it."""
    import shutil
    from pathlib import Path

    here = Path(__file__).resolve().parents[1]
    figures: dict[str, object] = {}
    for name in CHANGED:
        with tempfile.TemporaryDirectory() as root, tempfile.TemporaryDirectory() as cache:
            for folder in ("toolkit", "urdf"):
                shutil.copytree(here / folder, Path(root) / folder,
                                ignore=shutil.ignore_patterns("__pycache__"))  # fmt: skip
            warmup(cache, root)  # every kernel compiled
            target = Path(root) / "toolkit" / name
            target.write_text(target.read_text() + "\n# changed\n")
            wall, compiling = warmup(cache, root)
        figures[name] = {"wall_s": wall, "compiling_s": compiling}
        print(f"after a change to {name}: warm-up {wall:.1f} s, {compiling:.1f} s compiling")
    return figures


_CALL = """
import time
t = time.perf_counter()
import numpy as np
import toolkit
from toolkit.kinematics import compile_seconds
ur5 = toolkit.load_example("ur5")
q = ur5.random_q(seed=1)
a = np.array([-1.4, -1.0, 1.5, -1.9, -1.57, 0.0])
wall = toolkit.Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])
calls = {
    "fk": lambda: ur5.fk(q),
    "ik": lambda: ur5.ik(ur5.fk(q)),
    "ik_all": lambda: ur5.ik_all(ur5.fk(q)),
    "in_collision": lambda: ur5.in_collision(q, scene=wall),
    "plan": lambda: ur5.plan(a, a * [-1, 1, 1, 1, 1, 1], scene=wall, seed=0),
}
calls[NAME]()
took, compiling = time.perf_counter() - t, compile_seconds()
from toolkit.common import background
while background.pending():  # the background process compiling what the call used
    time.sleep(0.2)
    calls[NAME]()  # a call collects it
print(took, compiling, time.perf_counter() - t)
"""


def first_call(name: str, mode: str) -> tuple[float, float, float]:
    """(wall seconds, of them compiling, seconds until its kernels run compiled) of one first
    call ``name`` in a fresh process with an empty cache, the import and the robot's load
    included; ``mode`` is ``TOOLKIT_COMPILE``'s (``background``: the default)."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "TOOLKIT_CACHE_DIR": cache, "TOOLKIT_COMPILE": mode}
        env.pop("NUMBA_CACHE_DIR", None)
        code = _CALL.replace("NAME", repr(name))
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True)  # fmt: skip
    if out.returncode != 0:
        raise RuntimeError(f"first {name} ({mode}) failed:\n{out.stderr[-4000:]}")
    wall, compiling, compiled = out.stdout.split()[-3:]
    return float(wall), float(compiling), float(compiled)


def help_seconds() -> float:
    """Wall time of ``python -m toolkit.cli --help`` in a fresh process."""
    begin_at = time.perf_counter()
    subprocess.run([sys.executable, "-m", "toolkit.cli", "--help"], capture_output=True,
                   check=True)  # fmt: skip
    return time.perf_counter() - begin_at


def first_calls(runs: int) -> dict[str, object]:
    """Each first call ``runs`` times: wall and compiling seconds per run."""
    figures: dict[str, object] = {}
    for name in ("fk", "ik", "ik_all", "in_collision", "plan"):
        for mode, tag in (("background", ""), ("wait", "_wait")):
            rows = [first_call(name, mode) for _ in range(runs)]
            figures[f"first_{name}{tag}_s"] = [w for w, _, _ in rows]
            figures[f"first_{name}{tag}_compiling_s"] = [c for _, c, _ in rows]
            figures[f"first_{name}{tag}_compiled_after_s"] = [a for _, _, a in rows]
            print(f"first {name} ({mode}): " + ", ".join(
                f"{w:.1f} s ({c:.1f} s compiling, compiled after {a:.1f} s)"
                for w, c, a in rows))  # fmt: skip
    helps = [help_seconds() for _ in range(max(3, runs))]
    figures["help_s"] = helps
    print(f"toolkit --help: {min(helps):.2f}-{max(helps):.2f} s")
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="fresh caches (>= 1)")
    parser.add_argument("--calls-only", action="store_true", help="only the first calls")
    parser.add_argument("--changes-only", action="store_true",
                        help="only the warm-up after a change to one file")  # fmt: skip
    args, info = begin(parser)
    if args.changes_only:
        write_json(args.json, {**info, "after_a_change": after_a_change()})
        return
    calls = first_calls(max(1, args.runs))
    if args.calls_only:
        write_json(args.json, {**info, **calls})
        return
    cold, cached = [], []
    for k in range(max(1, args.runs)):
        with tempfile.TemporaryDirectory() as cache:
            cold.append(warmup_seconds(cache))
            cached.append(warmup_seconds(cache))
        print(f"run {k + 1}: compile {cold[-1]:.1f} s, from the cache {cached[-1]:.1f} s")
    figures: dict[str, object] = {**info, **calls, "compile_s": cold, "cached_s": cached}
    for name, values in (("compile every kernel", cold), ("load them from the cache", cached)):
        print(
            f"{name}: {min(values):.1f}-{max(values):.1f} s "
            f"(median {statistics.median(values):.1f} s of {len(values)})"
        )
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
