"""The browser viewer: :mod:`~toolkit.viz.viewer` (:class:`Viewer`, on meshcat, bound to
127.0.0.1 only), :mod:`~toolkit.viz.visuals` (a robot's visual shapes, meshes found or
replaced by bones) and :mod:`~toolkit.viz.server` (the meshcat server process)."""

from .viewer import MissingMeshWarning, Viewer, ViewerUnavailable, meshcat_available
from .visuals import Visuals, camera_position, frame_box, scene_box, visual_model

__all__ = [
    "MissingMeshWarning",
    "Viewer",
    "ViewerUnavailable",
    "Visuals",
    "camera_position",
    "frame_box",
    "meshcat_available",
    "scene_box",
    "visual_model",
]
