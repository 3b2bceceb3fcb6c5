"""IK benchmark following the TRAC-IK protocol; prints its figures (never asserts times).

For each robot: N random configurations within the limits -> FK -> target pose; each
target is solved with a 5 ms budget and a 1e-5 tolerance on position [m] and orientation
[rad]. Prints success rate, mean and median time per solve. The peers that are installed
(the ``bench`` extra: roboticstoolbox-python's ik_LM, TRAC-IK through pytracik) run on
the same targets in the same run. Then the closed-form solvers' time per target.

Neutral by construction:

* every solver meets target i in turn before target i + 1 (interleaved per target), in an
  order that rotates with i, so cache warmth and machine load favour no one;
* each solver is a (prepare, call, convert) triple and only ``call`` is timed: a peer's
  inputs (arrays, quaternions, its start) are built before the clock starts and its
  answer is turned into our q after it stops; the judge (our independent FK) runs
  outside every timed region;
* every solver that takes a start gets the same one (the middle of the joint ranges,
  where ``Robot.ik`` starts); ik_LM also runs from its own default start (random), and
  both rows are reported.

    python benchmarks/ik.py [--n 10000]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import toolkit
from toolkit import arm5dof, katana

try:  # run as a script (python benchmarks/ik.py) or imported from the benchmarks folder
    from machine import describe, summary
except ImportError:  # pragma: no cover
    from benchmarks.machine import describe, summary

ROBOTS = ("katana_6m90a", "ur5", "panda", "kinova", "ur5_floating")


def _load(name: str) -> toolkit.Robot:
    if name in toolkit.available_models():
        return toolkit.load(name)
    if name.endswith("_floating"):
        return toolkit.load_example(name[: -len("_floating")], floating=True)
    return toolkit.load_example(name)


def _judge(robot, q, T, tol: float) -> bool:
    """The one success criterion for every solver: our independent FK and the limits."""
    if q is None or not np.all(np.isfinite(q)):
        return False
    reached = robot.fk(q)
    pos = np.linalg.norm(reached[:3, 3] - T[:3, 3])
    rot = np.linalg.norm(pin.log3(reached[:3, :3].T @ T[:3, :3]))
    return bool(pos <= tol and rot <= tol and robot.joints.within_limits(q, tol=1e-9))


def _peers(robot, tol: float, budget: float) -> dict:
    """(prepare, call, convert) of each installed peer (the bench extra): ``prepare(T)``
    builds the call's arguments, ``call(*args)`` is the bare peer call (the only timed
    part), ``convert(raw)`` gives our q (or None)."""
    peers = {}
    if robot.joints.has_other or "free_flyer" in {j.kind for j in robot.joints.joints}:
        print(f"  ({robot.name} has a floating base: the peers take fixed-base chains)")
        return peers
    mid = robot.joints.angles(
        robot._numeric.ik_state.mid
    )  # one value per joint: where Robot.ik starts
    ets = _rtb_ets(robot)
    if ets is not None:
        n = ets.n

        def convert(sol):
            angles = mid.copy()  # joints beyond the chain (fingers) stay where they start
            angles[:n] = sol[0]
            return robot.joints.q_from_angles(angles)

        # ik_LM stops on E = e^T e / 2 < its tol: tol^2 / 4 keeps both norms below tol
        def call(T, q0):
            return ets.ik_LM(T, q0=q0, tol=tol * tol / 4, ilimit=30, slimit=100)

        start = np.ascontiguousarray(mid[:n])
        peers["rtb ik_LM, same start"] = (lambda T: (T, start), call, convert)
        peers["rtb ik_LM, its default start"] = (lambda T: (T, None), call, convert)
    tracik = _tracik(robot, tol, budget, mid)
    if tracik is not None:
        probe = robot.fk(robot.random_q(10, seed=1))
        prepare, call, convert = tracik
        if any(convert(call(*prepare(T))) is not None for T in probe):
            peers["TRAC-IK (pytracik), same start"] = tracik
        else:
            print(f"  (TRAC-IK found no solution for 10 reachable {robot.name} targets: skipped)")
    return peers


def _rtb_ets(robot):
    try:
        import warnings

        import roboticstoolbox as rtb
    except ImportError:
        return None
    try:
        import xacrodoc.packages

        from toolkit.descriptions import example_robot_data_dir

        xacrodoc.packages.update_package_cache(
            {"example-robot-data": str(example_robot_data_dir().parent)}
        )
    except ImportError:
        pass
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            other = rtb.Robot.URDF(str(robot.urdf_path))
            return other.ets(end=robot.tip if robot.tip in other.link_dict else None)
        except Exception as exc:  # the peer's own loader: report and go on
            print(f"  (roboticstoolbox cannot load {robot.name}: {exc}; skipped)")
            return None


def _tracik(robot, tol: float, budget: float, mid: np.ndarray):
    try:
        import pytracik
    except ImportError:
        return None
    text = Path(robot.urdf_path).read_text(encoding="utf-8")
    base = next(  # the URDF's root link (Pinocchio's own "universe" is not in the file)
        f.name
        for f in robot.model.frames
        if f.parentJoint == 0 and f.type == pin.BODY and f.name != "universe"
    )
    # eps bounds each axis: eps = tol / sqrt(3) keeps the norms below tol
    solver = pytracik.TRAC_IK(
        base, robot.tip, text, budget, tol / np.sqrt(3), pytracik.SolveType.Speed
    )
    n, j = 0, robot.model.frames[robot.frames.id(None)].parentJoint
    while j > 0:  # the joints from the base to the tip come first in q (Panda: 7 of 9)
        n, j = n + 1, robot.model.parents[j]
    start = np.ascontiguousarray(mid[:n])

    def prepare(T):
        quat = pin.Quaternion(T[:3, :3])
        x, y, z = T[:3, 3]
        return (solver, start, x, y, z, quat.x, quat.y, quat.z, quat.w)

    def convert(out):
        out = np.asarray(out)
        if out.size != n + 1 or out[0] <= 0:  # out[0]: TRAC-IK's own success flag
            return None
        angles = mid.copy()
        angles[:n] = out[1:]  # the judge decides whether this q is right
        return robot.joints.q_from_angles(angles)

    return prepare, pytracik.ik, convert


def numeric(name: str, n: int, budget: float, tol: float) -> dict:
    """Our IK, single and batched, and the installed peers on the same targets, interleaved
    in blocks of 50 so that a change in machine load hits every solver alike."""
    robot = _load(name)
    targets = robot.fk(robot.random_q(n, seed=2024))
    solvers = {
        "toolkit Robot.ik": (
            lambda T: (T,),
            lambda T: robot.ik(T, tol=tol, restarts=10_000, time_limit=budget, method="numeric"),
            lambda res: res.q,
        )
    }
    solvers.update(_peers(robot, tol, budget))
    labels = list(solvers)
    for prepare, call, convert in solvers.values():  # warm up (JIT, caches)
        convert(call(*prepare(targets[0])))
    times = {k: np.empty(n) for k in labels}
    ok = dict.fromkeys(labels, 0)
    for i, T in enumerate(targets):
        shift = i % len(labels)
        for label in labels[shift:] + labels[:shift]:  # the order rotates with i
            prepare, call, convert = solvers[label]
            args = prepare(T)
            t0 = time.perf_counter()
            raw = call(*args)
            times[label][i] = time.perf_counter() - t0
            ok[label] += _judge(robot, convert(raw), T, tol)
    robot.ik_batch(
        targets[:4], tol=tol, method="numeric"
    )  # warm up: the serial and the parallel kernels
    robot.ik_batch(targets[:64], tol=tol, method="numeric")
    t0 = time.perf_counter()
    batch = robot.ik_batch(targets, tol=tol, restarts=200, seed=0, method="numeric")
    batch_s = time.perf_counter() - t0
    batch_ok = sum(_judge(robot, q, T, tol) for q, T in zip(batch.q, targets, strict=True))
    ours = float(np.median(times["toolkit Robot.ik"]))
    print(
        f"{name}: {n} targets, budget {1e3 * budget:g} ms, tol {tol:g}, "
        f"engine {robot.kinematics.engine.name}"
    )
    rows = {}
    for label in solvers:
        med = float(np.median(times[label]))
        rows[label] = {
            "success_percent": 100 * ok[label] / n,
            "mean_ms": 1e3 * float(times[label].mean()),
            "median_ms": 1e3 * med,
            "percentiles_ms": np.percentile(1e3 * times[label], np.arange(101)).round(4).tolist(),
        }
        ratio = "" if label.startswith("toolkit") else f"   ours/theirs median {ours / med:.2f}"
        print(
            f"  {label:<24} success {rows[label]['success_percent']:6.2f} %   "
            f"mean {rows[label]['mean_ms']:.4f} ms   median {1e3 * med:.4f} ms{ratio}"
        )
    print(
        f"  {'toolkit Robot.ik_batch':<24} success {100 * batch_ok / n:6.2f} %   "
        f"{n / batch_s:,.0f} solves/s on {os.cpu_count()} cores (no time budget, 200 restarts)"
    )
    return {
        "robot": name,
        "targets": n,
        "engine": robot.kinematics.engine.name,
        "solvers": rows,
        "batch_solves_per_s": n / batch_s,
        "batch_success_percent": 100 * batch_ok / n,
    }


def closed_form(n: int) -> dict:
    """The closed forms on reachable targets only: each target is the FK of a random
    configuration (within the Katana's Table 2 limits for its closed form)."""
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, size=(n, 5))
    P = arm5dof.forward(q)
    # the pitch of the last link seen from the front (the target's direction from the base
    # axis): pi - (t2 + t3 + t4) when the gripper point lies behind the base axis
    phi = q[:, 1] + q[:, 2] + q[:, 3]
    behind = P[:, 0] * np.cos(q[:, 0]) + P[:, 1] * np.sin(q[:, 0]) < 0
    phi = np.where(behind, np.pi - phi, phi)
    t0 = time.perf_counter()
    for i in range(min(n, 20_000)):
        arm5dof.geometric_ik_batch(P[i : i + 1], phi[i : i + 1])
    single = (time.perf_counter() - t0) / min(n, 20_000)
    t0 = time.perf_counter()
    for i in range(min(n, 5_000)):
        arm5dof.geometric_ik(P[i], phi[i])
    listed = (time.perf_counter() - t0) / min(n, 5_000)
    big = 1_000_000
    Pb = np.repeat(P, big // n + 1, axis=0)[:big]
    phib = np.resize(phi, big)
    t0 = time.perf_counter()
    arm5dof.geometric_ik_batch(Pb, phib)
    batched = time.perf_counter() - t0
    robot = toolkit.load("katana_6m180")
    qk = robot.random_q(min(n, 5_000), seed=3)
    Tk = katana.closed_form_fk(qk)  # frame 0, at the shoulder
    pk, ak = Tk[:, :3, 3], Tk[:, :3, 2]  # tool point and approach axis
    front = pk[:, :2] / np.linalg.norm(pk[:, :2], axis=1, keepdims=True)
    pitch = np.arctan2(ak[:, 2], np.einsum("ij,ij->i", ak[:, :2], front))
    t0 = time.perf_counter()
    found = sum(bool(katana.closed_form_ik(pk[i], pitch[i], roll=qk[i, 4])) for i in range(len(qk)))
    kat = (time.perf_counter() - t0) / len(qk)
    print(f"katana.closed_form_ik: a solution for {found} of {len(qk)} reachable targets")
    print(f"geometric IK (paper 2), batch of 1:        {1e6 * single:8.2f} us per target")
    print(f"geometric_ik (merged, filtered list):      {1e6 * listed:8.2f} us per target")
    print(f"geometric IK batched, {big} targets:  {big / batched:12.0f} targets/s")
    print(f"katana.closed_form_ik (6M180, limits):     {1e6 * kat:8.2f} us per target")
    return {
        "geometric_ik_us": 1e6 * listed,
        "katana_closed_form_ik_us": 1e6 * kat,
        "batched_targets_per_s": big / batched,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000, help="targets per robot")
    parser.add_argument("--budget", type=float, default=0.005, help="seconds per solve")
    parser.add_argument("--tol", type=float, default=1e-5)
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), help="robots to run")
    parser.add_argument(
        "--json",
        help="also write the figures here (toolkit report shows toolkit/report/ik_benchmark.json)",
    )
    args = parser.parse_args()
    print(f"numeric IK: {args.n} targets, budget {1e3 * args.budget:g} ms, tol {args.tol:g}")
    info = describe()
    print(summary(info))
    results = [numeric(name, args.n, args.budget, args.tol) for name in args.robots]
    closed = closed_form(args.n)
    if args.json:
        payload = {
            **info,
            "date": str(info["date"])[:10],
            "machine": summary(info),
            "targets": args.n,
            "budget_ms": 1e3 * args.budget,
            "tol": args.tol,
            "numeric": results,
            "closed_form": closed,
        }
        Path(args.json).write_text(json.dumps(payload), encoding="utf-8")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
