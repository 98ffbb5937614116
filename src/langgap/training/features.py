"""What `small-bc` observes, from the privileged state: the robot (proprioception) and the scene's entities.

Proprioception (14): end-effector position (3), orientation matrix (9), gripper fingers (2).
An entity is a `body/<name>` (object or fixture root body) or a `joint/<name>` (articulated fixture
joint); its features (11) are position relative to the end effector (3), position (3), wxyz
quaternion (4) and joint position (1), zeros where they do not apply. Entities are named, and the
name is read as words (see `text`), never as an index: the model must match names to sentences.
"""

from __future__ import annotations

import numpy as np

PROPRIO_DIM = 14
ENTITY_DIM = 11


def entity_names(privileged: dict) -> list[str]:
    """The entities of a scene, in a fixed (sorted) order."""
    return sorted(k for k in privileged if k.startswith(("body/", "joint/")))


def proprio(privileged: dict) -> np.ndarray:
    """(..., 14) proprioception from (stacked) privileged arrays."""
    eef = np.asarray(privileged["eef_pos"])
    lead = eef.shape[:-1]
    mat = np.asarray(privileged["eef_mat"]).reshape(*lead, 9)
    return np.concatenate([eef, mat, np.asarray(privileged["gripper_qpos"])], axis=-1).astype(np.float32)


def entities(privileged: dict, names: list[str]) -> np.ndarray:
    """(..., E, 11) entity features for `names` from (stacked) privileged arrays."""
    eef = np.asarray(privileged["eef_pos"])
    out = np.zeros((*eef.shape[:-1], len(names), ENTITY_DIM), dtype=np.float32)
    for i, name in enumerate(names):
        value = np.asarray(privileged[name])
        if name.startswith("body/"):
            out[..., i, 0:3] = value[..., :3] - eef
            out[..., i, 3:10] = value[..., :7]
        else:
            out[..., i, 10] = value[..., 0]
    return out


def name_words(name: str) -> str:
    """The text of an entity key: `body/akita_black_bowl_1` -> `akita_black_bowl_1`."""
    return name.split("/", 1)[1]
