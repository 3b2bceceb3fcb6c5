"""Views of the toolkit's answers in a :class:`~toolkit.viz.Viewer` (mixed into it): where a
placement puts the robot (:meth:`AnswerViews.show_placement`), every IK branch of a target
at once (:meth:`AnswerViews.show_branches`) and a trajectory or a plan played in real time
(:meth:`AnswerViews.play`)."""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..collision import Scene
from ..common import caller_level
from ..common import validate as _validate
from ..errors import CollisionWarning, InvalidParameterError
from .visuals import bones_model, frame_box

__all__ = ["BRANCH_COLOURS", "AnswerViews"]

BRANCH_COLOURS = (
    (0.84, 0.15, 0.16, 0.6), (0.17, 0.63, 0.17, 0.6), (0.58, 0.40, 0.74, 0.6),
    (0.89, 0.47, 0.76, 0.6), (0.55, 0.34, 0.29, 0.6), (0.74, 0.74, 0.13, 0.6),
    (0.09, 0.75, 0.81, 0.6), (0.30, 0.30, 0.30, 0.6), (0.12, 0.47, 0.71, 0.6),
)  # fmt: skip
"""The ghosts' colours, one per branch after the first (translucent; the robot's own orange
is the first branch)."""


class AnswerViews:
    """The answer views of :class:`~toolkit.viz.Viewer` (mixed into it)."""

    if TYPE_CHECKING:  # Viewer's, declared for the type checker
        meshcat: Any
        _ghosts: dict[str, Any]
        _q: np.ndarray

        def _load(self, name: str, color: np.ndarray | None, geometry: Any = None) -> Any: ...

        def _node(self, name: str) -> Any: ...

        def _drop(self, name: str) -> None: ...

        robot: Any
        _main: Any

        def show(self, q: ArrayLike) -> None: ...

        def frame(self, q: ArrayLike | None = None) -> None: ...

        def show_scene(self, scene: Scene, color: Sequence[float] = ...) -> None: ...

        def ghost(self, q: ArrayLike, name: str = ..., color: Sequence[float] = ...) -> None: ...

        def marker(
            self, position: Sequence[float], name: str = ..., radius: float = ...,
            color: Sequence[float] = ...,
        ) -> None: ...  # fmt: skip

    def _bones(self) -> Any:
        """The robot as a stick figure: it takes a colour, where meshes may keep their own."""
        low, high = frame_box(self.robot)
        return bones_model(self.robot, 0.02 * max(float(np.linalg.norm(high - low)), 0.05))

    def show_placement(
        self, result: Any, rank: int = 0, scene: Scene | None = None, dt: float = 0.5
    ) -> int:
        """The robot at a base of a :func:`toolkit.maps.placement` answer (``rank`` 0: the
        best), drawn in that base's frame: the tasks as markers (green: reached there, red:
        not), the ``scene`` as that base sees it, and the robot reaching each reached task
        in turn, ``dt`` seconds each (0: the last one only). Returns the tasks shown."""
        from ..maps import Placement, base_pose, scene_from_base

        if not isinstance(result, Placement):
            raise InvalidParameterError(
                f"result must be a toolkit.maps.Placement, got {result!r:.80}"
            )
        rank = _validate.count(rank, "rank", minimum=0, maximum=len(result.bases) - 1)
        dt = _validate.number(dt, "dt [s]", lower=0.0)
        B = base_pose(result.bases[rank])
        tasks = np.linalg.inv(B) @ result.tasks
        reached = result.reached[rank]
        self._drop("markers")
        for i, (T, ok) in enumerate(zip(tasks, reached, strict=True)):
            color = (0.1, 0.75, 0.2, 1.0) if ok else (0.9, 0.1, 0.1, 1.0)
            self.marker(T[:3, 3], name=f"task{i}", radius=0.012, color=color)
        if scene is not None:
            self.show_scene(scene_from_base(scene, B))  # type: ignore[arg-type]
        shown = result.q[rank][reached]
        if len(shown):
            self.frame(shown[-1])
        for k, q in enumerate(shown):
            self.show(q)
            if dt and k < len(shown) - 1:
                time.sleep(dt)
        return len(shown)

    def show_branches(self, result: Any, *, within_limits: bool = True) -> list[str]:
        """Every branch of a :meth:`~toolkit.Robot.ik_all` answer at once: the robot at the
        first, a translucent stick figure in its own colour (:data:`BRANCH_COLOURS`: the
        primitive shapes of :func:`~toolkit.viz.visuals.bones_model`, which take a colour where
        a description's meshes may not) at each other,
        one configuration per branch label (the first row listed; of the rows within the
        limits unless ``within_limits=False``). Ghosts of an earlier call that this one does
        not use are hidden. Returns the labels drawn, the robot's first."""
        from ..ik import IKAllResult

        if not isinstance(result, IKAllResult):
            raise InvalidParameterError(
                f"result must be the answer of Robot.ik_all, got {result!r:.80}"
            )
        within_limits = _validate.flag(within_limits, "within_limits")
        keep = result.success if within_limits else np.ones(len(result.q), dtype=bool)
        reached = (result.position_error <= 1e-9) & (result.orientation_error <= 1e-9)
        first: dict[str, np.ndarray] = {}
        for q, label, ok in zip(result.q, result.labels, keep & reached, strict=True):
            if ok:
                first.setdefault(label, q)
        labels = list(first)
        for name in self._ghosts:
            if name.startswith("branch"):
                self._node(name).set_property("visible", False)
        if not labels:
            return []
        self.frame(first[labels[0]])
        self.show(first[labels[0]])
        shapes = None
        for k, label in enumerate(labels[1:]):
            name = f"branch{k}"
            if name not in self._ghosts:  # a stick figure takes the colour (meshes may not)
                shapes = self._bones() if shapes is None else shapes
                colour = np.array(BRANCH_COLOURS[k % len(BRANCH_COLOURS)])
                self._ghosts[name] = self._load(name, colour, shapes)
            self._ghosts[name].display(first[label])
            self._node(name).set_property("visible", True)
        return labels

    def play(
        self, trajectory: Any, *, rate: float = 30.0, layer: Any = None,
        scene: Scene | None = None, acceleration: float = 2.0,
    ) -> int:  # fmt: skip
        """Play a :class:`toolkit.motion.Trajectory`, or a plan (a
        :class:`toolkit.planning.PlanResult`, timed trapezoidally at ``acceleration``
        [rad/s^2] within the description's velocity limits), in real time with meshcat's
        animation (the browser's Animations panel: play, pause, the time slider), sampled at
        ``rate`` [frames/s]; ``scene`` is drawn, and a sampled frame that collides (with the
        robot itself or the scene) is shown as a red ghost at the first such frame, with a
        warning naming the time and the pair. With a :class:`~toolkit.backlash.Backlash`
        ``layer``, the robot shows the joint outputs along the motion (the motion's torques:
        :func:`toolkit.backlash.along`) and a ghost the commands. Returns the number of
        frames."""
        from meshcat.animation import Animation

        trajectory = _timed(self.robot, trajectory, acceleration)
        rate = _validate.number(rate, "rate [frames/s]", lower=0.0, strict=True, upper=240.0)
        samples = trajectory.at_rate(self.robot, rate)
        commands = samples.q
        if scene is not None:
            self.show_scene(scene)
        self._first_collision(samples.t, commands, scene)
        shown, ghost = commands, None
        if layer is not None:
            from ..papers.backlash import along

            shown = along(layer, trajectory, rate).theta_dynamic
            self.ghost(commands[0], name="commanded")
            ghost = self._ghosts["commanded"]
        self.show(shown[0])
        animation = Animation(default_framerate=rate)
        for k in range(len(shown)):
            with animation.at_frame(self.meshcat, k) as frame:
                _place(self._main, shown[k], frame)
                if ghost is not None:
                    _place(ghost, commands[k], frame)
        self.meshcat.set_animation(animation, play=True, repetitions=1)
        return len(shown)

    def _first_collision(self, t: np.ndarray, Q: np.ndarray, scene: Scene | None) -> None:
        """A red ghost and a warning at the first sampled configuration that collides."""
        hits = np.atleast_1d(np.asarray(self.robot.in_collision(Q, scene), dtype=bool))
        if not hits.any():
            return
        k = int(np.argmax(hits))
        pair = self.robot.collision_checker(scene).collisions(Q[k])[0]
        if "collision" not in self._ghosts:  # a stick figure: it takes the red (meshes may not)
            red = np.array([0.9, 0.1, 0.1, 0.8])
            self._ghosts["collision"] = self._load("collision", red, self._bones())
        self._ghosts["collision"].display(Q[k])
        warnings.warn(
            f"the motion collides at t = {t[k]:.3f} s: {pair[0]} with {pair[1]} "
            f"({int(hits.sum())} of {len(hits)} frames); the red ghost shows the first",
            CollisionWarning,
            stacklevel=caller_level(),
        )


def _timed(robot: Any, value: Any, acceleration: float) -> Any:
    """A Trajectory: ``value`` itself, or a solved plan's path timed trapezoidally."""
    from ..motion import Trajectory, trapezoidal
    from ..planning import PlanResult

    if isinstance(value, PlanResult):
        if not value.success:
            raise InvalidParameterError(f"the plan has no path to play: {value.reason}")
        return trapezoidal(robot, value.path, acceleration=acceleration)
    if not isinstance(value, Trajectory):
        raise InvalidParameterError(
            f"play takes a toolkit.motion.Trajectory or a toolkit.planning.PlanResult, got "
            f"{value!r:.80} (animate() takes joint values)"
        )
    return value


def _place(viz: Any, q: np.ndarray, frame: Any) -> None:
    """Each visual shape of a pinocchio MeshcatVisualizer ``viz`` at configuration q, as an
    animation frame's transforms (rotation and position: the scale the shape was loaded
    with stays)."""
    import pinocchio as pin

    pin.forwardKinematics(viz.model, viz.data, q)
    pin.updateGeometryPlacements(viz.model, viz.data, viz.visual_model, viz.visual_data)
    for k, shape in enumerate(viz.visual_model.geometryObjects):
        name = viz.getViewerNodeName(shape, pin.GeometryType.VISUAL)
        frame[name].set_transform(viz.visual_data.oMg[k].homogeneous)
