"""`clip_from_video`: a `GeneratedClip` of frames and estimated cameras from a video or a folder of frames.

The clip carries what a real video gives: frames (`video.read_frames`, within the budget), one
camera per frame (`camera_motion.video_cameras`: still, or a pan estimated from the frames), the
frame rate and the user's optional prompt. It carries no depth, masks or tracks: reconstruction
estimates them (`morphosim_gym.priors`), labelling the moving regions with the prompt's nouns.
`info["backend"] == "video"`; `info["video"]` says how the file was read (shot, stride, size) and
`info["camera"]` how the cameras were found.
"""

from __future__ import annotations

from pathlib import Path

from .camera_motion import video_cameras
from .clip import GeneratedClip
from .video import read_frames

__all__ = ["clip_from_video"]


def clip_from_video(path: str | Path, fov_deg: float = 50.0, prompt: str | None = None, max_frames: int = 49,
                    size: int = 160, fps: float | None = None, camera: str = "auto", camera_height: float = 1.6,
                    pitch_deg: float = 20.0, shot: int | str = "longest",
                    start: int = 0) -> GeneratedClip:
    """See `GeneratedClip.from_video`."""
    if prompt is not None and (not isinstance(prompt, str) or not prompt.strip()):
        raise ValueError(f"Expected prompt as a non-empty string or None, found {prompt!r}")
    video = read_frames(path, max_frames=max_frames, size=size, fps=fps, shot=shot, start=start)
    try:
        cameras, cam_info = video_cameras(video.frames, fov_deg, camera, camera_height, pitch_deg)
    except ValueError as exc:
        raise ValueError(f"{exc} (video {path})") from exc
    info = {"backend": "video", "video": video.info, "camera": cam_info}
    return GeneratedClip(video.frames, tuple(cameras), video.fps, prompt=prompt or "", info=info)
