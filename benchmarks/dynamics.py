"""Batch inverse dynamics: ``toolkit.dynamics.inverse_dynamics`` (the compiled RNEA over
every core) against a Python loop over Pinocchio's ``rnea`` (what a user writes without the
toolkit) on the same 100,000 random samples (q, qd, qdd) of the UR5, the Panda and the
Kinova Jaco 2 (j2s6s200), one after the other. The two timings alternate, ``--repeats``
times; each figure is the median, and the ratio the median of the repeats' ratios. The
agreement with Pinocchio (largest |difference| [N m]) is printed beside the speed.

Where ``roboticstoolbox-python`` is installed (the ``bench`` extra), the Robotics Toolbox's
``rne`` (500 samples) and ``inertia`` (100) on the same URDF file, against Pinocchio's (and
on every catalogue model's URDF, 100 samples each). On
an arm with fingers, a difference is traced: the same comparison with the fingers' links
massless in the one file both read, and, for prismatic fingers, their gravity torques
(mirror images, axes +y and -y of the hand: the torques must be opposite) at the first
sample. Nothing is asserted.

    python benchmarks/dynamics.py [--n 100000] [--repeats 3] [--json out.json]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
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


def _alternating(ours, theirs, repeats: int) -> tuple[float, float, float, object, object]:
    """(our median seconds, theirs, the median of the per-repeat ratios, our answer, theirs):
    the two runs alternate, so a busy minute slows both."""
    mine, other = ours(), theirs()  # the kernels loaded (compiled, or from the cache)
    times: list[tuple[float, float]] = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        mine = ours()
        t1 = time.perf_counter()
        other = theirs()
        times.append((t1 - t0, time.perf_counter() - t1))
    a, b = statistics.median(t for t, _ in times), statistics.median(t for _, t in times)
    return a, b, statistics.median(o / t for t, o in times), mine, other


def _rtb_model(text: str, folder: str, name: str):
    """The Robotics Toolbox's model of a URDF text (written to ``folder``) and Pinocchio's of
    the same file, or None without the Toolbox."""
    try:
        import roboticstoolbox as rtb
    except ImportError:
        return None
    path = Path(folder) / f"{name}.urdf"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        peer = rtb.Robot.URDF(str(path))
    return peer, pin.buildModelFromUrdf(str(path))


def _rtb(robot: toolkit.Robot, Q, V, A, folder: str) -> dict[str, object] | None:
    """The Robotics Toolbox's ``rne`` and ``inertia`` on the same URDF (its package paths made
    absolute; one angle per joint where Pinocchio stores (cos, sin)): samples per second and
    the largest |difference| from Pinocchio; on an arm with fingers, the trace of a
    difference (the fingers' links massless; the fingers' gravity torques)."""
    share = robot.urdf_path.parents[3]  # .../share/example-robot-data
    text = robot.urdf_path.read_text().replace("package://example-robot-data/", f"{share}/")
    models = _rtb_model(text, folder, robot.name)
    if models is None:
        return None
    peer, model = models
    k = min(len(Q), 500)
    angles = robot.joints.angles(Q[:k])
    t0 = time.perf_counter()
    for q, v, a in zip(angles, V[:k], A[:k], strict=True):
        peer.rne(q, v, a)
    seconds = (time.perf_counter() - t0) / k
    rne, inertia = _worst(peer, model, (Q[:k], angles), V, A)
    row: dict[str, object] = {"rtb_rne_per_s": 1.0 / seconds, "rtb_max_difference_Nm": rne,
                              "rtb_inertia_max_difference": inertia}  # fmt: skip
    fingers = [i for i, j in enumerate(model.names) if "finger" in j and i > 0]
    if fingers and model.joints[fingers[-1]].shortname().startswith("JointModelP"):
        rest, at = np.zeros(model.nv), [model.joints[i].idx_v for i in fingers]
        row["finger_gravity_Nm"] = {  # a tilted hand (at q = 0 their axes are horizontal)
            "pinocchio": pin.rnea(model, model.createData(), Q[0], rest, rest)[at].tolist(),
            "rtb": np.asarray(peer.rne(angles[0], rest, rest))[at].tolist()}  # fmt: skip
    if any("finger" in name for name in _massive_links(text)):
        light = _rtb_model(_without_fingers(text), folder, robot.name + "_light")
        assert light is not None
        rne, inertia = _worst(*light, (Q[:k], angles), V, A)
        row["rtb_massless_fingers"] = {"max_difference_Nm": rne, "inertia_max_difference": inertia}
    return row


def _massive_links(text: str) -> list[str]:
    """The links of a URDF text that have an inertial."""
    return [link.get("name") or "" for link in ET.fromstring(text).iter("link")
            if link.find("inertial") is not None]  # fmt: skip


def _without_fingers(text: str) -> str:
    """The URDF text with every link named "...finger..." massless and without inertia."""
    root = ET.fromstring(text)
    for link in root.iter("link"):
        body = link.find("inertial")
        if "finger" in (link.get("name") or "") and body is not None:
            mass, inertia = body.find("mass"), body.find("inertia")
            if mass is not None:
                mass.set("value", "0.0")
            for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"):
                if inertia is not None:
                    inertia.set(key, "0.0")
    return ET.tostring(root, encoding="unicode")


def _negative_axes(text: str, model: pin.Model) -> np.ndarray:
    """Per degree of freedom: whether its URDF joint's axis points along a negative unit axis
    (an axis such as "0 -1 0")."""
    axes = {joint.get("name"): joint.find("axis") for joint in ET.fromstring(text).iter("joint")}
    out = np.zeros(model.nv, dtype=bool)
    for j in range(1, model.njoints):
        axis = axes.get(model.names[j])
        if axis is not None and model.joints[j].nv == 1:
            values = np.array(axis.get("xyz", "1 0 0").split(), dtype=float)
            out[model.joints[j].idx_v] = values.sum() < 0
    return out


class _Negated:
    """A Toolbox robot whose ``rne`` takes the velocities and accelerations of the ``flips``
    joints negated and gives their torques negated (the trace of its sign on negative axes:
    their angle it reads as given, their rates and torque along the opposite axis)."""

    def __init__(self, peer, flips: np.ndarray) -> None:
        self.peer, self.sign = peer, np.where(flips, -1.0, 1.0)

    def rne(self, q, v, a):
        return self.sign * np.asarray(self.peer.rne(q, self.sign * v, self.sign * a))

    def inertia(self, q):
        return self.sign[:, None] * np.asarray(self.peer.inertia(q)) * self.sign[None, :]


def _worst(peer, model, Q, V, A) -> tuple[float, float]:
    """The largest |difference| of the Toolbox's ``rne`` [N m] from Pinocchio's ``rnea``, and
    of its ``inertia`` from Pinocchio's CRBA (100 samples), at Q = (Pinocchio's q, angles)."""
    data = model.createData()
    rne = max(float(np.abs(np.asarray(peer.rne(a_, v, a)) - pin.rnea(model, data, q, v, a)).max())
              for q, a_, v, a in zip(*Q, V[: len(Q[0])], A[: len(Q[0])], strict=True))  # fmt: skip
    inertia = 0.0
    for q, angles in zip(Q[0][:100], Q[1][:100], strict=True):
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        inertia = max(inertia, float(np.abs(np.asarray(peer.inertia(angles)) - M).max()))
    return rne, inertia


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
        V = rng.uniform(-2.0, 2.0, (args.n, robot.joints.nv))
        A = rng.uniform(-5.0, 5.0, (args.n, robot.joints.nv))
        model, data = robot.model, robot.model.createData()

        def loop(model=model, data=data, Q=Q, V=V, A=A) -> np.ndarray:
            return np.array(
                [pin.rnea(model, data, q, v, a) for q, v, a in zip(Q, V, A, strict=True)]
            )

        ours, theirs, ratio, tau, ref = _alternating(
            lambda r=robot, Q=Q, V=V, A=A: dynamics.inverse_dynamics(r, Q, V, A), loop,
            args.repeats)  # fmt: skip
        diff = float(np.abs(np.asarray(tau) - np.asarray(ref)).max())
        with tempfile.TemporaryDirectory() as folder:
            rtb = _rtb(robot, Q, V, A, folder)
        row = {"toolkit_per_s": args.n / ours, "pinocchio_loop_per_s": args.n / theirs,
               "ratio": ratio, "max_difference_Nm": diff, **(rtb or {})}  # fmt: skip
        figures[name] = row
        print(f"{name:7s} toolkit {row['toolkit_per_s'] / 1e6:.2f} M/s, Python loop over "
              f"pin.rnea {row['pinocchio_loop_per_s'] / 1e3:.0f} k/s: {ratio:.1f}x; "
              f"largest difference {diff:.1e} N m")  # fmt: skip
        if rtb is not None:
            print(f"        RTB (same URDF): rne {rtb['rtb_rne_per_s']:.0f}/s, largest difference "
                  f"{rtb['rtb_max_difference_Nm']:.1e} N m; inertia largest difference "
                  f"{rtb['rtb_inertia_max_difference']:.1e}")  # fmt: skip
        if rtb is not None and "rtb_massless_fingers" in rtb:
            light = rtb["rtb_massless_fingers"]
            print(f"        traced: the fingers massless, rne {light['max_difference_Nm']:.1e} "
                  f"N m, inertia {light['inertia_max_difference']:.1e}")  # fmt: skip
        if rtb is not None and "finger_gravity_Nm" in rtb:
            g = rtb["finger_gravity_Nm"]
            print(f"        the two fingers' gravity torques at the first sample [N]: Pinocchio "
                  f"{g['pinocchio'][0]:+.4f}, {g['pinocchio'][1]:+.4f}; RTB "
                  f"{g['rtb'][0]:+.4f}, {g['rtb'][1]:+.4f}")  # fmt: skip
    figures["mass_matrix"] = _mass_matrices(args.n, args.repeats)
    figures["rtb_catalogue"] = _rtb_catalogue()
    write_json(args.json, figures)


def _mass_matrices(n: int, repeats: int) -> dict[str, object]:
    """The batch mass matrix (``dynamics.mass_matrix``, compiled CRBA) against a plain Python
    loop over ``pin.crba`` on the same configurations, alternating; per arm the rates, the
    ratio and the largest difference from Pinocchio's (made symmetric)."""
    out: dict[str, object] = {}
    for name in ("ur10", "panda", "kinova", "z1"):
        robot = toolkit.load_example(name)
        Q = robot.random_q(n, seed=2)
        model, data = robot.model, robot.model.createData()

        def loop(model=model, data=data, Q=Q) -> list[np.ndarray]:
            return [pin.crba(model, data, q) for q in Q]

        ours, theirs, ratio, M, _ = _alternating(
            lambda r=robot, Q=Q: dynamics.mass_matrix(r, Q), loop, repeats
        )
        ref = np.array([np.array(pin.crba(model, data, q)) for q in Q[:200]])
        ref = np.triu(ref) + np.transpose(np.triu(ref, 1), (0, 2, 1))
        diff = float(np.abs(np.asarray(M)[:200] - ref).max())
        out[name] = {"toolkit_per_s": n / ours, "pinocchio_loop_per_s": n / theirs,
                     "ratio": ratio, "max_difference": diff}  # fmt: skip
        print(f"{name:7s} mass matrix: toolkit {n / ours / 1e3:.0f} k/s, Python loop over "
              f"pin.crba {n / theirs / 1e3:.0f} k/s: {ratio:.1f}x; largest difference "
              f"{diff:.1e}")  # fmt: skip
    return out


def _rtb_catalogue(samples: int = 100) -> dict[str, object]:
    """The Robotics Toolbox's ``rne`` and ``inertia`` against Pinocchio's on every catalogue
    model's URDF (the toolkit's own templates), ``samples`` random states each."""
    rows: dict[str, object] = {}
    with tempfile.TemporaryDirectory() as folder:
        for name in toolkit.available_models():
            robot = toolkit.load(name)
            models = _rtb_model(robot.urdf_path.read_text(), folder, name)
            if models is None:
                return rows
            if models[0].n != robot.joints.nv or models[1].nv != robot.joints.nv:  # mimic joints
                rows[name] = {"skipped": f"RTB reads {models[0].n} joints, the toolkit "
                                         f"{robot.joints.nv} (its mimic joints)"}  # fmt: skip
                print(f"        RTB on {name}: {rows[name]['skipped']}")
                continue
            rng = np.random.default_rng(2)
            Q = robot.random_q(samples, seed=rng)
            V, A = rng.uniform(-2.0, 2.0, (2, samples, robot.joints.nv))
            rne, inertia = _worst(*models, (Q, robot.joints.angles(Q)), V, A)
            rows[name] = {"rne_max_difference_Nm": rne, "inertia_max_difference": inertia}
            flips = _negative_axes(robot.urdf_path.read_text(), models[1])
            line = f"        RTB on {name}: rne {rne:.1e} N m, inertia {inertia:.1e}"
            if flips.any():  # traced: the same with those joints' rates and torques negated
                flipped, flipped_inertia = _worst(_Negated(models[0], flips), models[1],
                                                  (Q, robot.joints.angles(Q)), V, A)  # fmt: skip
                rows[name]["rne_negative_axes_negated_Nm"] = flipped
                rows[name]["inertia_negative_axes_negated"] = flipped_inertia
                which = np.flatnonzero(flips).tolist()
                line += (f"; its joints {which} on negative axes: rates and torques negated, "
                         f"{flipped:.1e} N m, inertia {flipped_inertia:.1e}")  # fmt: skip
            print(line)
    return rows


if __name__ == "__main__":
    main()
