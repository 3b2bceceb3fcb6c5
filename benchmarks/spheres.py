"""Sphere covers of the example arms' collision meshes (``collision.sphere_model``): per
shape count, the spheres' union volume over the shape's own (median and worst shape), and
the seconds a cover takes; every cover holds every point of every surface (tested).

    python benchmarks/spheres.py [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import toolkit
from toolkit.collision import sphere_model

try:  # run as a script (python benchmarks/spheres.py) or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    args, info = begin(parser)
    figures: dict[str, list] = {}
    for name in ("panda", "ur5"):
        robot = toolkit.load_example(name)
        rows = []
        for k in (1, 2, 4, 8, 16, 32):
            start = time.perf_counter()
            model = sphere_model(robot, per_shape=k)
            took = time.perf_counter() - start
            excess = np.array(list(model.excess.values()))
            rows.append({"per_shape": k, "spheres": len(model), "seconds": took,
                         "union_over_shape_median": float(np.median(excess)),
                         "union_over_shape_max": float(excess.max())})  # fmt: skip
            print(
                f"{name:6s} {k:3d} per shape: {len(model):4d} spheres, union / shape "
                f"{np.median(excess):.2f} (median), {excess.max():.2f} (worst), {took:.2f} s"
            )
        figures[name] = rows
    write_json(args.json, {"machine": info, "figures": figures})


if __name__ == "__main__":
    main()
