"""From a desired end-effector pose to one OSC_POSE delta action.

LIBERO's controller reads an action as a pose change of at most 5 cm and 0.5 rad (world frame)
per 20 Hz step, so a proportional command toward the target, scaled by those maxima and clipped,
is a well-damped servo. Positions saturate as a vector so the end effector moves in a straight line.
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
    """One action moving the end effector toward (target_pos, target_mat); `speed` caps the step (0..1]."""
    move = (np.asarray(target_pos) - eef_pos) / MAX_TRANSLATION
    norm = float(np.linalg.norm(move))
    if norm > speed:
        move *= speed / norm
    turn = mat_to_axis_angle(np.asarray(target_mat) @ eef_mat.T) / MAX_ROTATION
    turn_norm = float(np.linalg.norm(turn))
    if turn_norm > 1.0:
        turn /= turn_norm
    return np.concatenate([move, turn, [grip]])
