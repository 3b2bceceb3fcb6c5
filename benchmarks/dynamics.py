"""Batch inverse dynamics: ``toolkit.dynamics.inverse_dynamics`` (the compiled RNEA over
every core) against a Python loop over Pinocchio's ``rnea`` (what a user writes without the
toolkit) on the same 100,000 random samples (q, qd, qdd) of the UR5, the Panda and the
Kinova Gen3, one after the other, and, where ``roboticstoolbox-python`` is installed (the
``bench`` extra), the Robotics Toolbox's ``rne`` on the same UR5 and Panda URDFs for the
first 500 samples. Each figure is the median of ``--repeats`` timings; the agreement with Pinocchio
(largest |difference| [N m]) is printed beside the speed. Nothing is asserted.

    python benchmarks/dynamics.py [--n 100000] [--repeats 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

import toolkit
from toolkit import dynamics

try:  # run as a script (python benchmarks/dynamics.py) or from the benchmarks folder
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.machine import begin, write_json

ROBOTS = ("ur5", "panda", "kinova")


def _timed(run, repeats: int) -> tuple[float, object]:
    out = run()  # the kernels loaded (compiled, or from the cache)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def _rtb(robot: toolkit.Robot, Q, V, A, ref, folder: str) -> tuple[float, float] | None:
    """(seconds per sample, largest |difference| from Pinocchio [N m]) of the Robotics
    Toolbox's ``rne`` on the same URDF (its package paths made absolute), or None."""
    try:
        import roboticstoolbox as rtb
    except ImportError:
        return None
    share = robot.urdf_path.parents[3]  # .../share/example-robot-data
    path = Path(folder) / f"{robot.name}.urdf"
    path.write_text(
        robot.urdf_path.read_text().replace("package://example-robot-data/", f"{share}/")
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        peer = rtb.Robot.URDF(str(path))
    k = min(len(Q), 500)
    t0 = time.perf_counter()
    out = np.array([peer.rne(q, v, a) for q, v, a in zip(Q[:k], V[:k], A[:k], strict=True)])
    seconds = (time.perf_counter() - t0) / k
    return seconds, float(np.abs(out - np.asarray(ref)[:k]).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000, help="samples per robot")
    parser.add_argument("--repeats", type=int, default=3)
    args, info = begin(parser)
    figures: dict[str, object] = {**info, "n": args.n}
    for name in ROBOTS:
        robot = toolkit.load_example(name)
        rng = np.random.default_rng(1)
        Q = robot.random_q(args.n, seed=rng)
        V = rng.uniform(-2.0, 2.0, (args.n, robot.nv))
        A = rng.uniform(-5.0, 5.0, (args.n, robot.nv))
        model, data = robot.model, robot.model.createData()

        def loop(model=model, data=data, Q=Q, V=V, A=A) -> np.ndarray:
            return np.array(
                [pin.rnea(model, data, q, v, a) for q, v, a in zip(Q, V, A, strict=True)]
            )

        ours, tau = _timed(
            lambda r=robot, Q=Q, V=V, A=A: dynamics.inverse_dynamics(r, Q, V, A), args.repeats
        )
        theirs, ref = _timed(loop, args.repeats)
        diff = float(np.abs(np.asarray(tau) - np.asarray(ref)).max())
        with tempfile.TemporaryDirectory() as folder:
            rtb = _rtb(robot, Q, V, A, ref, folder) if name in ("ur5", "panda") else None
        row = {"toolkit_per_s": args.n / ours, "pinocchio_loop_per_s": args.n / theirs,
               "ratio": theirs / ours, "max_difference_Nm": diff,
               "rtb_rne_per_s": None if rtb is None else 1.0 / rtb[0],
               "rtb_max_difference_Nm": None if rtb is None else rtb[1]}  # fmt: skip
        figures[name] = row
        peer = "" if rtb is None else (f"; RTB rne (same URDF) {1.0 / rtb[0]:.0f}/s, "
                                       f"largest difference {rtb[1]:.1e} N m")  # fmt: skip
        print(f"{name:7s} toolkit {row['toolkit_per_s'] / 1e6:.2f} M/s, Python loop over "
              f"pin.rnea {row['pinocchio_loop_per_s'] / 1e3:.0f} k/s: {row['ratio']:.1f}x; "
              f"largest difference {diff:.1e} N m{peer}")  # fmt: skip
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
