"""The Panda hand's geometry around its grip site, measured from robosuite's collision meshes.

All offsets are in the grip-site frame: x is the finger-closing axis, z the approach axis (pointing
out of the fingers), y the third axis. A top-down grasp has z pointing down.
"""

from __future__ import annotations

import numpy as np

PAD_GAP_OPEN = 0.076  # distance between the finger pads, fully open
MAX_GRASP_WIDTH = 0.068  # widest material the pads close on with room to spare
FINGER_THICKNESS = 0.018  # pad face to the finger's outer face, near the tip
FINGER_DEPTH = 0.013  # half-extent of a finger along y
TIP = 0.010  # finger tips, ahead of the grip site along z
PAD_CENTRE = -0.004  # centre of the pads along z (behind the grip site)
PAD_HALF_HEIGHT = 0.008
PALM = -0.030  # the palm's lower face starts this far behind the grip site
PALM_STEP = -0.088  # the palm is slimmer below this height than above it
PALM_TOP = -0.115
PALM_HALF_LENGTH = 0.102  # along x
PALM_HALF_DEPTH_LOW = 0.021  # along y, next to the fingers
PALM_HALF_DEPTH_HIGH = 0.032
WRIST_TOP = -0.20  # the wrist (the arm's last links), a narrower block above the palm
WRIST_HALF_WIDTH = 0.05
REACH = 0.07  # how far the open fingers reach sideways from the grip site
# The arm's last links behind a hand pointing sideways (link 6 hangs below them: sliding onto a drawer's
# handle along the bar, it met a wine bottle's top 5 cm below the grip site, 20 cm behind it).
FOREARM = np.array([[-0.08, -0.06, -0.30, 0.08, 0.06, -0.10]])


def finger_boxes(width: float) -> np.ndarray:
    """The two fingers (2, 6) as boxes in the grip-site frame, pads `width` apart."""
    half = width / 2.0
    boxes = []
    for side in (-1.0, 1.0):
        inner, outer = side * half, side * (half + FINGER_THICKNESS)
        boxes.append([min(inner, outer), -FINGER_DEPTH, PALM, max(inner, outer), FINGER_DEPTH, TIP])
    return np.array(boxes)


def palm_boxes() -> np.ndarray:
    """The palm (two slabs) and the wrist above it (3, 6) as boxes in the grip-site frame."""
    return np.array(
        [
            [-PALM_HALF_LENGTH, -PALM_HALF_DEPTH_LOW, PALM_STEP, PALM_HALF_LENGTH, PALM_HALF_DEPTH_LOW, PALM],
            [-PALM_HALF_LENGTH, -PALM_HALF_DEPTH_HIGH, PALM_TOP, PALM_HALF_LENGTH, PALM_HALF_DEPTH_HIGH, PALM_STEP],
            [-WRIST_HALF_WIDTH, -WRIST_HALF_WIDTH, WRIST_TOP, WRIST_HALF_WIDTH, WRIST_HALF_WIDTH, PALM_TOP],
        ]
    )


def local_boxes(width: float) -> np.ndarray:
    """The fingers (pads `width` apart), the palm and the wrist (5, 6) as boxes in the grip-site frame."""
    return np.concatenate([finger_boxes(width), palm_boxes()])
