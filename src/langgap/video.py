"""Writing episode videos (mp4) with OpenCV, which the LIBERO stack already installs."""

from __future__ import annotations

from pathlib import Path

import numpy as np

CONTROL_HZ = 20


def write_video(path: str | Path, frames: list[np.ndarray], fps: int = CONTROL_HZ) -> Path:
    """Write RGB uint8 frames (H, W, 3) to an mp4 file at the control rate; returns the path."""
    import cv2

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
    try:
        for frame in frames:
            writer.write(cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    return path
