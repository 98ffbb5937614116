"""LeRobot's LIBERO conventions (lerobot 0.6: `envs/libero.py`, `processor/env_processor.py`), in one place.

LeRobot's LIBERO env returns the raw render (upside down) under `pixels/image` (agentview) and
`pixels/image2` (wrist) plus a nested `robot_state`; its `LiberoProcessorStep` then flips both image
axes and builds the 8-D `observation.state` (eef position, axis-angle, gripper joints). A policy
therefore sees upright images under `observation.images.image` / `image2` — exactly `TaskEnv`'s
images — and the same 8-D state as `TaskEnv`.

Importing this module needs LeRobot (and torch); core LangGap never imports it.
"""

from __future__ import annotations

import numpy as np

from langgap.errors import DependencyNotInstalled

# LangGap camera -> key under LeRobot's `pixels` / `observation.images.`.
CAMERA_KEYS = {"agentview": "image", "robot0_eye_in_hand": "image2"}
# LeRobot's LIBERO camera names (`--env.camera_name`) -> LangGap cameras.
LIBERO_CAMERA_NAMES = {"agentview_image": "agentview", "robot0_eye_in_hand_image": "robot0_eye_in_hand"}
IMAGE_PREFIX = "observation.images."
STATE_KEY = "observation.state"
ACTION_KEY = "action"
FPS = 20  # robosuite's control frequency; LeRobot's LIBERO env config uses the same

try:
    import lerobot  # noqa: F401
    import torch
except ImportError as exc:  # pragma: no cover - depends on the environment
    raise DependencyNotInstalled(
        f"LeRobot is not installed ({exc.name}); run this in .venv-lerobot (./setup.sh makes it)"
    ) from None


def robot_state(robosuite_obs: dict, controller_ori_mat: np.ndarray) -> dict:
    """LeRobot's nested `robot_state` from a robosuite observation dict."""
    return {
        "eef": {
            "pos": np.asarray(robosuite_obs["robot0_eef_pos"], dtype=np.float64),
            "quat": np.asarray(robosuite_obs["robot0_eef_quat"], dtype=np.float64),
            "mat": np.asarray(controller_ori_mat, dtype=np.float64).reshape(3, 3),
        },
        "gripper": {
            "qpos": np.asarray(robosuite_obs["robot0_gripper_qpos"], dtype=np.float64),
            "qvel": np.asarray(robosuite_obs["robot0_gripper_qvel"], dtype=np.float64),
        },
        "joints": {
            "pos": np.asarray(robosuite_obs["robot0_joint_pos"], dtype=np.float64),
            "vel": np.asarray(robosuite_obs["robot0_joint_vel"], dtype=np.float64),
        },
    }


def image_tensor(image: np.ndarray) -> torch.Tensor:
    """An (H, W, 3) uint8 image as LeRobot's (1, 3, H, W) float32 in [0, 1] (its `preprocess_observation`)."""
    return torch.from_numpy(np.ascontiguousarray(image)).permute(2, 0, 1).unsqueeze(0).float() / 255.0
