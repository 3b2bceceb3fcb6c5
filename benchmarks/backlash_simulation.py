"""[P1]'s backlash along a motion by two routes: the quasi-static dynamic reading
(``backlash.along``: eq. 16 with the motion's torques) against a simulation of the links
driven through their gaps (``backlash.simulate``: forward dynamics, springs of eq. 17's
stiffness, damping ratio 0.7), on the Katana 6M180 pick and place (0.5 kg) at several
durations. Per duration: for the joints gravity loads (2-4), the largest and root mean
square distance of the simulated links from the dynamic reading beside the static
reading's distance from it [mrad]; for the unloaded joints (1 and 5) the largest distance
[mrad]; the tool's largest deviation [mm] by each route; the simulation's seconds.
Nothing is asserted.

    python benchmarks/backlash_simulation.py [--json out.json]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import toolkit
from toolkit import backlash as bl

try:  # run as a script or imported from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json

DURATIONS = (10.0, 5.0, 3.0, 2.0, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args, info = begin(parser)
    layer = bl.Backlash(toolkit.load("katana_6m180"), payload=0.5)
    rows = {}
    for duration in DURATIONS:
        motion = bl.pick_and_place(duration)
        reading = bl.along(layer, motion, 200.0)
        start = time.perf_counter()
        sim = bl.simulate(layer, motion, rate=200.0)
        took = time.perf_counter() - start
        off = 1e3 * (sim.theta - reading.theta_dynamic)
        moved = 1e3 * (reading.theta_static - reading.theta_dynamic)
        row = {
            "loaded_max_mrad": float(np.abs(off[:, 1:4]).max()),
            "loaded_rms_mrad": float(np.sqrt((off[:, 1:4] ** 2).mean())),
            "static_loaded_max_mrad": float(np.abs(moved[:, 1:4]).max()),
            "static_loaded_rms_mrad": float(np.sqrt((moved[:, 1:4] ** 2).mean())),
            "unloaded_max_mrad": float(np.abs(off[:, [0, 4]]).max()),
            "tool_mm": {
                "simulated": 1e3 * float(sim.deviation.max()),
                "dynamic": 1e3 * float(reading.deviation_dynamic.max()),
                "static": 1e3 * float(reading.deviation_static.max()),
            },
            "simulation_s": took,
        }
        rows[f"{duration:g} s"] = row
        tool = row["tool_mm"]
        print(f"{duration:4.1f} s: joints 2-4 simulated - dynamic reading "
              f"{row['loaded_max_mrad']:.3f} mrad at most ({row['loaded_rms_mrad']:.3f} rms), "
              f"static - dynamic {row['static_loaded_max_mrad']:.3f} "
              f"({row['static_loaded_rms_mrad']:.3f} rms); joints 1 and 5 "
              f"{row['unloaded_max_mrad']:.1f} mrad at most; tool {tool['simulated']:.1f} / "
              f"{tool['dynamic']:.1f} / {tool['static']:.1f} mm (simulated / dynamic / "
              f"static); {took:.1f} s")  # fmt: skip
    write_json(args.json, {"machine": info, "figures": rows})


if __name__ == "__main__":
    main()
