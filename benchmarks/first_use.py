"""What a new user waits for on first use: ``toolkit.warmup()`` compiling every kernel into
an empty cache, and then loading them from that cache, each in a fresh process, ``--runs``
times (default 3). Prints the range the README, docs/ik.md and ``toolkit report`` quote.
Nothing is asserted.

    python benchmarks/first_use.py [--runs 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile

try:  # run as a script (python benchmarks/first_use.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def warmup_seconds(cache: str) -> float:
    """Wall time of ``toolkit.warmup()`` in a fresh process with the cache folder ``cache``
    (the import of the toolkit included: a user's first call pays it too)."""
    env = {**os.environ, "TOOLKIT_CACHE_DIR": cache}
    env.pop("NUMBA_CACHE_DIR", None)
    code = (
        "import time; t = time.perf_counter(); import toolkit; toolkit.warmup(); "
        "print(time.perf_counter() - t)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="fresh caches (>= 1)")
    args, info = begin(parser)
    cold, cached = [], []
    for k in range(max(1, args.runs)):
        with tempfile.TemporaryDirectory() as cache:
            cold.append(warmup_seconds(cache))
            cached.append(warmup_seconds(cache))
        print(f"run {k + 1}: compile {cold[-1]:.1f} s, from the cache {cached[-1]:.1f} s")
    figures: dict[str, object] = {**info, "compile_s": cold, "cached_s": cached}
    for name, values in (("compile every kernel", cold), ("load them from the cache", cached)):
        print(
            f"{name}: {min(values):.1f}-{max(values):.1f} s "
            f"(median {statistics.median(values):.1f} s of {len(values)})"
        )
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
