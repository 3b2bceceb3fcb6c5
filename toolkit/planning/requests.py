"""MoveIt's motion plan requests (``moveit_msgs/MotionPlanRequest``) read into a
:class:`MotionRequest`, and joint trajectories (``moveit_msgs/RobotTrajectory``) written and
read as YAML (:mod:`toolkit.planning.moveit` has the formats' rules)."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..descriptions import read_srdf
from ..errors import InvalidParameterError
from .moveit import listed, load_yaml, numbers, pose_of

__all__ = [
    "JointTrajectory",
    "MotionRequest",
    "read_joint_trajectory",
    "read_request",
    "write_joint_trajectory",
]


@dataclass(frozen=True)
class MotionRequest:
    """A motion plan request: the ``start`` joint values by name, the goals (``joint_goals``:
    joint values by name, or ``pose_goals``: (link, 4x4 pose) pairs; any one goal ends a
    plan), the ``group`` named and the ``time_limit`` allowed [s] (None: not given)."""

    start: Mapping[str, float]
    joint_goals: tuple[Mapping[str, float], ...] = ()
    pose_goals: tuple[tuple[str, np.ndarray], ...] = field(default=(), repr=False)
    group: str = ""
    time_limit: float | None = None

    def planned(self, robot: Any) -> list[str]:
        """The joints the plan moves: those the joint goals name, or for pose goals the
        joints that move the goal's link."""
        if self.joint_goals:
            names = {n for goal in self.joint_goals for n in goal}
            return [n for n in robot.joints.names if n in names]
        model = robot.model
        frame = model.frames[robot.frames.id(self.pose_goals[0][0])]
        moving = set(model.supports[frame.parentJoint][1:])
        return [model.names[j] for j in range(1, model.njoints) if j in moving]

    def held(self, robot: Any) -> list[str]:
        """The robot's other joints (fingers, say): held at their start values."""
        moved = set(self.planned(robot))
        return [n for n in robot.joints.names if n not in moved]

    def ignored(self, robot: Any) -> list[str]:
        """The joints the start state names that do not move in the robot's description:
        fixed there (a gripper's knuckles, Baxter's head) or not in it (Fetch's wheels, in
        a description of the arm and torso). MoveIt takes no value for them either."""
        moving = set(robot.joints.names)
        return [name for name in self.start if name not in moving]

    def start_q(self, robot: Any) -> np.ndarray:
        """The start configuration q: the named joints at their values, the others at the
        robot's neutral values; a held joint outside its limits is brought to the nearest
        limit (a request's finger opening wider than the description allows), a planned
        one is left for the planner to refuse. Joints that do not move in the description
        are :meth:`ignored`."""
        fixed = set(self.ignored(robot))
        named = {name: value for name, value in self.start.items() if name not in fixed}
        values = _set(robot, robot.joints.angles(robot.joints.neutral()), named, "start_state")
        low, high = (
            np.asarray(robot.joints.lower, float),
            np.asarray(robot.joints.upper, float),
        )  # per q
        model = robot.model
        for name in self.held(robot):
            joint = model.joints[model.getJointId(name)]
            if joint.nq == 1:  # a continuous joint's angle has no limit to bring it to
                k, at = joint.idx_v, joint.idx_q
                values[k] = min(max(values[k], low[at]), high[at])
        return np.asarray(robot.joints.q_from_angles(values), dtype=float)

    def goal_q(self, robot: Any) -> np.ndarray:
        """The joint goals as configurations (G, nq), the unnamed joints at the start's."""
        if not self.joint_goals:
            raise InvalidParameterError("the request's goals are poses: see pose_goals")
        start = robot.joints.angles(self.start_q(robot))
        goals = [_set(robot, start.copy(), g, f"goal_constraints[{i}]")
                 for i, g in enumerate(self.joint_goals)]  # fmt: skip
        return np.asarray(robot.joints.q_from_angles(np.array(goals)), dtype=float)

    def robot_for(self, robot: Any) -> Any:
        """The robot the request plans for: where the robot's SRDF declares the request's
        ``group_name``, the group's robot (``robot.group``: its other joints locked at the
        start state's values, and left out of the plan and its trajectory); else
        ``robot`` (its joints the goals leave out are :meth:`held`)."""
        if not self.group or self.group not in read_srdf(robot.srdf_path)[0]:
            return robot
        return robot.group(self.group, at=self.start_q(robot))

    def plan(self, robot: Any, scene: Any = None, **options: Any) -> Any:
        """``robot.plan`` of this request (a :class:`~toolkit.planning.PlanResult`): for
        :meth:`robot_for` (pass that robot: its path holds the group's joints), from
        :meth:`start_q` to the goals, :meth:`held` joints held, the request's time limit
        unless ``time_limit`` is given; ``options`` as for ``Robot.plan``."""
        robot = self.robot_for(robot)
        if self.time_limit is not None:
            options.setdefault("time_limit", self.time_limit)
        start, hold = self.start_q(robot), self.held(robot) or None
        if self.joint_goals:
            result = robot.plan(start, self.goal_q(robot), scene=scene, hold=hold, **options)
        else:
            poses = np.array([T for _, T in self.pose_goals])
            result = robot.plan(start, pose=poses, frame=self.pose_goals[0][0], scene=scene,
                                hold=hold, **options)  # fmt: skip
        return dataclasses.replace(result, ignored=tuple(self.ignored(robot)))


def _fixed_joints(robot: Any) -> set[str]:
    """The names of the joints the robot's description fixes (Pinocchio's fixed-joint
    frames)."""
    import pinocchio as pin

    return {f.name for f in robot.model.frames if f.type == pin.FrameType.FIXED_JOINT}


def _set(robot: Any, values: np.ndarray, named: Mapping[str, float], where: str) -> np.ndarray:
    for name, value in named.items():
        if name not in robot.joints.names:
            joints = ", ".join(robot.joints.names)
            fixed = " (its description fixes it)" if name in _fixed_joints(robot) else ""
            raise InvalidParameterError(
                f"{where}: no moving joint {name!r} in {robot.name}{fixed}; its joints: {joints}"
            )
        values[robot.joints.names.index(name)] = value
    return values


def _joint_goal(constraints: list[Any], where: str) -> dict[str, float]:
    goal = {}
    for k, c in enumerate(constraints):
        if not isinstance(c, Mapping) or not isinstance(c.get("joint_name"), str):
            raise InvalidParameterError(f"{where}.joint_constraints[{k}]: {{joint_name, position}}")
        goal[c["joint_name"]] = float(
            numbers(c.get("position"), 1, f"{where}.joint_constraints[{k}].position")[0]
        )
    return goal


def _pose_goal(item: Mapping[str, Any], where: str) -> tuple[str, np.ndarray]:
    pos, rot = (
        listed(item, "position_constraints", where),
        listed(item, "orientation_constraints", where),
    )
    if len(pos) != 1 or len(rot) != 1:
        raise InvalidParameterError(
            f"{where}: a pose goal is one position and one orientation constraint "
            f"(got {len(pos)} and {len(rot)}); a position alone is not read"
        )
    p, o = pos[0], rot[0]
    link = str(p.get("link_name", "")) if isinstance(p, Mapping) else ""
    if not link or not isinstance(o, Mapping) or o.get("link_name") != link:
        raise InvalidParameterError(f"{where}: both constraints on one link_name")
    offset = numbers(p.get("target_point_offset", [0, 0, 0]), 3, f"{where}.target_point_offset")
    if np.abs(offset).max() > 0:
        raise InvalidParameterError(f"{where}.target_point_offset: only a zero offset is read")
    region = p.get("constraint_region") or {}
    poses = listed(region, "primitive_poses", f"{where}.constraint_region")
    if len(poses) != 1:
        raise InvalidParameterError(f"{where}.constraint_region: one primitive pose (the target)")
    T = pose_of(poses[0], f"{where}.constraint_region.primitive_poses[0]")
    T[:3, :3] = pose_of({"orientation": o.get("orientation")}, f"{where}.orientation")[:3, :3]
    return link, T


def read_request(source: object) -> MotionRequest:
    """The :class:`MotionRequest` of a MoveIt motion plan request (a YAML file or its
    mapping; :mod:`toolkit.planning.moveit`)."""
    data, label = load_yaml(source, "a MoveIt motion plan request")
    try:
        state = data.get("start_state") or {}
        js = state.get("joint_state") or {} if isinstance(state, Mapping) else {}
        names, values = listed(js, "name", "start_state.joint_state"), js.get("position") or []
        values = numbers(values, len(names), "start_state.joint_state.position") if names else []
        start = {str(n): float(v) for n, v in zip(names, values, strict=True)}
        joints: list[dict[str, float]] = []
        poses: list[tuple[str, np.ndarray]] = []
        for i, item in enumerate(listed(data, "goal_constraints", "request")):
            where = f"goal_constraints[{i}]"
            if not isinstance(item, Mapping):
                raise InvalidParameterError(f"{where}: a mapping of constraints")
            constraints = listed(item, "joint_constraints", where)
            if constraints:
                joints.append(_joint_goal(constraints, where))
            else:
                poses.append(_pose_goal(item, where))
        if not joints and not poses:
            raise InvalidParameterError("goal_constraints: no goal")
        if joints and poses:
            raise InvalidParameterError("goal_constraints: joint goals and pose goals together")
        if len({link for link, _ in poses}) > 1:
            raise InvalidParameterError("goal_constraints: pose goals on different links")
        limit = data.get("allowed_planning_time")
        seconds = float(numbers(limit, 1, "allowed_planning_time")[0]) if limit else None
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"{label}: {exc}") from None
    return MotionRequest(start, tuple(joints), tuple(poses), str(data.get("group_name") or ""),
                         seconds if seconds and seconds > 0 else None)  # fmt: skip


@dataclass(frozen=True)
class JointTrajectory:
    """A joint trajectory as MoveIt holds one: ``names`` (n,), ``times`` (K,) [s] from the
    start, ``positions`` (K, n) (joint values: angles [rad] or strokes [m]), and where
    given ``velocities`` and ``accelerations`` (K, n)."""

    names: tuple[str, ...]
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None = None
    accelerations: np.ndarray | None = None


def write_joint_trajectory(
    path: str | os.PathLike[str], names: Sequence[str], times: ArrayLike, positions: ArrayLike,
    velocities: ArrayLike | None = None, accelerations: ArrayLike | None = None,
) -> Path:  # fmt: skip
    """Write a ``moveit_msgs/RobotTrajectory`` YAML file (its ``joint_trajectory``): the
    ``names`` of n joints, ``times`` (K,) [s] from the start, increasing, ``positions`` (K,
    n), and optionally ``velocities`` and ``accelerations`` (K, n). Returns the path."""
    import yaml

    names = [str(n) for n in names] if not isinstance(names, str) else []
    t = _validate.real_array(times, "times").ravel()
    Q = _validate.real_array(positions, "positions")
    if not names or Q.shape != (len(t), len(names)) or not np.isfinite(Q).all():
        raise InvalidParameterError(
            f"positions must be finite (K, n) for {len(t)} times and {len(names)} joint names, "
            f"got {Q.shape}"
        )
    if not np.isfinite(t).all() or t[0] < 0 or (np.diff(t) <= 0).any():
        raise InvalidParameterError("times must be finite, >= 0 and increasing")
    extra = {}
    for key, value in (("velocities", velocities), ("accelerations", accelerations)):
        if value is not None:
            arr = _validate.real_array(value, key)
            if arr.shape != Q.shape or not np.isfinite(arr).all():
                raise InvalidParameterError(f"{key} must be finite {Q.shape}, got {arr.shape}")
            extra[key] = arr
    points = []
    for k, tk in enumerate(t):
        sec = math.floor(tk)
        nano = min(round((tk - sec) * 1e9), 999_999_999)
        point: dict[str, Any] = {"positions": [float(v) for v in Q[k]]}
        point.update({key: [float(v) for v in arr[k]] for key, arr in extra.items()})
        point["time_from_start"] = {"sec": int(sec), "nanosec": int(nano)}
        points.append(point)
    document = {"joint_trajectory": {"joint_names": names, "points": points}}
    out = Path(path)
    out.write_text(yaml.safe_dump(document, default_flow_style=None, sort_keys=False),
                   encoding="utf-8")  # fmt: skip
    return out


def read_joint_trajectory(source: object) -> JointTrajectory:
    """The :class:`JointTrajectory` of a ``moveit_msgs/RobotTrajectory`` YAML file (or its
    ``joint_trajectory`` alone), as :func:`write_joint_trajectory` writes it."""
    data, label = load_yaml(source, "a MoveIt joint trajectory")
    traj = data.get("joint_trajectory", data)
    try:
        names = tuple(str(n) for n in listed(traj, "joint_names", "joint_trajectory"))
        points = listed(traj, "points", "joint_trajectory")
        if not names or not points:
            raise InvalidParameterError("joint_trajectory: joint_names and points are needed")
        cols: dict[str, list[np.ndarray]] = {"positions": [], "velocities": [], "accelerations": []}
        times = []
        for k, p in enumerate(points):
            where = f"joint_trajectory.points[{k}]"
            if not isinstance(p, Mapping):
                raise InvalidParameterError(f"{where}: a mapping")
            for key, rows in cols.items():
                if p.get(key) or key == "positions":
                    rows.append(numbers(p.get(key), len(names), f"{where}.{key}"))
            stamp = p.get("time_from_start") or {}
            sec = stamp.get("sec", stamp.get("secs", 0)) if isinstance(stamp, Mapping) else stamp
            nano = stamp.get("nanosec", stamp.get("nsecs", 0)) if isinstance(stamp, Mapping) else 0
            times.append(float(numbers([sec, nano], 2, f"{where}.time_from_start") @ [1.0, 1e-9]))
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"{label}: {exc}") from None
    extra = {k: (np.array(v) if len(v) == len(points) else None) for k, v in cols.items()}
    return JointTrajectory(names, np.array(times), np.array(cols["positions"]),
                           extra["velocities"], extra["accelerations"])  # fmt: skip
