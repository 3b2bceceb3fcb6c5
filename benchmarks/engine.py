"""The compiled back end's throughput against the issue's goals: batch FK (UR5, >= 5 M/s),
backlash Monte Carlo (``Backlash.fk`` on 200,000 Katana commands, >= 1 M/s), ``ik_batch``
(UR5, >= 80 k solves/s), on this machine's cores; and the first-use cost, ``toolkit
warmup`` compiling every kernel into an empty cache, then loading them from it.

Each figure is measured in ``--runs`` separate processes (default 3), each the median of
three timings after the kernels are loaded; the script prints and records the median over
the runs and their range (a single best run overstates what another run gives). Nothing
is asserted.

    python benchmarks/engine.py [--runs 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import toolkit
from toolkit import backlash

try:  # run as a script (python benchmarks/engine.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def _best(run, repeats: int = 3) -> float:
    """The median of ``repeats`` timings, after one untimed call that loads the kernels."""
    run()  # load the kernels (compiled, or from the cache)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _warmup_seconds(cache: str) -> float:
    """Wall time of ``toolkit.warmup()`` in a fresh process with the cache folder ``cache``."""
    env = {**os.environ, "TOOLKIT_CACHE_DIR": cache}
    env.pop("NUMBA_CACHE_DIR", None)
    code = "import toolkit; print(toolkit.warmup()['total'])"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    return float(out.stdout.split()[-1])


def measure() -> dict[str, float]:
    """One run's figures (in this process)."""
    with tempfile.TemporaryDirectory() as cache:
        cold, warm = _warmup_seconds(cache), _warmup_seconds(cache)
    ur5 = toolkit.load_example("ur5")
    Q = ur5.random_q(1_000_000, seed=1)
    fk = len(Q) / _best(lambda: ur5.fk(Q))
    kinova = toolkit.load_example("kinova")
    Qk = kinova.random_q(1_000_000, seed=1)
    fk_k = len(Qk) / _best(lambda: kinova.fk(Qk))
    layer = backlash.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    commands = layer.robot.random_q(200_000, seed=2)
    mc = len(commands) / _best(lambda: layer.fk(commands))
    targets = ur5.fk(ur5.random_q(20_000, seed=3))
    ik = len(targets) / _best(lambda: ur5.ik_batch(targets, tol=1e-5, method="numeric"), repeats=2)
    return {
        "warmup_cold_s": cold,
        "warmup_cached_s": warm,
        "fk_ur5_per_s": fk,
        "fk_kinova_per_s": fk_k,
        "backlash_fk_per_s": mc,
        "ik_batch_ur5_per_s": ik,
    }


LINES = {
    "warmup_cold_s": ("toolkit warmup into an empty cache", 1.0, "s"),
    "warmup_cached_s": ("toolkit warmup from the cache", 1.0, "s"),
    "fk_ur5_per_s": ("batch FK, UR5, 1,000,000 configurations (goal >= 5 M/s)", 1e-6, "M/s"),
    "fk_kinova_per_s": ("batch FK, Kinova Jaco 2 (continuous joints)", 1e-6, "M/s"),
    "backlash_fk_per_s": ("Backlash.fk, Katana 6M180, 200,000 commands (goal >= 1)", 1e-6, "M/s"),
    "ik_batch_ur5_per_s": ("ik_batch, UR5, 20,000 targets (goal >= 80 k/s)", 1e-3, "k/s"),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="separate processes (>= 1)")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    if "--one" in sys.argv:  # a child run: its figures as JSON on the last line
        print(json.dumps(measure()))
        return
    args, info = begin(parser)
    runs = []
    for k in range(max(1, args.runs)):
        out = subprocess.run(
            [sys.executable, __file__, "--one"], capture_output=True, text=True, check=True
        )
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(f"run {k + 1} of {args.runs} done")
    figures: dict[str, object] = {**info, "runs": runs}
    for key, (label, scale, unit) in LINES.items():
        values = [run[key] for run in runs]
        mid = statistics.median(values)
        figures[key] = mid
        figures[f"{key}_range"] = [min(values), max(values)]
        print(
            f"{label}: {scale * mid:.3g} {unit} median of {len(values)} runs "
            f"({scale * min(values):.3g}-{scale * max(values):.3g})"
        )
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
