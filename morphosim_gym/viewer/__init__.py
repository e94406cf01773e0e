"""The browser viewer: `morphosim view SCENE_OR_PROMPT` (a 4D scene, edited by language) and
`morphosim view --env ID` (an episode of an env with a policy).

Images come from our renderer and are streamed to the page as JPEG frames; the page (viser,
three.js) gives the camera, the controls and the text box. The state behind the page is a
`ViewerSession`, usable and tested without a browser or web server.
"""

from .camera import camera_from_viewer, render_size, viewer_pose, viewer_view
from .session import LogEntry, Snapshot, ViewerSession, format_log, resize_keep_fov, resolve_source
from .worker import FrameWorker

__all__ = [
    "ViewerSession", "LogEntry", "Snapshot", "format_log", "resize_keep_fov", "resolve_source",
    "camera_from_viewer", "viewer_pose", "viewer_view", "render_size",
    "FrameWorker", "SceneViewer", "EnvViewer", "EnvRunner",
]

_LAZY = {"SceneViewer": "app", "EnvViewer": "env_app", "EnvRunner": "env_app"}


def __getattr__(name: str):
    if name in _LAZY:                   # the web app imports viser: only when asked for
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
