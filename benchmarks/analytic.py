"""Analytic IK (every branch) against EAIK on the same targets in one run; a
calibrated UR5's polished branches; how many arms have a structure. Prints its figures,
asserts nothing.

* UR5, N random reachable targets (FK of random configurations): per target, in an order
  that rotates with the target, ``Robot.ik_all`` (the whole API: checks, every branch,
  verification by an independent FK, one row per branch; with ``turns=True`` every
  equivalent angle within the limits), ``Robot.ik`` by default (the nearest verified
  branch) and numeric, the
  family solver alone (the branches before verification, in Python and compiled) and
  EAIK's bare ``IK`` call and IK-Geo's ``get_ik`` (their inputs built before the clock
  starts). The branch sets are compared outside the timed region, as sets of angles up to
  whole turns. IK-Geo is given the chain's axes and offsets at zero (its H, P) as its
  ``three_parallel_two_intersecting`` robot (the UR5's family in its list; its general
  ``three_parallel`` answered only least-squares poses 0.3-0.75 m off on this chain), the
  target's rotation times the tool's at zero transposed (its binding reads and writes a
  rotation's rows as columns: its own forward kinematics returns R^T).
* The UR5 after ``calibration.perturb`` (+-1 mm, +-0.2 deg): every branch polished on the
  real model; its time against the exact UR5's; what EAIK says of it.
* The Kinova Jaco 2 (a spherical wrist): ``Robot.ik_all`` and the compiled kernel against
  EAIK and IK-Geo, the branch sets compared.
* The Katana 6M180 (5R, axes 2, 3, 4 parallel): ``Robot.ik_all`` against EAIK's ``IK``,
  interleaved, the branch sets compared; every distinct solution the numeric IK finds from
  200 random starts looked up among the branches; the perturbed arm's branches.
* [P3]'s five positioning structures (compiled families placing a point): ``ik_all``
  against the family's Python form, ``ik`` against the numeric ``ik``, ``ik_all_batch``.
* The Panda with joint 3 locked (the ``meeting pairs, search`` family) exact and calibrated,
  and that family on random robots: the generating configuration and the numeric IK's
  solutions looked up among the branches.
* Coverage: the catalogue and example-robot-data arms with a structure, beside EAIK's
  verdict on the same files.

    python benchmarks/analytic.py [--n 10000] [--json analytic.json]
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np
from machine import begin, write_json

import toolkit
from toolkit import calibration as cal
from toolkit.ik import registry

ZERO6 = np.zeros(6)  # the free joints' angles at a singular pose (none here)
FREE = np.zeros(8, np.int64)  # the kernels' free-joint bits


def _peers(robot: toolkit.Robot) -> dict[str, object]:
    out: dict[str, object] = {}
    try:
        from eaik.IK_URDF import UrdfRobot

        out["eaik"] = UrdfRobot(str(robot.urdf_path))
    except ImportError:
        print("  (eaik not installed: pip install '.[bench]')")
    return out


def _ikgeo(
    chain: object, points: np.ndarray | None = None, family: str = "three_parallel_two_intersecting"
) -> tuple[object, np.ndarray] | None:
    """IK-Geo's robot of ``family`` for a chain (its H, P from the axes and ``points`` on
    them, default the joints' origins) and the tool's rotation at zero, or None when
    ``ik-geo`` is not installed."""
    try:
        import ik_geo
    except ImportError:
        print("  (ik-geo not installed: pip install '.[bench]')")
        return None
    H = chain.axes  # type: ignore[attr-defined]
    o = chain.points if points is None else points  # type: ignore[attr-defined]
    P = np.vstack([o[0], np.diff(o, axis=0), chain.tip[:3, 3] - o[-1]])  # type: ignore[attr-defined]
    robot = getattr(ik_geo.Robot, family)(H.tolist(), P.tolist())
    return robot, chain.tip[:3, :3].copy()  # type: ignore[attr-defined]


def _ikgeo_input(T: np.ndarray, MR: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """IK-Geo's (R, t) of a target: the rotation without the tool's, rows as columns."""
    return np.ascontiguousarray((T[:3, :3] @ MR.T).T), np.ascontiguousarray(T[:3, 3])


def _peer_exact(label: str, answer: object) -> list[np.ndarray]:
    """A peer's exact (not least-squares) solutions: EAIK's ``IK`` answer or IK-Geo's list
    of (q, is least squares)."""
    if label.startswith("EAIK"):
        pairs = zip(answer.Q, answer.is_LS, strict=True)  # type: ignore[attr-defined]
    else:
        pairs = answer  # type: ignore[assignment]
    return [np.asarray(q) for q, ls in pairs if not ls]


def _same_sets(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    def key(rows: list[np.ndarray]) -> list[np.ndarray]:
        return [np.remainder(r + np.pi, 2 * np.pi) - np.pi for r in rows]

    ka, kb = key(a), key(b)
    if len(ka) != len(kb):
        return False
    return all(any(np.abs(np.remainder(x - y + np.pi, 2 * np.pi) - np.pi).max() < 1e-6
                   for y in kb) for x in ka)  # fmt: skip


def ur5_against_peers(n: int) -> dict[str, object]:
    ur5 = toolkit.load_example("ur5")
    chain, found = ur5._analytic._chain_structure(ur5.frames.id(None))
    assert chain is not None and found.points is not None
    assert found.family is not None
    family = registry.REGISTRY[found.family].python
    peers = _peers(ur5)
    targets = ur5.fk(ur5.random_q(n, seed=2025))
    X = np.eye(4)
    if "eaik" in peers:  # EAIK's end frame is the last joint's: T_eaik = T_ours X
        q = ur5.random_q(seed=1)
        X = np.linalg.inv(ur5.fk(q)) @ peers["eaik"].fwdKin(q[:6])  # type: ignore[attr-defined]
    solvers = {
        "toolkit Robot.ik_all (verified, one row per branch)": (lambda T: (T,), ur5.ik_all),
        "toolkit Robot.ik_all(turns=True) (verified, every turn)": (
            lambda T: (T,), lambda T: ur5.ik_all(T, turns=True),
        ),
        "toolkit Robot.ik (the default: nearest verified branch)": (lambda T: (T,), ur5.ik),
        "toolkit Robot.ik(method='numeric') (one solution)": (
            lambda T: (T,), lambda T: ur5.ik(T, method="numeric"),
        ),
        "toolkit family solver alone (Python)": (
            lambda T: (chain, found.points, T), family,
        ),
    }  # fmt: skip
    from toolkit.ik import family_kernels
    from toolkit.ik.analytic.door import packed_family

    packed = packed_family(chain, found)
    out, roots = np.zeros((8, 6)), np.full((8, 3), -1, np.int64)
    solvers["toolkit compiled family kernel (numba)"] = (
        lambda T: (*packed, T, False, ZERO6, out, roots, FREE), family_kernels.three_parallel,
    )  # fmt: skip
    if "eaik" in peers:
        solvers["EAIK 1.2 IK (C++)"] = (lambda T: (T @ X,), peers["eaik"].IK)  # type: ignore[attr-defined]
    geo = _ikgeo(chain)
    if geo is not None:
        solvers["IK-Geo 1.0 get_ik (Rust)"] = (lambda T: _ikgeo_input(T, geo[1]), geo[0].get_ik)  # type: ignore[attr-defined]
    labels = list(solvers)
    times, answers = _interleaved(solvers, targets)
    cols = list(chain.columns)
    ours = [_base_rows(ur5, r, cols) for r in answers[labels[0]]]
    verified = sum(bool(r.success.any()) for r in answers[labels[0]])  # type: ignore[attr-defined]
    worst = max(float(max(r.position_error.max(), r.orientation_error.max()))  # type: ignore[attr-defined]
                for r in answers[labels[0]] if len(r.q))  # type: ignore[attr-defined]  # fmt: skip
    figures: dict[str, object] = {"targets": n, "verified_percent": 100 * verified / n,
                                  "worst_error": worst, "solvers": {}}  # fmt: skip
    mean_branches = float(np.mean([len(b) for b in ours]))
    print(f"UR5, {n} targets: a verified branch for {100 * verified / n:.2f} %, "
          f"{mean_branches:.2f} branches on average, worst error {worst:.1e}")  # fmt: skip
    figures["solvers"] = _solver_rows(times, answers, ours)
    return figures


def _interleaved(
    calls: dict[str, tuple[object, object]], targets: np.ndarray
) -> tuple[dict[str, np.ndarray], dict[str, list[object]]]:
    """Each solver (label: (prepare, call)) on every target, the order rotating with the
    target, after one warm-up call each; the call alone is timed, its input built before:
    (seconds per target, raw answers), by label."""
    labels = list(calls)
    for prepare, call in calls.values():
        call(*prepare(targets[0]))  # type: ignore[operator]
    times = {k: np.empty(len(targets)) for k in labels}
    answers: dict[str, list[object]] = {k: [] for k in labels}
    for i, T in enumerate(targets):
        shift = i % len(labels)
        for label in labels[shift:] + labels[:shift]:
            prepare, call = calls[label]
            args = prepare(T)  # type: ignore[operator]
            t0 = time.perf_counter()
            raw = call(*args)  # type: ignore[operator]
            times[label][i] = time.perf_counter() - t0
            answers[label].append(raw)
    return times, answers


def _solver_rows(
    times: dict[str, np.ndarray], answers: dict[str, list[object]], ours: list[list[np.ndarray]]
) -> dict[str, dict[str, object]]:
    """Per solver its median and mean [us] and, for a peer, on how many targets its exact
    solutions are our branch set (``ours``, per target); printed as well."""
    rows: dict[str, dict[str, object]] = {}
    for label, t in times.items():
        row: dict[str, object] = {"median_us": 1e6 * statistics.median(t),
                                  "mean_us": 1e6 * float(t.mean())}  # fmt: skip
        if label.startswith(("EAIK", "IK-Geo")):
            sets = [_peer_exact(label, answer) for answer in answers[label]]
            row["same_sets"] = sum(_same_sets(a, b) for a, b in zip(ours, sets, strict=True))
        rows[label] = row
        same = f", same branch sets on {row['same_sets']} of {len(t)}" if "same_sets" in row else ""
        print(f"  {label:<52} median {row['median_us']:9.1f} us  "
              f"mean {row['mean_us']:9.1f} us{same}")  # fmt: skip
    _print_ratios(rows)
    return rows


def _print_ratios(rows: dict[str, dict[str, object]]) -> None:
    """The ratios the goals are stated in, from the medians of one run: EAIK's call over
    ``ik_all``'s and over the family kernel's (above 1: faster than EAIK), and the default
    ``ik`` over the numeric one (below 1: faster)."""

    def median(prefix: str) -> float | None:
        found = [r["median_us"] for k, r in rows.items() if k.startswith(prefix)]
        return float(found[0]) if found else None  # type: ignore[arg-type]

    eaik, ik_all = median("EAIK"), median("toolkit Robot.ik_all (verified")
    ik, numeric = median("toolkit Robot.ik (the default"), median("toolkit Robot.ik(method=")
    kernel = median("toolkit compiled family kernel")
    parts = []
    if eaik and ik_all:
        parts.append(f"EAIK / ik_all {eaik / ik_all:.2f}x")
    if eaik and kernel:
        parts.append(f"EAIK / kernel {eaik / kernel:.2f}x")
    if ik and numeric:
        parts.append(f"ik / numeric ik {ik / numeric:.2f}x")
    if parts:
        print("  ratios (this run's medians): " + ", ".join(parts))


def _base_rows(robot: toolkit.Robot, result: object, cols: list[int]) -> list[np.ndarray]:
    """One row per branch label (the turns of a joint aside), chain angles only."""
    seen: dict[str, np.ndarray] = {}
    for q, label in zip(result.q, result.labels, strict=True):  # type: ignore[attr-defined]
        seen.setdefault(label, robot.joints.angles(q)[cols])
    return list(seen.values())


def _toolkit_calls(arm: toolkit.Robot) -> tuple[Any, Any, dict[str, tuple[object, object]]]:
    """(chain, structure, the toolkit's calls for :func:`_interleaved`) of a 6R arm with a
    compiled family: ``ik_all``, the default ``ik``, the numeric ``ik`` and the family
    kernel alone."""
    from toolkit.ik.analytic.door import packed_family

    chain, found = arm._analytic._chain_structure(arm.frames.id(None))
    assert chain is not None and found.family is not None and found.points is not None
    packed, out, roots = packed_family(chain, found), np.zeros((8, 6)), np.zeros((8, 3), np.int64)
    calls: dict[str, tuple[object, object]] = {
        "toolkit Robot.ik_all (verified, one row per branch)": (lambda T: (T,), arm.ik_all),
        "toolkit Robot.ik (the default: nearest verified branch)": (lambda T: (T,), arm.ik),
        "toolkit Robot.ik(method='numeric') (one solution)": (
            lambda T: (T,), lambda T: arm.ik(T, method="numeric"),
        ),
        "toolkit compiled family kernel (numba)": (
            lambda T: (*packed, T, False, ZERO6, out, roots, FREE),
            registry.REGISTRY[found.family].kernel,
        ),
    }  # fmt: skip
    return chain, found, calls


def spherical_wrist_arm(n: int) -> dict[str, object]:
    """The Kinova Jaco 2 (``spherical wrist``, compiled; continuous joints): ``ik_all``, the
    family kernel alone, EAIK's ``IK`` and IK-Geo's ``spherical_two_parallel`` robot on the
    same targets, interleaved; the branch sets compared (chain angles up to whole turns)."""

    arm = toolkit.load_example("kinova")
    chain, found, calls = _toolkit_calls(arm)
    targets = arm.fk(arm.random_q(n, seed=2027))
    peer = _peers(arm).get("eaik")
    if peer is not None:  # EAIK's end frame is the last joint's: T_eaik = T_ours X
        q = arm.random_q(seed=1)
        X = np.linalg.inv(arm.fk(q)) @ peer.fwdKin(arm.joints.angles(q)[list(chain.columns)])  # type: ignore[attr-defined]
        calls["EAIK 1.2 IK (C++)"] = (lambda T: (T @ X,), peer.IK)  # type: ignore[attr-defined]
    geo = _ikgeo(chain, found.points, "spherical_two_parallel")  # its general "spherical"
    # answered no solution on this chain; axes 2, 3 are parallel here (EAIK's class too)
    if geo is not None:
        calls["IK-Geo 1.0 get_ik (Rust)"] = (lambda T: _ikgeo_input(T, geo[1]), geo[0].get_ik)  # type: ignore[attr-defined]
    labels = list(calls)
    times, answers = _interleaved(calls, targets)
    cols = list(chain.columns)
    ours = [_base_rows(arm, r, cols) for r in answers[labels[0]]]
    solved = sum(bool(r.success.any()) for r in answers[labels[0]])  # type: ignore[attr-defined]
    figures: dict[str, object] = {"targets": n, "solved": solved}
    print(f"Kinova Jaco 2 (spherical wrist, compiled), {n} targets: a verified branch for "
          f"{solved}, {np.mean([len(b) for b in ours]):.2f} branches on average")  # fmt: skip
    figures["solvers"] = _solver_rows(times, answers, ours)
    return figures


def _outer_urdf(rng: np.random.Generator, meeting: bool) -> str:
    """A random 6R URDF with axes 1, 2, 3 parallel (EAIK's "outer" case), axes 5, 6
    meeting where ``meeting`` (the case EAIK solves), every link frame parallel to the base
    at zero, joint limits +-pi, a tool offset."""

    def xyz(v: np.ndarray) -> str:
        return " ".join(repr(float(x)) for x in v)

    h = [v / np.linalg.norm(v) for v in rng.normal(size=(6, 3))]
    h[1], h[2] = h[0], -h[0]
    o = rng.normal(size=(6, 3)) * 0.3
    if meeting:
        o[5] = o[4]
    links = "".join(f'<link name="l{i}"/>' for i in range(7)) + '<link name="lt"/>'
    joints, prev = [], np.zeros(3)
    for i in range(6):
        joints.append(f'<joint name="j{i + 1}" type="revolute"><parent link="l{i}"/>'
                      f'<child link="l{i + 1}"/><origin xyz="{xyz(o[i] - prev)}"/>'
                      f'<axis xyz="{xyz(h[i])}"/><limit lower="-3.14159" upper="3.14159" '
                      'effort="1" velocity="1"/></joint>')  # fmt: skip
        prev = o[i]
    tool = xyz(rng.normal(size=3) * 0.1)
    joints.append('<joint name="tool" type="fixed"><parent link="l6"/><child link="lt"/>'
                  f'<origin xyz="{tool}" rpy="0.3 -0.2 0.1"/></joint>')  # fmt: skip
    return f'<robot name="outer6r">{links}{"".join(joints)}</robot>'


def _written(text: str) -> str:
    """``text`` in a new temporary URDF file; its path (EAIK reads files)."""
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as fh:
        fh.write(text)
    return fh.name


def outer_parallel(n: int) -> dict[str, object]:
    """A random 6R arm with axes 1, 2, 3 parallel and axes 5, 6 meeting (``6R, axes 1, 2, 3
    parallel`` here, EAIK's ``THREE_PARALLEL_TWO_INTERSECTING``): ``ik_all``, ``ik``, the
    numeric ``ik``, the family kernel alone and EAIK's ``IK`` on the same targets,
    interleaved; the branch sets compared. Then whether EAIK takes the general arm (axes
    4-6 anywhere), which the family solves as well."""

    rng = np.random.default_rng(7)
    path = _written(_outer_urdf(rng, meeting=True))
    arm = toolkit.load_urdf(path)
    chain, _, calls = _toolkit_calls(arm)
    targets = arm.fk(arm.random_q(n, seed=2028))
    peer = _peers(arm).get("eaik")
    kinds = {}
    if peer is not None:
        from eaik.IK_URDF import UrdfRobot

        kinds["meeting"] = str(peer.getKinematicFamily())  # type: ignore[attr-defined]
        general = UrdfRobot(_written(_outer_urdf(rng, meeting=False)))
        kinds["general"] = str(general.getKinematicFamily())
        q = arm.random_q(seed=1)
        X = np.linalg.inv(arm.fk(q)) @ peer.fwdKin(q)  # type: ignore[attr-defined]
        calls["EAIK 1.2 IK (C++)"] = (lambda T: (T @ X,), peer.IK)  # type: ignore[attr-defined]
    times, answers = _interleaved(calls, targets)
    first = answers[next(iter(calls))]
    ours = [_base_rows(arm, r, list(chain.columns)) for r in first]
    solved = sum(bool(r.success.any()) for r in first)  # type: ignore[attr-defined]
    mean = np.mean([len(b) for b in ours])
    print(f"6R, axes 1, 2, 3 parallel, axes 5, 6 meeting (EAIK: {kinds}), {n} targets: a "
          f"verified branch for {solved}, {mean:.2f} branches")  # fmt: skip
    return {"targets": n, "solved": solved, "eaik_family": kinds,
            "solvers": _solver_rows(times, answers, ours)}  # fmt: skip


def calibrated(n: int) -> dict[str, object]:
    ur5 = toolkit.load_example("ur5")
    arm = toolkit.load_urdf(cal.perturb(ur5, seed=1).urdf_text, mimic=False, tip=ur5.tip)
    Q = ur5.random_q(n, seed=7)
    exact_t, cal_t, worst, same, lost = [], [], 0.0, 0, 0
    for q in Q:
        T, Tc = ur5.fk(q), arm.fk(q)
        t0 = time.perf_counter()
        a = ur5.ik_all(T)
        exact_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        b = arm.ik_all(Tc)
        cal_t.append(time.perf_counter() - t0)
        if len(b.q):
            worst = max(worst, float(b.position_error.max()), float(b.orientation_error.max()))
        same += len(set(a.labels)) == len(set(b.labels))
        lost += b.lost
    ratio = statistics.median(cal_t) / statistics.median(exact_t)
    missing, distinct = numeric_missing(arm, Q[: max(1, n // 10)], starts=40)
    verdict = "not tried"
    try:
        import tempfile

        from eaik.IK_URDF import UrdfRobot

        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as fh:
            fh.write(cal.perturb(ur5, seed=1).urdf_text)
        try:
            peer = UrdfRobot(fh.name)
            verdict = (f"{peer.getKinematicFamily()}, known decomposition: "
                       f"{peer.hasKnownDecomposition()}")  # fmt: skip
            peer.IK(arm.fk(Q[0]))
        except Exception as exc:  # the peer's own refusal, reported as it words it
            verdict += f"; IK refused: {str(exc).strip()[:90]}"
    except ImportError:
        pass
    print(f"calibrated UR5 ({arm.structure.reason}), {n} targets: every branch polished to "
          f"{worst:.1e}; as many branches as the exact UR5 on {same} of {n} ({lost} lost in "
          f"all); median time {ratio:.2f}x the exact UR5's; of {distinct} distinct solutions "
          f"the numeric IK found from 40 starts on {max(1, n // 10)} targets, {missing} "
          f"missing from the branches; EAIK: {verdict}")  # fmt: skip
    return {"targets": n, "worst_error": worst, "same_branch_count": same, "lost": lost,
            "time_ratio": ratio, "eaik": verdict, "numeric_distinct": distinct,
            "missing": missing}  # fmt: skip


def numeric_missing(robot: toolkit.Robot, Q: np.ndarray, starts: int) -> tuple[int, int]:
    """(solutions the numeric IK finds from ``starts`` random starts that no branch holds,
    distinct solutions it found) over the targets FK(Q)."""

    def gap(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi).max())

    missing = distinct = 0
    for i, q in enumerate(Q):
        T = robot.fk(q)
        ours = [robot.joints.angles(x) for x in robot.ik_all(T).q]
        found: list[tuple[np.ndarray, float]] = []
        for start in robot.random_q(starts, seed=i):
            res = robot.ik(T, q0=start, restarts=0, tol=1e-10, method="numeric")
            a = robot.joints.angles(res.q)
            if res.success and not any(gap(a, f) < 1e-6 for f, _ in found):
                # a pose within 1e-10 fixes the angles to 1e-10 over the Jacobian's smallest
                # singular value: near a singularity, more loosely than 1e-6
                sigma = np.linalg.svd(robot.jacobian(res.q), compute_uv=False)[-1]
                found.append((a, max(1e-6, 10 * 1e-10 / sigma)))
        distinct += len(found)
        missing += sum(not any(gap(f, o) < close for o in ours) for f, close in found)
    return missing, distinct


def batches(n: int, runs: int = 5) -> dict[str, object]:
    """Targets per second, all branches, on this machine's cores: ``Robot.ik_all_batch``
    (verified), the family's door kernel alone (verified, without the Python door),
    EAIK's ``IK_batched`` with as many threads and IK-Geo's ``get_ik`` in a Python loop;
    each the median of ``runs`` in one run, alternating; then the calibrated UR5's batch
    against the exact one's."""
    import os

    ur5 = toolkit.load_example("ur5")
    chain, _ = ur5._analytic._chain_structure(ur5.frames.id(None))
    assert chain is not None
    Ts = ur5.fk(ur5.random_q(n, seed=3))
    rates: dict[str, list[float]] = {"ik_all_batch (verified)": [], "door kernel alone": []}
    threads = os.cpu_count() or 1
    peer = _peers(ur5).get("eaik")
    TE = None
    if peer is not None:
        q = ur5.random_q(seed=1)
        TE = np.ascontiguousarray(Ts @ (np.linalg.inv(ur5.fk(q)) @ peer.fwdKin(q[:6])))  # type: ignore[attr-defined]
        rates[f"EAIK IK_batched ({threads} threads)"] = []
        peer.IK_batched(TE[:100], threads)  # type: ignore[attr-defined]
    geo = _ikgeo(chain)
    geo_in = [_ikgeo_input(T, geo[1]) for T in Ts] if geo is not None else []
    if geo is not None:
        rates["IK-Geo get_ik, a Python loop (1 thread)"] = []
    ur5.ik_all_batch(Ts[:100])
    door = ur5._analytic._door(ur5.frames.id(None))
    assert door is not None
    door.call(Ts[:100], 1e-10, door.mid2, door.mid_pref2, spread=True)
    for _ in range(runs):
        t0 = time.perf_counter()
        ur5.ik_all_batch(Ts)
        rates["ik_all_batch (verified)"].append(n / (time.perf_counter() - t0))
        t0 = time.perf_counter()
        door.call(Ts, 1e-10, door.mid2, door.mid_pref2, spread=True)
        rates["door kernel alone"].append(n / (time.perf_counter() - t0))
        if peer is not None:
            t0 = time.perf_counter()
            peer.IK_batched(TE, threads)  # type: ignore[attr-defined]
            rates[f"EAIK IK_batched ({threads} threads)"].append(n / (time.perf_counter() - t0))
        if geo is not None:
            solve = geo[0].get_ik  # type: ignore[attr-defined]
            t0 = time.perf_counter()
            for R, t in geo_in:
                solve(R, t)
            rates["IK-Geo get_ik, a Python loop (1 thread)"].append(n / (time.perf_counter() - t0))
    out: dict[str, object] = {"targets": n}
    for label, values in rates.items():
        out[label] = {
            "median_per_s": statistics.median(values),
            "range": [min(values), max(values)],
        }
        print(f"  {label:<34} {statistics.median(values):>10,.0f} targets/s "
              f"({min(values):,.0f}-{max(values):,.0f})")  # fmt: skip
    arm = toolkit.load_urdf(cal.perturb(ur5, seed=1).urdf_text, mimic=False, tip=ur5.tip)
    Tc = arm.fk(ur5.random_q(n, seed=3))
    arm.ik_all_batch(Tc[:100])
    t0 = time.perf_counter()
    res = arm.ik_all_batch(Tc)
    cal_rate = n / (time.perf_counter() - t0)
    worst = float(np.nanmax(np.maximum(res.position_error, res.orientation_error)))
    exact = statistics.median(rates["ik_all_batch (verified)"])
    print(f"  calibrated UR5 ik_all_batch        {cal_rate:>10,.0f} targets/s, "
          f"{exact / cal_rate:.1f}x the exact UR5's time; worst error {worst:.1e}")  # fmt: skip
    out["calibrated"] = {"per_s": cal_rate, "time_ratio": exact / cal_rate, "worst_error": worst}
    return out


def locked_panda(n: int, joint: str = "panda_joint7") -> dict[str, object]:
    """The Panda with ``joint`` locked (at the generating configuration's angle), exact and
    calibrated (perturbed +-1 mm, +-0.2 deg): branches, errors and the time of ``ik_all``
    (each new lock value's structure found in it); then ``ik_all`` with one lock value for
    every target (its structure found once)."""
    panda = toolkit.load_example("panda")
    arm = toolkit.load_urdf(cal.perturb(panda, seed=1).urdf_text, mimic=False, tip=panda.tip)
    col = panda.joints.names.index(joint)
    Q = panda.random_q(n, seed=8)
    exact_t, cal_t, worst, count, hit = [], [], 0.0, [], 0
    for q in Q:
        lock = {joint: float(panda.joints.angles(q)[col])}
        t0 = time.perf_counter()
        a = panda.ik_all(panda.fk(q), lock=lock)
        exact_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        b = arm.ik_all(arm.fk(q), lock=lock)
        cal_t.append(time.perf_counter() - t0)
        if len(b.q):
            worst = max(worst, float(b.position_error.max()), float(b.orientation_error.max()))
        count.append(len(set(a.labels)))
        seen = panda.joints.angles(q)[:7]
        hit += any(np.abs(np.remainder(panda.joints.angles(r)[:7] - seen + np.pi,
                                       2 * np.pi) - np.pi).max() < 1e-6 for r in b.q)  # fmt: skip
    ratio = statistics.median(cal_t) / statistics.median(exact_t)
    fixed, Qf = {joint: 0.3}, Q.copy()
    Qf[:, col] = 0.3
    panda.ik_all(panda.fk(Qf[0]), lock=fixed)
    fixed_t = []
    for T in panda.fk(Qf):
        t0 = time.perf_counter()
        panda.ik_all(T, lock=fixed)
        fixed_t.append(time.perf_counter() - t0)
    found = panda.structure_of(lock={joint: 0.3})
    print(f"Panda, {joint} locked ({found.family}{', reversed' if found.reversed else ''}), "
          f"{n} targets: {statistics.mean(count):.2f} branches on average, "
          f"median ik_all {1e3 * statistics.median(exact_t):.2f} ms; calibrated: every branch "
          f"polished to {worst:.1e}, the generating q among them on {hit} of {n}, median "
          f"{1e3 * statistics.median(cal_t):.2f} ms ({ratio:.2f}x); one lock value for "
          f"all targets: median ik_all {1e3 * statistics.median(fixed_t):.3f} ms "
          f"({'compiled' if found.compiled else 'Python'})")  # fmt: skip
    return {"joint": joint, "family": found.family, "targets": n,
            "branches_mean": statistics.mean(count),
            "exact_ms": 1e3 * statistics.median(exact_t),
            "calibrated_ms": 1e3 * statistics.median(cal_t), "time_ratio": ratio,
            "fixed_lock_ms": 1e3 * statistics.median(fixed_t), "compiled": found.compiled,
            "worst_error": worst, "generating_q_found": hit}  # fmt: skip


def _ur5_completeness(n: int) -> dict[str, object]:
    ur5 = toolkit.load_example("ur5")
    missing, distinct = numeric_missing(ur5, ur5.random_q(n, seed=11), starts=200)
    print(f"UR5 completeness: of {distinct} distinct solutions the numeric IK found from 200 "
          f"random starts on each of {n} targets, {missing} not among the branches")  # fmt: skip
    return {"targets": n, "starts": 200, "numeric_distinct": distinct, "missing": missing}


def positioning_structures(n: int, runs: int = 3) -> dict[str, object]:
    """[P3]'s five positioning structures (frame ``point_m``, compiled families placing a
    point): per structure, interleaved on the same targets, ``ik_all`` (verified, one row
    per branch), the family's Python form alone (unverified; what ``ik_all`` ran before
    its kernel), ``ik`` by default and numerically; then ``ik_all_batch`` of all the
    targets (median of ``runs``). Every ``ik_all`` row that succeeds is checked by
    Pinocchio's forward kinematics."""
    out: dict[str, object] = {"targets": n}
    for name in ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic"):
        out[name] = _positioning_structure(toolkit.load(name), n, runs)
    return out


def _positioning_structure(robot: toolkit.Robot, n: int, runs: int) -> dict[str, object]:
    chain, found = robot._analytic._chain_structure(robot.frames.id("point_m"))
    assert chain is not None and found.family is not None and found.compiled
    python = registry.REGISTRY[found.family].python
    P = robot.fk(robot.random_q(n, seed=17), "point_m")[:, :3, 3]
    calls = {
        "ik_all": (lambda p: (p,), lambda p: robot.ik_all(p, frame="point_m")),
        "python_form": (lambda p: (chain, found.points, _pose_of(p)), python),
        "ik": (lambda p: (p,), lambda p: robot.ik(p, frame="point_m")),
        "ik_numeric": (lambda p: (p,), lambda p: robot.ik(p, frame="point_m", method="numeric")),
    }
    times, answers = _interleaved(calls, P)  # type: ignore[arg-type]
    worst, solved = 0.0, 0
    for p, r in zip(P, answers["ik_all"], strict=True):
        good = r.q[r.success]  # type: ignore[attr-defined]
        solved += bool(len(good))
        for q in good:  # Pinocchio's forward kinematics, not the door's
            worst = max(worst, float(np.abs(robot.fk(q, "point_m")[:3, 3] - p).max()))
    robot.ik_all_batch(P[:10], frame="point_m")
    rates = []
    for _ in range(runs):
        t0 = time.perf_counter()
        robot.ik_all_batch(P, frame="point_m")
        rates.append(n / (time.perf_counter() - t0))
    med = {k: 1e6 * statistics.median(v) for k, v in times.items()}
    row = {"family": str(found.family), "solved": solved, "worst_error": worst,
           "median_us": med, "batch_per_s": statistics.median(rates)}  # fmt: skip
    print(f"  {robot.name:<16} {found.family!s:<24} ik_all {med['ik_all']:6.1f} us (Python "
          f"form {med['python_form']:6.1f}), ik {med['ik']:5.1f} us (numeric "
          f"{med['ik_numeric']:5.1f}), batch {row['batch_per_s']:>9,.0f}/s, solved "
          f"{solved}/{n}, worst {worst:.1e} m")  # fmt: skip
    return row


def _pose_of(p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def katana_5r(n: int, starts: int = 200) -> dict[str, object]:
    """The Katana 6M180 (a 5R family): ``ik_all`` and the compiled family kernel alone
    against EAIK on the same targets (interleaved), the numeric IK's solutions looked up
    among the branches, and the perturbed arm."""
    from toolkit.ik import family_kernels
    from toolkit.ik.analytic.door import packed_family

    katana = toolkit.load("katana_6m180")
    Q = katana.random_q(n, seed=2026)
    peer = _peers(katana).get("eaik")
    chain, found = katana._analytic._chain_structure(katana.frames.id(None))
    assert chain is not None
    packed, out, roots = packed_family(chain, found), np.zeros((8, 5)), np.zeros((8, 3), np.int64)
    calls = {
        "ours": katana.ik_all,
        "kernel": lambda T: family_kernels.five_r_parallel(
            *packed, T, False, ZERO6[:5], out, roots, FREE
        ),
        "eaik": None if peer is None else peer.IK,  # type: ignore[attr-defined]
        "ik": katana.ik,  # the default: the nearest verified branch
        "ik_numeric": lambda T: katana.ik(T, method="numeric"),
    }
    times: dict[str, list[float]] = {k: [] for k in calls}
    same = solved = 0
    for i, q in enumerate(Q):
        T = katana.fk(q)
        order = list(calls)[i % len(calls) :] + list(calls)[: i % len(calls)]
        for who in order:
            call = calls[who]
            if call is None:
                continue
            t0 = time.perf_counter()
            answer = call(T)
            times[who].append(time.perf_counter() - t0)
            if who == "ours":  # verified branches, within the limits or not (as EAIK's)
                reached = (answer.position_error <= 1e-10) & (answer.orientation_error <= 1e-10)
                ours = [katana.joints.angles(x) for x in answer.q[reached]]
                solved += bool(answer.success.any())
            elif who == "eaik":
                theirs = _peer_exact("EAIK", answer)
        if peer is not None:
            same += _same_sets(ours, theirs)
    med = {k: 1e6 * statistics.median(v) for k, v in times.items() if v}
    missing, distinct = numeric_missing(katana, Q, starts)
    arm = toolkit.load_urdf(cal.perturb(katana, seed=1).urdf_text, tip=katana.tip)
    kept = lost = hit = 0
    cal_t, exact_t = [], []
    for q in Q[: max(1, n // 5)]:
        t0 = time.perf_counter()
        katana.ik_all(katana.fk(q))
        exact_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        b = arm.ik_all(arm.fk(q))
        cal_t.append(time.perf_counter() - t0)
        kept += len(b.q)
        lost += b.lost
        seen = arm.joints.angles(q)
        hit += any(np.abs(np.remainder(arm.joints.angles(x) - seen + np.pi, 2 * np.pi)
                          - np.pi).max() < 1e-6 for x in b.q)  # fmt: skip
    m = max(1, n // 5)
    ratio = statistics.median(cal_t) / statistics.median(exact_t)
    print(f"Katana 6M180, {n} targets: a verified branch for {solved} of {n}; ik_all median "
          f"{med['ours']:.1f} us, the compiled family kernel alone {med['kernel']:.1f} us, "
          f"ik {med['ik']:.1f} us (numeric {med['ik_numeric']:.1f} us)"
          + (f", EAIK IK {med['eaik']:.1f} us, the same branch sets on "
          f"{same} of {n}" if "eaik" in med else "") + f"; of {distinct} distinct solutions "
          f"the numeric IK found from {starts} starts, {missing} missing from the branches; "
          f"perturbed arm, {m} targets: {kept} branches kept, {lost} lost (another branch's "
          f"pose is not exactly reachable once the symmetry is broken), the generating q "
          f"kept on {hit}, {ratio:.2f}x the exact time")  # fmt: skip
    return {"targets": n, "solved": solved, "median_us": med, "same_sets": same,
            "starts": starts, "numeric_distinct": distinct, "missing": missing,
            "perturbed": {"targets": m, "kept": kept, "lost": lost, "generating_kept": hit,
                          "time_ratio": ratio}}  # fmt: skip


def search_family(robots: int = 20, targets: int = 30, starts: int = 5) -> dict[str, object]:
    """The search family (``meeting pairs, search``) on random robots built from random
    axes (axes 1, 2 through one point, axes 4, 5 through another): how often the
    generating configuration is among the branches, and whether every distinct solution
    the numeric IK finds is."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from helpers import chain_urdf, same_up_to_turns, unit

    rng = np.random.default_rng(31)
    missed = total = numeric = missing = 0
    times = []
    for _ in range(robots):
        h = [unit(rng.normal(size=3)) for _ in range(6)]
        S, W = rng.normal(size=3) * 0.2, rng.normal(size=3) * 0.3 + [0.0, 0.0, 0.6]
        o = [S, S, rng.normal(size=3) * 0.3, W, W, W + rng.normal(size=3) * 0.15]
        robot = toolkit.load_urdf(chain_urdf(h, o, o[5] + rng.normal(size=3) * 0.1, "pairs"))
        assert robot.structure.family == "meeting pairs, search"
        for s in range(targets):
            q = robot.random_q(seed=s)
            T = robot.fk(q)
            t0 = time.perf_counter()
            res = robot.ik_all(T)
            times.append(time.perf_counter() - t0)
            total += 1
            missed += not any(same_up_to_turns(x, q, 1e-7) for x in res.q)
            found: list[np.ndarray] = []
            for start in robot.random_q(starts, seed=1000 + s):
                f = robot.ik(T, q0=start, tol=1e-10, restarts=0, method="numeric")
                if not f.success or any(same_up_to_turns(f.q, x, 1e-6) for x in found):
                    continue
                found.append(f.q)
                sigma = np.linalg.svd(robot.jacobian(f.q), compute_uv=False)[-1]
                close = max(1e-6, 10 * 1e-10 / sigma)
                missing += not any(same_up_to_turns(x, f.q, close) for x in res.q)
            numeric += len(found)
    med = 1e3 * statistics.median(times)
    print(
        f"search family, {robots} random robots x {targets} targets: the generating q among "
        f"the branches for {total - missed} of {total}; of {numeric} distinct numeric "
        f"solutions ({starts} starts each), {missing} missing; median ik_all {med:.2f} ms"
    )
    return {
        "robots": robots,
        "targets": total,
        "generating_found": total - missed,
        "numeric_distinct": numeric,
        "missing": missing,
        "median_ms": med,
    }


def _eaik_verdict(path: str) -> str:
    try:
        from eaik.IK_URDF import UrdfRobot
    except ImportError:
        return "n/a"
    try:
        e = UrdfRobot(path)
        return str(e.getKinematicFamily()) if e.hasKnownDecomposition() else "none"
    except Exception:  # the peer's own refusal
        return "refused"


def _pybullet_rows() -> list[dict[str, object]]:
    """pybullet_data's arms (the ``test`` extra): whole, and the 7-joint ones with joint 3
    locked."""
    try:
        import pybullet_data
    except ImportError:
        return []
    import warnings
    from pathlib import Path

    rows = []
    for file in ("kuka_iiwa/model.urdf", "franka_panda/panda.urdf", "xarm/xarm6_robot.urdf"):
        path = str(Path(pybullet_data.getDataPath()) / file)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # meshes the viewer would miss: not used here
            robot = toolkit.load_urdf(path)
        rows.append({"robot": file, "from": "pybullet_data", "ours": robot.structure.family,
                     "eaik": _eaik_verdict(path)})  # fmt: skip
        names = [robot.model.names[j] for j in range(1, robot.model.njoints)]
        if robot.structure.family is None and len(names) >= 7:
            locked = robot.structure_of(lock={names[2]: 0.3}).family
            rows.append({"robot": f"{file}, joint 3 locked", "from": "pybullet_data",
                         "ours": locked, "eaik": "not tried (a locked joint)"})  # fmt: skip
    for r in rows:
        print(
            f"  {r['robot']:<16} {'pybullet_data':<18} ours: {r['ours'] or '-':<16} "
            f"EAIK: {r['eaik']}"
        )
    return rows


def coverage() -> dict[str, object]:
    names = [("catalogue", n) for n in toolkit.available_models()] + [
        ("example-robot-data", n) for n in toolkit.EXAMPLE_ROBOTS
    ]
    rows = []
    for where, name in names:
        robot = toolkit.load(name) if where == "catalogue" else toolkit.load_example(name)
        eaik = "n/a"
        try:
            from eaik.IK_URDF import UrdfRobot

            try:
                e = UrdfRobot(str(robot.urdf_path))
                eaik = e.getKinematicFamily() if e.hasKnownDecomposition() else "none"
            except Exception:  # the peer's own refusal
                eaik = "refused"
        except ImportError:
            pass
        rows.append({"robot": name, "from": where, "ours": robot.structure.family, "eaik": eaik})
        print(f"  {name:<16} {where:<18} ours: {robot.structure.family or '-':<16} EAIK: {eaik}")
    panda = toolkit.load_example("panda")
    rows += _pybullet_rows()
    for j in (7, 3):
        locked = panda.structure_of(lock={f"panda_joint{j}": 0.3}).family
        rows.append({"robot": f"panda, joint {j} locked", "from": "example-robot-data",
                     "ours": locked, "eaik": "not tried (a locked joint)"})  # fmt: skip
        print(f"  {f'panda (j{j} locked)':<16} {'example-robot-data':<18} ours: {locked}")
    ours = sum(r["ours"] is not None for r in rows)
    theirs = sum(r["eaik"] not in ("none", "refused", "n/a", "not tried (a locked joint)")
                 for r in rows)  # fmt: skip
    files = sum(not str(r["eaik"]).startswith("not tried") for r in rows)
    print(f"coverage: {ours} of {len(rows)} rows with a structure here ({len(rows) - files} "
          f"of them with a joint locked); EAIK {theirs} of the {files} files")  # fmt: skip
    return {"rows": rows, "ours": ours, "eaik": theirs, "arms": len(rows), "files": files}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000, help="UR5 targets")
    parser.add_argument("--only", nargs="+", metavar="SECTION",
                        help="run these sections only (the JSON keys below)")  # fmt: skip
    args, info = begin(parser)
    n = args.n
    sections = {
        "ur5": lambda: ur5_against_peers(n),
        "calibrated_ur5": lambda: calibrated(min(n, 1000)),
        "ur5_completeness": lambda: _ur5_completeness(min(n, 1000)),
        "locked_panda": lambda: locked_panda(min(n, 300)),
        "locked_panda_joint3": lambda: locked_panda(min(n, 300), "panda_joint3"),
        "katana_6m180": lambda: katana_5r(min(n, 1000)),
        "kinova_spherical_wrist": lambda: spherical_wrist_arm(min(n, 2000)),
        "outer_parallel": lambda: outer_parallel(min(n, 2000)),
        "positioning_structures": lambda: positioning_structures(min(n, 2000)),
        "search_family": search_family,
        "batches": lambda: batches(max(n, 20_000)),
        "coverage": coverage,
    }
    unknown = sorted(set(args.only or ()) - set(sections))
    if unknown:
        parser.error(f"unknown section(s) {unknown}; sections: {', '.join(sections)}")
    figures: dict[str, object] = {"machine": info}
    for name, run in sections.items():
        if not args.only or name in args.only:
            figures[name] = run()
    write_json(args.json, figures)


if __name__ == "__main__":
    main()
