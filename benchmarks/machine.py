"""What every benchmark records beside its figures: the machine, the CPU count, the
library versions and the commit (``python benchmarks/machine.py`` prints it)."""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import time
from pathlib import Path


def describe() -> dict[str, object]:
    """Date, machine, CPU count, Python, NumPy, numba, Pinocchio, toolkit and git commit."""
    import numba
    import numpy
    import pinocchio

    import toolkit

    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            cwd=Path(__file__).resolve().parent,
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit = ""
    return {
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "machine": f"{platform.machine()} {platform.processor() or platform.platform()}",
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "numba_threading_layer": os.environ.get("NUMBA_THREADING_LAYER", "toolkit's choice"),
        "pinocchio": pinocchio.__version__,
        "toolkit": toolkit.__version__,
        "commit": commit or "unknown",
    }


def begin(parser: argparse.ArgumentParser) -> tuple[argparse.Namespace, dict[str, object]]:
    """A benchmark's start: ``--json`` added to ``parser``, the arguments parsed, and the
    machine described (:func:`describe`) and printed in one line (:func:`summary`)."""
    parser.add_argument("--json", help="also write the figures here")
    args = parser.parse_args()
    info = describe()
    print(summary(info))
    return args, info


def write_json(path: str | None, figures: dict[str, object]) -> None:
    """Write a benchmark's figures (with :func:`describe`'s facts) to ``path``, if given."""
    if path:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(figures, fh, indent=2)
        print(f"wrote {path}")


def summary(info: dict[str, object]) -> str:
    """One line for the report: cores, machine, versions, commit."""
    return (
        f"{info['cpu_count']} cores, {info['machine']}, Python {info['python']}, "
        f"Pinocchio {info['pinocchio']}, numba {info['numba']}, commit {info['commit']}"
    )


if __name__ == "__main__":
    print(json.dumps(describe(), indent=2))
