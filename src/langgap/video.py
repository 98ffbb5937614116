"""Writing episode videos with OpenCV, which the LIBERO stack already installs.

Clips are WebM (VP8): OpenCV's wheels encode it without extra libraries and every browser plays it,
whereas their mp4 writer only has MPEG-4 Part 2, which browsers do not play.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

CONTROL_HZ = 20
# Clips show every other control step: a render costs ~80 ms whatever its size, so filming at 10 fps
# halves what a clip costs, and is still smooth to watch.
FRAME_EVERY = 2
VIDEO_FPS = CONTROL_HZ // FRAME_EVERY
VIDEO_SUFFIX = ".webm"


@contextlib.contextmanager
def _stderr_silenced() -> Iterator[None]:
    """Send file descriptor 2 (where C libraries print) to /dev/null for the duration."""
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def write_video(path: str | Path, frames: list[np.ndarray], fps: int = VIDEO_FPS) -> Path:
    """Write RGB uint8 frames (H, W, 3) to a WebM file (`fps` frames per second); returns the path."""
    import cv2

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    height, width = frames[0].shape[:2]
    with _stderr_silenced():  # OpenCV's FFmpeg prints a harmless line about the WebM tag on every open
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"VP80"), fps, (width, height))
    if not writer.isOpened():
        raise RuntimeError(f"OpenCV cannot write a WebM video to {path}")
    try:
        for frame in frames:
            writer.write(cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    return path
