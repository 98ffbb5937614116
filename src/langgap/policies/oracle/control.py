"""From a desired end-effector pose to one OSC_POSE delta action.

LIBERO's controller reads an action as a pose change of at most 5 cm and 0.5 rad per world axis
(it clips each component on its own) per 20 Hz step, so a proportional command toward the target,
scaled by those maxima and clipped, is a well-damped servo. A command beyond the limits is scaled
down as a whole until its largest component fits: the end effector keeps a straight line, and a
diagonal motion uses the full range of every axis (up to 1.7 times faster than a Euclidean cap).
Turns keep the Euclidean cap (0.5 rad per step about any axis): turning at the full rate about every
axis at once shook held bowls loose (goal/s3's bowl-in-drawer lost init states 3 and 11 of 0–11).
"""

from __future__ import annotations

import numpy as np

from langgap.policies.oracle.geometry import mat_to_axis_angle

MAX_TRANSLATION = 0.05  # metres per unit action (robosuite OSC_POSE output_max)
MAX_ROTATION = 0.5  # radians per unit action
OPEN = -1.0
CLOSE = 1.0


def servo(
    eef_pos: np.ndarray,
    eef_mat: np.ndarray,
    target_pos: np.ndarray,
    target_mat: np.ndarray,
    grip: float,
    speed: float = 1.0,
) -> np.ndarray:
    """One action moving the end effector toward (target_pos, target_mat); `speed` (0..1] caps each
    position component of the step."""
    move = _saturate((np.asarray(target_pos) - eef_pos) / MAX_TRANSLATION, speed)
    turn = mat_to_axis_angle(np.asarray(target_mat) @ eef_mat.T) / MAX_ROTATION
    turn_norm = float(np.linalg.norm(turn))
    return np.concatenate([move, turn / max(turn_norm, 1.0), [grip]])


def _saturate(command: np.ndarray, limit: float) -> np.ndarray:
    """`command` scaled down, keeping its direction, until no component exceeds `limit`."""
    largest = float(np.abs(command).max())
    return command * (limit / largest) if largest > limit else command
