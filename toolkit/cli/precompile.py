"""``toolkit.warmup()`` and ``toolkit warmup``: compile every kernel ahead of time.

A kernel's first call after an installation runs it as Python while a background process
compiles it into the cache (:mod:`toolkit.common.background`); the warm-up compiles every
kernel here and now instead, so that every call runs compiled from the first. The kernels'
signatures do not depend on the robot, so one small robot with every joint kind the
compiled back end takes (revolute, prismatic, continuous, mimic, a free flyer) compiles all
of them.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..collision import Bounds, Scene
from ..common import background
from ..common import validate as _validate
from ..ik import checks
from ..kinematics import PARALLEL_MIN, CompiledBackend, cache_folder
from ..papers.backlash import Backlash
from ..robot import Robot, load, load_example

__all__ = ["warmup"]

_LINK = (
    '<link name="{n}"><inertial><mass value="1"/><origin xyz="0.05 0 0"/>'
    '<inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>'
)
_LIMIT = '<limit lower="-2" upper="2" effort="10" velocity="1"/>'


def _urdf(joints: list[tuple[str, str]]) -> str:
    """A chain of links joined by (type, extra XML) joints."""
    links = "".join(_LINK.format(n=f"l{i}") for i in range(len(joints) + 1))
    body = "".join(
        f'<joint name="j{i}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0.1 0 0.05"/><axis xyz="0 0.6 0.8"/>{extra}</joint>'
        for i, (kind, extra) in enumerate(joints)
    )
    return f'<robot name="warmup">{links}{body}</robot>'


def _meeting_shoulder() -> str:
    """A 6R arm whose axes 1, 2 meet and axes 4, 5, 6 meet (the `spherical wrist, meeting
    shoulder` family)."""
    return _axes_chain([("z", "0 0 0.3"), ("y", "0 0 0"), ("x", "0.1 0 0.4"),
                        ("z", "0.3 0 0.1"), ("y", "0 0 0"), ("z", "0 0 0")])  # fmt: skip


def _general_3r() -> str:
    """A 3R arm with its axes in general position (the `3R, general` family, by SP5)."""
    return _axes_chain([("z", "0 0 0.3"), ("x", "0.1 0.05 0.2"), ("y", "0.3 0.1 0.1"),
                        ("fixed", "0.2 0.05 0.1")])  # fmt: skip


def _axes_chain(joints: list[tuple[str, str]]) -> str:
    """A chain of revolute joints about the x, y or z axis at the given offsets (a
    "fixed" one last for a tool)."""
    links = "".join(_LINK.format(n=f"l{i}") for i in range(len(joints) + 1))
    axes = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}
    body = "".join(
        f'<joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}"/></joint>'
        if a == "fixed"
        else f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}"/><axis xyz="{axes[a]}"/>{_LIMIT}</joint>'
        for i, (a, xyz) in enumerate(joints)
    )
    return f'<robot name="chain">{links}{body}</robot>'


def _robots() -> list[Robot]:
    every_kind = _urdf(
        [
            ("revolute", _LIMIT),
            ("prismatic", _LIMIT),
            ("continuous", ""),
            ("revolute", _LIMIT + '<mimic joint="j0" multiplier="2" offset="0.1"/>'),
        ]
    )
    floating = pin.buildModelFromXML(every_kind, pin.JointModelFreeFlyer(), mimic=True)
    plain = pin.buildModelFromXML(_urdf([("revolute", _LIMIT)] * 3))
    return [Robot(floating, tip="l4"), Robot(plain, tip="l3")]


def warmup(verbose: bool = False) -> dict[str, float]:
    """Compile (or load from the cache) every kernel of the compiled back end, of the
    collision pre-filter, of the backlash layer, of the analytic IK and of the planner;
    returns the seconds each step took (``"total"`` included).

    With ``verbose``, prints each step and where the kernels are cached."""
    verbose = _validate.flag(verbose, "verbose")
    notice = logging.getLogger("toolkit.compile")  # the first-use notice: this is the use
    quiet, notice.disabled = notice.disabled, True
    try:
        with background.waiting():  # compiled here and now, not run as Python
            return _warm(verbose)
    finally:
        notice.disabled = quiet


def _warm(verbose: bool) -> dict[str, float]:  # long: one step a kind of call, each timed
    times: dict[str, float] = {}
    start = time.perf_counter()

    def step(name: str, run: object) -> None:
        t0 = time.perf_counter()
        run() if callable(run) else None
        times[name] = time.perf_counter() - t0
        if verbose:
            print(f"  {name:<28} {times[name]:7.2f} s", flush=True)

    folder, why = cache_folder()
    if verbose:
        print(f"compiled kernels cached in: {folder or 'memory'} ({why})", flush=True)
    for robot in _robots():
        few, many = robot.random_q(2, seed=0), robot.random_q(PARALLEL_MIN, seed=0)
        targets = robot.fk(many[:16])
        label = f"{robot.name} (nq {robot.nq})"
        step(f"fk {label}", lambda r=robot, a=few, b=many: (r.fk(a), r.fk(b)))
        step(f"jacobian {label}", lambda r=robot, a=few, b=many: (r.jacobian(a), r.jacobian(b)))
        step(f"gravity {label}", lambda r=robot, a=few, b=many: (r.gravity(a), r.gravity(b)))
        step(f"ik {label}", lambda r=robot, t=targets: (r.ik(t[0]), r.ik(t[0][:3, 3])))
        step(f"ik_batch {label}", lambda r=robot, t=targets: r.ik_batch(np.repeat(t, 4, axis=0)))
        if isinstance(robot.kinematics, CompiledBackend):
            bounds = Bounds(pin.GeometryModel(), robot.kinematics)
            step(
                f"collision pre-filter {label}",
                lambda b=bounds, a=few, m=many: (b.decide(a), b.decide(m)),
            )
        if robot.nq == robot.joints.nv:
            layer = Backlash(robot, nominal_torque=np.full(robot.nq, 5.0))
            step(f"backlash {label}", lambda b=layer, a=few, m=many: (b.solve(a), b.solve(m)))
    _analytic_steps(step)
    _planning_step(step)
    times["total"] = time.perf_counter() - start
    if verbose:
        print(f"warm-up done in {times['total']:.1f} s", flush=True)
    return times


def _planning_step(step: Callable[[str, object], None]) -> None:
    """The planner's compiled search (a UR5 around a wall: trees, edges, shortcuts)."""
    ur5 = load_example("ur5")
    wall = Scene().add_box("wall", [0.1, 1.2, 0.8], [0.45, 0.0, 0.4])
    a = np.array([-1.4, -1.0, 1.5, -1.9, -1.57, 0.0])
    b = a * [-1, 1, 1, 1, 1, 1]
    step("planner ur5", lambda: ur5.plan(a, b, scene=wall, seed=0))


def _analytic_steps(step: Callable[[str, object], None]) -> None:
    """The analytic IK's compiled families, one target and a batch each."""
    ur5 = load_example("ur5")  # three parallel
    kinova = load_example("kinova")  # a spherical wrist, continuous joints
    katana = load("katana_6m180")  # 5R, axes 2, 3, 4 parallel
    shoulder = Robot(pin.buildModelFromXML(_meeting_shoulder()), tip="l6")
    arms = (("ur5", ur5), ("kinova", kinova), ("katana_6m180", katana), ("shoulder", shoulder))
    backend = ur5.kinematics  # the judge of a calibrated arm's polished rows
    if isinstance(backend, CompiledBackend):
        q, chain = ur5.random_q(PARALLEL_MIN, seed=0), backend.chain(ur5.frames.id(None))
        owner, poses = np.zeros(len(q), np.int64), ur5.fk(q)
        step("analytic polish errors", lambda: [
            checks.owned_errors(s, q, *chain, poses, owner) for s in (False, True)])  # fmt: skip
    for name, robot in arms:
        poses = robot.fk(robot.random_q(PARALLEL_MIN, seed=0))
        step(f"analytic ik_all {name}", lambda r=robot, p=poses: r.ik_all(p[0]))
        step(
            f"analytic ik_all_batch {name}",
            lambda r=robot, p=poses: (r.ik_all_batch(p[:2]), r.ik_all_batch(p)),
        )
    # the families placing a point ([P3]'s five structures, a 3R with axes 2, 3 parallel, a
    # general 3R) and the search (the Panda with joint 3 locked): each its own kernel
    general = Robot(pin.buildModelFromXML(_general_3r()), tip="l4")
    parallel_3r = Robot(pin.buildModelFromXML(_axes_chain([
        ("z", "0 0 0.3"), ("y", "0.1 0 0.2"), ("y", "0.3 0 0.1"), ("fixed", "0.2 0 0.1")])),
        tip="l4")  # fmt: skip
    panda, lock = load_example("panda"), {"panda_joint3": 0.3}
    more: list[tuple[str, Robot, str | None, dict[str, float] | None]] = [
        (name, load(name), "point_m", None)
        for name in ("cartesian", "cylindrical", "spherical", "scara", "anthropomorphic")
    ]
    more += [("3R parallel", parallel_3r, None, None), ("3R general", general, None, None),
             ("panda, joint 3 locked", panda, None, lock)]  # fmt: skip
    for name, robot, frame, held in more:
        q = robot.random_q(PARALLEL_MIN, seed=0)
        if held:
            q[:, 2] = 0.3
        poses = robot.fk(q, frame)
        targets = poses[:, :3, 3] if robot.structure_of(frame, lock=held).places_point else poses
        step(
            f"analytic ik_all {name}",
            lambda r=robot, t=targets, f=frame, k=held: r.ik_all(t[0], frame=f, lock=k),
        )
        step(
            f"analytic ik_all_batch {name}",
            lambda r=robot, t=targets, f=frame, k=held: (
                r.ik_all_batch(t[:2], frame=f, lock=k),
                r.ik_all_batch(t, frame=f, lock=k),
            ),
        )
