"""Browser viewer on meshcat (optional extra: ``pip install manipulator-toolkit[viz]``).

:class:`Viewer` starts a meshcat server bound to 127.0.0.1 only (``toolkit.viz.server``),
draws a :class:`~toolkit.robot.Robot` from its URDF visuals through Pinocchio's
``MeshcatVisualizer``, and adds target markers, tool paths, joint-trajectory
animation and a translucent "ghost" (e.g. the commanded pose beside the
backlash-affected one), a scene's objects, the links in collision in red and the
collision shapes (:meth:`Viewer.show_collisions`, :meth:`Viewer.show_collision_geometry`).
Without meshcat installed, constructing a viewer raises :class:`ViewerUnavailable` with
the install command; nothing else in the toolkit needs meshcat.
"""

from __future__ import annotations

import contextlib
import io
import os
import queue
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..collision import FLOOR, Scene
from ..common import cache as _cache
from ..common import validate as _validate
from ..errors import (
    ConfigurationError,
    InvalidParameterError,
    ToolkitError,
    UnsupportedModelError,
)
from ..robot import Robot, checker_for
from .answers import AnswerViews
from .visuals import MissingMeshWarning, Visuals, camera_position, scene_box, visual_model

__all__ = ["MissingMeshWarning", "Viewer", "ViewerUnavailable", "meshcat_available"]


class ViewerUnavailable(ToolkitError, RuntimeError):
    """meshcat is not installed, or its server could not start."""


def meshcat_available() -> bool:
    """True if the optional meshcat package can be imported."""
    try:
        import meshcat  # noqa: F401
    except ImportError:
        return False
    return True


def _start_server(timeout: float = 20.0) -> tuple[subprocess.Popen[str], str, str]:
    """Start ``toolkit.viz.server`` watching this process; (process, zmq, web URLs)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "toolkit.viz.server", "--parent", str(os.getpid())],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:  # a thread, so that a silent server cannot block us past timeout
        for line in proc.stdout or ():
            lines.put(line)
        lines.put("")

    threading.Thread(target=read, daemon=True).start()
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    while len(urls) < 2 and time.monotonic() < deadline:
        try:
            line = lines.get(timeout=0.2)
        except queue.Empty:
            continue
        if not line:  # the server exited
            break
        key, _, value = line.strip().partition("=")
        if key in ("zmq_url", "web_url"):
            urls[key] = value
    if len(urls) < 2:
        proc.kill()
        raise ViewerUnavailable("the meshcat server did not start")
    return proc, urls["zmq_url"], urls["web_url"]


def _probe(zmq_url: str, timeout: float) -> None:
    """Refuse a ZeroMQ URL that nothing answers on within ``timeout`` seconds."""
    parts = urlsplit(zmq_url)
    if parts.scheme != "tcp" or not parts.hostname or not parts.port:
        raise InvalidParameterError(f"zmq_url must look like tcp://HOST:PORT, got {zmq_url!r}")
    try:
        socket.create_connection((parts.hostname, parts.port), timeout=timeout).close()
    except OSError as exc:
        raise ViewerUnavailable(
            f"no meshcat server answers at {zmq_url} within {timeout:g} s: {exc}"
        ) from exc


def _drawable(obj: Any, scene: Scene) -> Any:
    """A copy of a scene object's geometry that meshcat can draw: a floor's half-space as
    a thin 4 m slab under its plane, a mesh with its file and scale."""
    import coal

    drawn = obj.copy()
    item = next(o for o in scene if o.name == obj.name)
    if item.kind == "floor":
        drawn.geometry = coal.Box(4.0, 4.0, 0.002)
        shift = pin.SE3(np.eye(3), np.array([0.0, 0.0, FLOOR[2] / 2 - 0.001]))  # its top
        drawn.placement = obj.placement * shift
    elif item.kind == "mesh":
        drawn.meshPath = str(item.path)
        drawn.meshScale = np.array(item.size, dtype=float)
    return drawn


def _rgba(color: Sequence[float]) -> np.ndarray:
    arr = np.asarray(color, dtype=float)
    if arr.shape == (3,):
        arr = np.append(arr, 1.0)
    if arr.shape != (4,) or np.any(arr < 0) or np.any(arr > 1):
        raise InvalidParameterError(f"color must be 3 or 4 numbers in [0, 1], got {color!r}")
    return arr


class Viewer(AnswerViews):
    """A meshcat scene showing one robot (plus optional ghosts, markers and paths).

    Args:
        robot: the robot to draw (its ``urdf_path`` supplies the visual shapes).
        zmq_url: connect to a running meshcat server (``tcp://HOST:PORT``) instead of
            starting one; refused with :class:`ViewerUnavailable` when nothing answers
            there within ``timeout`` seconds.
        open: open the scene in the default web browser.
        timeout: seconds to wait for the server at ``zmq_url`` (> 0).
        q: the first configuration shown, on which the camera is framed (default: neutral).

    Meshes (STL, DAE, OBJ) are drawn from the robot's description; one that is missing or
    in another format is drawn as a primitive shape, with a
    :class:`~toolkit.visuals.MissingMeshWarning` naming the file (``missing_meshes``).

    A viewer is a context manager; ``close()`` (or leaving the ``with`` block) stops the
    server it started, and the server also ends by itself when this process ends.

    Attributes:
        url: the address of the scene (http://127.0.0.1:PORT/static/).
    """

    def __init__(
        self,
        robot: Robot,
        *,
        zmq_url: str | None = None,
        open: bool = False,
        timeout: float = 5.0,
        q: ArrayLike | None = None,
    ) -> None:
        timeout = _validate.number(timeout, "timeout", lower=0.0, strict=True)
        if not meshcat_available():
            raise ViewerUnavailable(
                "the viewer needs meshcat: pip install 'manipulator-toolkit[viz]' "
                "(everything else works without it)"
            )
        if not isinstance(robot, Robot):
            raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r}")
        if robot.urdf_path is None:
            raise UnsupportedModelError(
                f"{robot.name}: the viewer needs a robot loaded from a URDF file"
            )
        import meshcat

        self.robot = robot
        self._proc: subprocess.Popen[str] | None = None
        if zmq_url is None:
            self._proc, zmq_url, _ = _start_server()
        else:
            _probe(zmq_url, timeout)
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL: we say it
            self.meshcat = meshcat.Visualizer(zmq_url=zmq_url)
        self.url: str = self.meshcat.url()
        first = robot.joints.neutral() if q is None else robot.joints.check(q)
        self._visuals: Visuals = visual_model(robot)  # warns about meshes it leaves out
        self._ghosts: dict[str, Any] = {}
        self._extra: dict[str, Any] = {}  # the scene's objects, the collision shapes
        self._roots: dict[str, str] = {}  # a node's path since it was last deleted
        self._drops = 0
        self._q = first
        self.frame(first)  # before the meshes: the browser gets the camera first
        self._main = self._load("robot", None)
        self.show(first)
        if open:
            self.meshcat.open()

    def _load(
        self, name: str, color: np.ndarray | None, geometry: pin.GeometryModel | None = None
    ) -> Any:
        """The robot's shapes (or ``geometry``) drawn as node ``name``, at its current path
        (a fresh one after a ``_drop``)."""
        from pinocchio.visualize import MeshcatVisualizer

        shapes = self._visuals.geometry if geometry is None else geometry
        viz = MeshcatVisualizer(self.robot.model, pin.GeometryModel(), shapes)
        viz.initViewer(viewer=self.meshcat)
        root = self._roots.get(name, name)
        if color is None:
            viz.loadViewerModel(rootNodeName=root)
        else:
            viz.loadViewerModel(rootNodeName=root, visual_color=list(color))
        return viz

    @property
    def missing_meshes(self) -> dict[str, str]:
        """The meshes drawn as primitive shapes instead, with the reason for each."""
        return dict(self._visuals.missing)

    def frame(self, q: ArrayLike | None = None) -> None:
        """Place the camera so that the robot's whole bounding box at q (default: neutral),
        meshes included, is in view (tall arms included)."""
        low, high = scene_box(self.robot, self._visuals, q)  # checks q
        eye = camera_position(low, high)
        # the camera node has three.js axes (y up): base-frame (x, y, z) is (x, z, -y) there
        position = [float(eye[0]), float(eye[2]), float(-eye[1])]
        self.meshcat["/Cameras/default/rotated/<object>"].set_property("position", position)

    # ------------------------------------------------------------------ drawing
    def show(self, q: ArrayLike) -> None:
        """Put the robot at configuration q (its collision shapes and attached objects
        too, when drawn)."""
        self._q = self.robot.joints.check(q)
        self._main.display(self._q)
        for extra in self._extra.values():
            extra.display(self._q)

    def show_scene(self, scene: Scene, color: Sequence[float] = (0.55, 0.6, 0.7, 0.35)) -> None:
        """Draw the objects of ``scene`` (a floor as a 4 m square slab; attached objects
        move with their link)."""
        if not isinstance(scene, Scene):
            raise InvalidParameterError(f"scene must be a toolkit Scene, got {scene!r:.80}")
        checker = checker_for(self.robot, scene)
        shapes = pin.GeometryModel()
        for obj in checker.parts.objects[checker.robot_count :]:
            shapes.addGeometryObject(_drawable(obj, scene))
        self._draw_extra("scene", shapes, _rgba(color))

    def show_collision_geometry(self, on: bool = True) -> None:
        """Show the robot's collision shapes (translucent green) in place of its visual
        ones; ``on=False`` switches back."""
        on = _validate.flag(on, "on")
        if on and "collision" not in self._extra:
            self._draw_extra("collision", self._collision_shapes(), _rgba((0.2, 0.75, 0.3, 0.6)))
        if "collision" in self._extra:
            self._node("collision").set_property("visible", on)
        self.meshcat["robot"].set_property("visible", not on)

    def _collision_shapes(self) -> pin.GeometryModel:
        """The robot's collision shapes (those the checker tests), as one geometry model."""
        checker = checker_for(self.robot, None)
        shapes = pin.GeometryModel()
        for k in range(checker.robot_count):
            shapes.addGeometryObject(checker.geom.geometryObjects[k].copy())
        return shapes

    def show_collisions(
        self, q: ArrayLike, scene: Scene | None = None, color: Sequence[float] = (0.9, 0.1, 0.1)
    ) -> list[tuple[str, str]]:
        """Put the robot at q, colour the links in collision (with each other or with an
        object of ``scene``, which is drawn) red, the others as loaded; the colliding
        pairs, by link or object name."""
        pairs = self.robot.collision_checker(scene).collisions(q)
        if scene is not None:
            self.show_scene(scene)
        self.show(q)
        hit = {name for pair in pairs for name in pair}
        red = [*(float(c) for c in _rgba(color)[:3]), 1.0]
        for obj in self._visuals.geometry.geometryObjects:
            link = self.robot.model.frames[int(obj.parentFrame)].name
            node = self._main.getViewerNodeName(obj, pin.GeometryType.VISUAL)
            rgba = red if link in hit else [float(c) for c in obj.meshColor]
            self.meshcat[node].set_property("color", rgba)
        return pairs

    def _node(self, name: str) -> Any:
        """The meshcat node drawn as ``name`` ("scene", "collision", "markers", "paths", a
        ghost's name): its path changes each time it is deleted (``_drop``)."""
        return self.meshcat[self._roots.get(name, name)]

    def _drop(self, name: str) -> None:
        """Delete node ``name``; its next drawing goes to a fresh path, because meshcat's
        server does not replay a path deleted and drawn again to a browser that connects
        later (the page would show nothing there)."""
        self._node(name).delete()
        self._drops += 1
        self._roots[name] = f"{name}_{self._drops}"

    def _draw_extra(self, name: str, shapes: pin.GeometryModel, color: np.ndarray) -> None:
        if name in self._extra:
            self._drop(name)
        self._extra[name] = self._load(name, color, shapes)
        self._extra[name].display(self._q)

    def ghost(
        self, q: ArrayLike, name: str = "ghost", color: Sequence[float] = (0.3, 0.6, 1.0, 0.35)
    ):
        """Draw a translucent copy of the robot at q (e.g. the commanded pose)."""
        if name not in self._ghosts:
            self._ghosts[name] = self._load(name, _rgba(color))
        self._ghosts[name].display(self.robot.joints.check(q))

    def show_backlash(self, layer: Any, q_cmd: ArrayLike) -> None:
        """The backlash-affected pose solid, the commanded pose as a ghost beside it."""
        q = self.robot.joints.check(q_cmd)
        self.show(layer.output_angles(q))
        self.ghost(q, name="commanded")

    def marker(
        self,
        position: Sequence[float],
        name: str = "target",
        radius: float = 0.015,
        color: Sequence[float] = (0.9, 0.1, 0.1, 1.0),
    ) -> None:
        """A sphere at a position of the base frame (a target, say)."""
        import meshcat.geometry as g

        rgba = _rgba(color)
        hexcolor = int(rgba[0] * 255) << 16 | int(rgba[1] * 255) << 8 | int(rgba[2] * 255)
        node = self._node("markers")[name]
        node.set_object(
            g.Sphere(radius),
            g.MeshLambertMaterial(
                color=hexcolor, opacity=float(rgba[3]), transparent=bool(rgba[3] < 1)
            ),
        )
        T = np.eye(4)
        T[:3, 3] = np.asarray(position, dtype=float)
        node.set_transform(T)

    def path(
        self, points: object, name: str = "path", color: Sequence[float] = (0.1, 0.6, 0.1)
    ) -> None:
        """A polyline through points (N, 3) of the base frame (a tool path, say)."""
        import meshcat.geometry as g

        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 2:
            raise ConfigurationError(f"path points must have shape (N >= 2, 3), got {pts.shape}")
        rgba = _rgba(color)
        colors = np.repeat(rgba[:3, None], len(pts), axis=1)
        self._node("paths")[name].set_object(
            g.Line(g.PointsGeometry(pts.T, color=colors), g.LineBasicMaterial(vertexColors=True))
        )

    def animate(self, trajectory: ArrayLike, dt: float = 0.02) -> None:
        """Play a joint trajectory (T, nq) in the browser, one frame every ``dt`` seconds."""
        qs = self.robot.joints.check(trajectory, batch=True)
        if qs.ndim != 2:
            raise ConfigurationError("trajectory must have shape (T, nq)")
        for q in qs:
            self._main.display(q)
            time.sleep(dt)

    def clear(self) -> None:
        """Remove markers, paths and ghosts."""
        for key in ("markers", "paths", *self._ghosts):
            self._drop(key)
        self._ghosts.clear()

    def save_html(self, path: str | os.PathLike[str]) -> Path:
        """The scene as it is now in one self-contained HTML file (meshes included) that
        opens in any browser without the server, e.g. to share or to look at later; written
        atomically (a file already there is replaced; a folder is refused). Returns the
        path."""
        out = Path(os.fspath(path))
        if out.is_dir():
            raise InvalidParameterError(f"save_html: {out} is a folder; give a file name")
        if not out.parent.is_dir():
            raise InvalidParameterError(f"save_html: no folder {out.parent} to write into")
        _cache.write_atomic(out, self.meshcat.static_html().encode("utf-8"))
        return out

    def cell(self, height: int = 400) -> Any:
        """The live scene inline in a Jupyter cell (make it the cell's last expression);
        the viewer stays open, so later ``show``/``marker`` calls update it."""
        height = int(_validate.number(height, "height", lower=50))
        return self.meshcat.jupyter_cell(height=height)

    def close(self) -> None:
        """Stop the meshcat server this viewer started."""
        if self._proc is not None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
            self._proc = None

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass
