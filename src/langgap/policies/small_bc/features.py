"""What `small-bc` observes, from the privileged state: the robot (proprioception) and the scene's entities.

Proprioception (14): end-effector position (3), orientation matrix (9), gripper fingers (2).
An entity is a `body/<name>` (object or fixture root body) or a `joint/<name>` (articulated fixture
joint); its features (14) are its position relative to the end effector at three scales (9: `tanh`
of it over 3 cm and 10 cm, for the centimetre precision a grasp needs, and over 30 cm, linear), its
wxyz quaternion (4) and joint position (1), zeros where they do not apply. Absolute positions are
left out: with few demonstrations a policy would latch on to them instead of relations. Entities are named, and the
name is read as words (see `text`), never as an index: the model must match names to sentences.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

PROPRIO_DIM = 14
ENTITY_DIM = 14
# Length scales (m) of the relative-position features: fine ones saturate, the coarse one is linear.
_FINE_SCALES = (0.03, 0.1)
_COARSE_SCALE = 0.3


def entity_names(privileged: Mapping) -> list[str]:
    """The entities of a scene, in a fixed (sorted) order."""
    return sorted(k for k in privileged if k.startswith(("body/", "joint/")))


def proprio(privileged: Mapping) -> np.ndarray:
    """(..., 14) proprioception from (stacked) privileged arrays."""
    eef = np.asarray(privileged["eef_pos"])
    lead = eef.shape[:-1]
    mat = np.asarray(privileged["eef_mat"]).reshape(*lead, 9)
    return np.concatenate([eef, mat, np.asarray(privileged["gripper_qpos"])], axis=-1).astype(np.float32)


def entities(privileged: Mapping, names: list[str]) -> np.ndarray:
    """(..., E, 14) entity features for `names` from (stacked) privileged arrays."""
    eef = np.asarray(privileged["eef_pos"])
    out = np.zeros((*eef.shape[:-1], len(names), ENTITY_DIM), dtype=np.float32)
    for i, name in enumerate(names):
        value = np.asarray(privileged[name])
        if name.startswith("body/"):
            relative = value[..., :3] - eef
            out[..., i, 0:3] = np.tanh(relative / _FINE_SCALES[0])
            out[..., i, 3:6] = np.tanh(relative / _FINE_SCALES[1])
            out[..., i, 6:9] = relative / _COARSE_SCALE
            out[..., i, 9:13] = value[..., 3:7]
        else:
            out[..., i, 13] = value[..., 0]
    return out


def name_words(name: str) -> str:
    """The text of an entity key: `body/akita_black_bowl_1` -> `akita_black_bowl_1`."""
    return name.split("/", 1)[1]
