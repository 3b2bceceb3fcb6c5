"""Online motion (Ruckig's online trajectory generation, the ``motion`` extra): a controller
loop asks, every cycle of ``dt`` seconds, for the next state toward a target that may
change at any cycle (a moving part, a new command), within joint velocity, acceleration
and jerk limits, from whatever state the arm is in: the state carries over, so the motion
stays smooth across a change of target."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..robot import as_robot
from .profiles import extra_module, limit_of

__all__ = ["Online"]


class Online:
    """Jerk-limited motion toward a target that may change every cycle.

    ``Online(robot, dt, acceleration=, jerk=, velocity=None, start=None)``: cycles of
    ``dt`` [s]; limits per joint or one for all [rad/s, rad/s^2, rad/s^3, or m] (velocity
    default: the description's); ``start`` the configuration q (default: the middle of
    the limits), at rest. :meth:`step` advances one cycle toward a target configuration;
    :meth:`run` steps until the target is reached at rest. ``q``, ``values`` (one per
    joint), ``qd``, ``qdd`` and ``t`` are the current state.
    """

    def __init__(
        self, robot: Any, dt: float, *, acceleration: ArrayLike, jerk: ArrayLike,
        velocity: ArrayLike | None = None, start: ArrayLike | None = None,
    ) -> None:  # fmt: skip
        self._ruckig = extra_module("ruckig", "Online")
        self.robot = as_robot(robot)
        self.dt = _validate.number(dt, "dt [s]", lower=0.0, strict=True, upper=10.0)
        n = self.robot.joints.nv
        v = limit_of(self.robot, velocity, "velocity", np.asarray(self.robot.model.velocityLimit))
        a = limit_of(self.robot, acceleration, "acceleration", None)
        j = limit_of(self.robot, jerk, "jerk", None)
        if v is None or a is None or j is None:
            raise InvalidParameterError(
                f"{self.robot.name}: give velocity= (its description has no finite limits), "
                "acceleration= and jerk="
            )
        self.limits = (v, a, j)
        q0 = self.robot.joints.neutral() if start is None else self.robot.joints.check(start)
        self.values = np.asarray(self.robot.joints.angles(q0), dtype=float)
        self.qd, self.qdd, self.t = np.zeros(n), np.zeros(n), 0.0
        self._otg = self._ruckig.Ruckig(n, self.dt)
        self._in = self._ruckig.InputParameter(n)
        self._out = self._ruckig.OutputParameter(n)
        self._in.max_velocity, self._in.max_acceleration = v.tolist(), a.tolist()
        self._in.max_jerk = j.tolist()

    @property
    def q(self) -> np.ndarray:
        """The current configuration (nq,)."""
        return np.asarray(self.robot.joints.q_from_angles(self.values), dtype=float)

    def step(self, target: ArrayLike) -> bool:
        """One cycle toward ``target`` (a configuration (nq,), within the limits); True once
        it is reached at rest. The state (``values``, ``qd``, ``qdd``, ``t``) moves on."""
        goal = self.robot.joints.check(target)
        if not self.robot.joints.within_limits(goal):
            raise InvalidParameterError(f"target is outside {self.robot.name}'s joint limits")
        inp, out = self._in, self._out
        inp.current_position = self.values.tolist()
        inp.current_velocity, inp.current_acceleration = self.qd.tolist(), self.qdd.tolist()
        inp.target_position = np.asarray(self.robot.joints.angles(goal), dtype=float).tolist()
        inp.target_velocity = inp.target_acceleration = [0.0] * self.robot.joints.nv
        result = self._otg.update(inp, out)
        if result not in (self._ruckig.Result.Working, self._ruckig.Result.Finished):
            raise InvalidParameterError(f"Ruckig found no motion to the target: {result}")
        self.values = np.array(out.new_position, dtype=float)
        self.qd = np.array(out.new_velocity, dtype=float)
        self.qdd = np.array(out.new_acceleration, dtype=float)
        self.t += self.dt
        return bool(result == self._ruckig.Result.Finished)

    def run(self, target: ArrayLike, max_cycles: int = 1_000_000) -> dict[str, np.ndarray]:
        """Step toward ``target`` until it is reached at rest (at most ``max_cycles``): the
        states of every cycle, ``t`` (M,), ``values``, ``qd``, ``qdd`` (M, nv)."""
        max_cycles = _validate.count(max_cycles, "max_cycles", minimum=1, maximum=10**8)
        rows: list[tuple[float, np.ndarray, np.ndarray, np.ndarray]] = []
        for _ in range(max_cycles):
            done = self.step(target)
            rows.append((self.t, self.values, self.qd, self.qdd))
            if done:
                break
        else:
            raise InvalidParameterError(f"the target was not reached in {max_cycles} cycles")
        names = ("t", "values", "qd", "qdd")
        return {name: np.array([r[k] for r in rows]) for k, name in enumerate(names)}
