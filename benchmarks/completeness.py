"""Every branch where the arm has one: how complete ``ik_all`` and ``ik_all_batch`` are where
users meet the hard cases, and what the cases cost. Prints its figures, asserts nothing.

* Singular poses: the UR5's home pose; the UR5 with q5 = 0 (axes 4 and 6 parallel) and the
  Kinova with q5 = pi (axes 4 and 6 on one line): targets answered, and the generating
  configuration returned when it is ``q_rest`` (the representative takes the free joints'
  angles from it).
* Calibrated UR5s (``calibration.perturb``, +-1 mm, +-0.2 deg; 5 arms) at targets with q5
  within 0.07 rad of +-pi (near the wrist singularity): every distinct solution the numeric
  IK finds from 40 random starts looked up among ``ik_all``'s branches, and ``ik_all_batch``
  against ``ik_all``; the same at random targets; the calibrated batch's time against the
  exact UR5's.
* An arm exact to 5e-11 rad (axis 3 tilted): targets with their generating configuration.
* Turned joints: the UR5 with joint 1 in -210..65 deg and joint 4 in -60..300 deg: targets
  with a branch from ``ik_all_batch``, and its verified rows found among ``ik_all``'s.
* Float32 targets (UR5, Kinova): targets solved to 1e-5 from the float32 pose.
* A KUKA iiwa (pybullet_data) with joint 7 locked: targets without a branch.

    python benchmarks/completeness.py [--n 200] [--json completeness.json]
"""

from __future__ import annotations

import argparse
import math
import re
import statistics
import time
from pathlib import Path

import numpy as np

try:
    from analytic import numeric_missing
    from machine import begin, write_json
except ImportError:  # pragma: no cover
    from benchmarks.analytic import numeric_missing
    from benchmarks.machine import begin, write_json

import toolkit
from toolkit import calibration as cal

HOME = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi).max())


def _has(robot: toolkit.Robot, result: object, q: np.ndarray, close: float = 1e-6) -> bool:
    want = robot.joints.angles(q)
    rows = result.q[result.success]  # type: ignore[attr-defined]
    return any(_gap(robot.joints.angles(r), want) < close for r in rows)


def singular(n: int) -> dict[str, object]:
    ur5, kinova = toolkit.load_example("ur5"), toolkit.load_example("kinova")
    home = ur5.ik_all(ur5.fk(HOME))
    free = sorted({j for f in home.free for j in f})
    out: dict[str, object] = {"ur5_home_branches": home.solved, "ur5_home_free": free}
    for name, arm, col, value in (("ur5_q5_0", ur5, 4, 0.0), ("kinova_q5_pi", kinova, 4, np.pi)):
        answered = kept = 0
        times = []
        for seed in range(n):
            a = arm.joints.angles(arm.random_q(seed=seed))
            a[col] = value
            g = arm.joints.q_from_angles(a)
            T = arm.fk(g)
            t0 = time.perf_counter()
            r = arm.ik_all(T)
            times.append(time.perf_counter() - t0)
            answered += bool(r.solved)
            kept += _has(arm, arm.ik_all(T, q0=g), g)
        out[name] = {"targets": n, "answered": answered, "generator_at_q_rest": kept,
                     "median_ik_all_ms": 1e3 * statistics.median(times)}  # fmt: skip
        print(
            f"{name}: {answered}/{n} answered, the generating configuration returned at "
            f"q_rest for {kept}/{n}; ik_all median {1e3 * statistics.median(times):.2f} ms"
        )
    print(f"UR5 home pose: {home.solved} branches, free joints {out['ur5_home_free']}")
    return out


def _batch_vs_single(arm: toolkit.Robot, Ts: np.ndarray) -> tuple[int, int]:
    """(branches of ik_all missing from ik_all_batch, branches of ik_all)."""
    batch = arm.ik_all_batch(Ts)
    missing = total = 0
    for i, T in enumerate(Ts):
        r = arm.ik_all(T)
        first: dict[int, int] = {}
        for k, b in enumerate(r.branch.tolist()):
            first.setdefault(b, k)
        rows = [arm.joints.angles(q) for q in batch.q[i, : batch.found[i]]]
        total += len(first)
        missing += sum(not any(_gap(arm.joints.angles(r.q[k]), x) < 1e-5 for x in rows)
                       for k in first.values())  # fmt: skip
    return missing, total


def calibrated(n: int) -> dict[str, object]:
    ur5 = toolkit.load_example("ur5")
    near = {"missing": 0, "distinct": 0, "batch_missing": 0, "branches": 0, "no_branch": 0}
    rand = {"missing": 0, "distinct": 0}
    per = max(1, n // 5)
    for s in range(1, 6):
        arm = toolkit.load_urdf(cal.perturb(ur5, seed=s).urdf_text, mimic=False, tip=ur5.tip)
        rng = np.random.default_rng(s)
        Q = arm.random_q(per, seed=100 + s)
        Q[:, 4] = np.sign(rng.normal(size=per)) * np.pi + rng.uniform(-0.07, 0.07, per)
        m, d = numeric_missing(arm, Q, 40)
        near["missing"] += m
        near["distinct"] += d
        bm, bt = _batch_vs_single(arm, arm.fk(Q))
        near["batch_missing"] += bm
        near["branches"] += bt
        near["no_branch"] += int(sum(arm.ik_all(T).solved == 0 for T in arm.fk(Q)))
        m, d = numeric_missing(arm, arm.random_q(per // 2, seed=200 + s), 40)
        rand["missing"] += m
        rand["distinct"] += d
    print(f"calibrated UR5s, q5 within 0.07 of +-pi, {5 * per} targets: {near['missing']} of "
          f"{near['distinct']} numeric solutions missing from ik_all, {near['no_branch']} "
          f"targets without a branch; ik_all_batch misses {near['batch_missing']} of "
          f"{near['branches']} ik_all branches; at random targets {rand['missing']} of "
          f"{rand['distinct']} missing")  # fmt: skip
    arm = toolkit.load_urdf(cal.perturb(ur5, seed=1).urdf_text, mimic=False, tip=ur5.tip)
    Ts = arm.fk(ur5.random_q(20_000, seed=4))
    arm.ik_all_batch(Ts[:100])
    ur5.ik_all_batch(Ts[:100])
    ratios = []
    for _ in range(3):
        t0 = time.perf_counter()
        arm.ik_all_batch(Ts)
        t1 = time.perf_counter()
        ur5.ik_all_batch(Ts)
        ratios.append((t1 - t0) / (time.perf_counter() - t1))
    single = []
    for T in Ts[:300]:
        t0 = time.perf_counter()
        arm.ik_all(T)
        t1 = time.perf_counter()
        ur5.ik_all(T)
        single.append((t1 - t0) / (time.perf_counter() - t1))
    print(
        f"calibrated UR5 batch of 20,000: {statistics.median(ratios):.1f}x the exact UR5's "
        f"time; single ik_all median {statistics.median(single):.1f}x"
    )
    return {"near_singular": near, "random": rand, "targets": 5 * per,
            "batch_time_ratio": statistics.median(ratios),
            "single_time_ratio": statistics.median(single)}  # fmt: skip


def _xyz(v: np.ndarray) -> str:
    return " ".join(repr(float(x)) for x in v)


def _chain_urdf(h: list[np.ndarray], o: list[np.ndarray], tip: np.ndarray) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(7)) + '<link name="lt"/>'
    joints, prev = [], np.zeros(3)
    for i, (axis, p) in enumerate(zip(h, o, strict=True)):
        d = p - prev
        joints.append(
            f'<joint name="j{i + 1}" type="revolute"><parent link="l{i}"/><child link='
            f'"l{i + 1}"/><origin xyz="{_xyz(d)}"/><axis xyz="{_xyz(axis)}"/><limit '
            'lower="-3.14159" upper="3.14159" effort="1" velocity="1"/></joint>'
        )
        prev = p
    d = tip - prev
    joints.append(f'<joint name="tool" type="fixed"><parent link="l6"/><child link="lt"/>'
                  f'<origin xyz="{_xyz(d)}" rpy="0.3 -0.2 0.1"/></joint>')  # fmt: skip
    return f'<robot name="near_exact">{links}{"".join(joints)}</robot>'


def near_exact(n: int) -> dict[str, object]:
    rng = np.random.default_rng(11)

    def unit(v: np.ndarray) -> np.ndarray:
        return v / np.linalg.norm(v)

    h = [unit(rng.normal(size=3)) for _ in range(6)]
    h[2], h[3] = h[1], -h[1]
    h[2] = unit(h[1] + 5e-11 * unit(np.cross(h[1], rng.normal(size=3))))
    o = [rng.normal(size=3) * 0.4 for _ in range(5)]
    o.append(o[4] - 0.12 * h[4])
    arm = toolkit.load_urdf(_chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1))
    kept = sum(_has(arm, arm.ik_all(arm.fk(q)), q) for q in arm.random_q(n, seed=1))
    print(
        f"arm exact to {arm.structure.deviation:.1g} rad: the generating configuration among "
        f"the branches (tol 1e-10) for {kept}/{n}"
    )
    return {"deviation": arm.structure.deviation, "targets": n, "generator_found": kept}


def turned(n: int) -> dict[str, object]:
    ur5 = toolkit.load_example("ur5")
    text = Path(ur5.urdf_path).read_text()
    for joint, lo, hi in (("shoulder_pan_joint", -210, 65), ("wrist_1_joint", -60, 300)):
        at = text.index(f'<joint name="{joint}"')
        end = text.index("</joint>", at)
        bounds = f'lower="{math.radians(lo)!r}" upper="{math.radians(hi)!r}"'
        part = re.sub(r'lower="[^"]*" upper="[^"]*"', bounds, text[at:end])
        text = text[:at] + part + text[end:]
    arm = toolkit.load_urdf(text, tip="tool0")
    Q = arm.random_q(n, seed=3)
    batch = arm.ik_all_batch(arm.fk(Q))
    answered = int(batch.success.any(axis=1).sum())
    rows = bad = 0
    for i in range(0, n, max(1, n // 200)):
        single = arm.ik_all(arm.fk(Q[i]))
        for q in batch.q[i][batch.success[i]]:
            rows += 1
            bad += bool(np.abs(single.q[single.success] - q).max(axis=1).min() >= 1e-9)
    print(
        f"turned joints: {answered}/{n} targets with a verified batch branch "
        f"({int((Q[:, 0] < -np.pi).sum())} need joint 1 below -pi); {rows - bad}/{rows} "
        "verified batch rows are ik_all rows"
    )
    return {"targets": n, "answered": answered, "rows": rows, "rows_in_ik_all": rows - bad}


def float32(n: int) -> dict[str, object]:
    out: dict[str, object] = {}
    for name in ("ur5", "kinova"):
        arm = toolkit.load_example(name)
        Ts = arm.fk(arm.random_q(n, seed=21)).astype(np.float32)
        solved = sum(bool(arm.ik_all(T, tol=1e-5).solved) for T in Ts)
        batch = int(arm.ik_all_batch(Ts, tol=1e-5).success.any(axis=1).sum())
        out[name] = {"targets": n, "ik_all": solved, "ik_all_batch": batch}
        print(f"{name} float32 targets, tol 1e-5: ik_all {solved}/{n}, batch {batch}/{n}")
    return out


def iiwa_locked(n: int) -> dict[str, object]:
    try:
        import pybullet_data
    except ImportError:
        return {"skipped": "pybullet not installed"}
    arm = toolkit.load_urdf(str(Path(pybullet_data.getDataPath()) / "kuka_iiwa/model.urdf"))
    j7 = arm.model.names[7]
    none = 0
    for seed in range(n):
        q = arm.random_q(seed=seed)
        value = float(q[6])
        none += int(arm.ik_all(arm.fk(q), lock={j7: value}).solved == 0)
    print(f"KUKA iiwa, joint 7 locked at the target's own angle: {none}/{n} without a branch")
    return {"targets": n, "without_branch": none}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="targets per case")
    args, info = begin(parser)
    figures = {
        "machine": info,
        "singular": singular(args.n),
        "calibrated": calibrated(args.n),
        "near_exact": near_exact(args.n),
        "turned": turned(10 * args.n),
        "float32": float32(args.n),
        "iiwa_locked": iiwa_locked(args.n),
    }
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
