"""The compiled back end's throughput against the issue's goals: batch FK (UR5, >= 5 M/s),
backlash Monte Carlo (``Backlash.fk`` on 200,000 Katana commands, >= 1 M/s), ``ik_batch``
(UR5, >= 80 k solves/s), on this machine's cores; and the first-use cost, ``toolkit
warmup`` compiling every kernel into an empty cache, then loading them from it. Prints its
figures (best of three runs, each timed after the kernels are loaded); nothing is asserted.

    python benchmarks/engine.py [--json out.json]
"""

from __future__ import annotations

import argparse
import os
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
    run()  # load the kernels (compiled, or from the cache)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return min(times)


def _warmup_seconds(cache: str) -> float:
    """Wall time of ``toolkit.warmup()`` in a fresh process with the cache folder ``cache``."""
    env = {**os.environ, "TOOLKIT_CACHE_DIR": cache}
    env.pop("NUMBA_CACHE_DIR", None)
    code = "import toolkit; print(toolkit.warmup()['total'])"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    return float(out.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args, info = begin(parser)
    with tempfile.TemporaryDirectory() as cache:
        cold, warm = _warmup_seconds(cache), _warmup_seconds(cache)
    print(f"toolkit warmup: {cold:.1f} s into an empty cache, {warm:.2f} s from the cache")
    ur5 = toolkit.load_example("ur5")
    Q = ur5.random_q(1_000_000, seed=1)
    fk = len(Q) / _best(lambda: ur5.fk(Q))
    print(f"batch FK, UR5, 1,000,000 configurations: {fk / 1e6:.2f} M/s (goal >= 5 M/s)")
    kinova = toolkit.load_example("kinova")
    Qk = kinova.random_q(1_000_000, seed=1)
    fk_k = len(Qk) / _best(lambda: kinova.fk(Qk))
    print(f"batch FK, Kinova Gen3 (continuous joints): {fk_k / 1e6:.2f} M/s")
    layer = backlash.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    commands = layer.robot.random_q(200_000, seed=2)
    mc = len(commands) / _best(lambda: layer.fk(commands))
    print(f"Backlash.fk, Katana 6M180, 200,000 commands: {mc / 1e6:.2f} M/s (goal >= 1 M/s)")
    targets = ur5.fk(ur5.random_q(20_000, seed=3))
    ik = len(targets) / _best(lambda: ur5.ik_batch(targets, tol=1e-5), repeats=2)
    print(f"ik_batch, UR5, 20,000 pose targets: {ik / 1e3:.1f} k solves/s (goal >= 80 k/s)")
    figures = {
        **info,
        "warmup_cold_s": cold,
        "warmup_cached_s": warm,
        "fk_ur5_per_s": fk,
        "fk_kinova_per_s": fk_k,
        "backlash_fk_per_s": mc,
        "ik_batch_ur5_per_s": ik,
    }
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
