"""The LeRobot v3 form of a collection, written with LeRobot's own dataset API.

Schema of `lerobot/libero`: `observation.images.image` (agentview) and `observation.images.image2`
(wrist), 256x256 by default (`image_size` renders another square size) and upright (LangGap's images:
the raw render rotated 180 degrees, what LeRobot's `LiberoProcessorStep` makes of the raw render),
`observation.state` 8-D, `action` 7-D (the oracle's command, without the execution noise of
`collect --noise`), the task string (the exact catalog instruction in the collection's style). One frame per
control step (LIBERO runs at 20 Hz), labelled 10 fps as the LIBERO datasets users train on are (`FPS`). Frames are
rendered by replaying the recorded states of kept demonstrations.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from langgap.demos.compact import LEROBOT_DIR, demo_files, read_manifest
from langgap.demos.render import IMAGE_SIZE, iter_demos
from langgap.errors import DependencyNotInstalled, LangGapError

# The fps label, not a rate: every frame is one 20 Hz control step, as in LIBERO's own demonstrations, which
# openpi's conversion and the `lerobot/libero` datasets label 10 fps. LeRobot aggregates only datasets of one
# label, and a policy's action chunk is a run of consecutive frames whatever the label (LeRobot turns the
# chunk's time offsets i / fps back into frame offsets i), so it spans consecutive control steps, which is what
# LangGap executes: one action per step.
FPS = 10
# LangGap camera -> LeRobot feature (the `lerobot/libero` names).
CAMERA_FEATURES = {"agentview": "observation.images.image", "robot0_eye_in_hand": "observation.images.image2"}


def lerobot_available() -> bool:
    """Whether LeRobot's dataset API can be imported here (it lives in .venv-lerobot)."""
    return importlib.util.find_spec("lerobot") is not None


def features(image_size: int = IMAGE_SIZE) -> dict:
    """The dataset features, as in `lerobot/libero` (whose images are `IMAGE_SIZE` square)."""
    image = {"dtype": "video", "shape": (image_size, image_size, 3), "names": ["height", "width", "rgb"]}
    return {
        **{key: dict(image) for key in CAMERA_FEATURES.values()},
        "observation.state": {
            "dtype": "float32",
            "shape": (8,),
            "names": {"motors": ["x", "y", "z", "roll", "pitch", "yaw", "gripper", "gripper"]},
        },
        "action": {
            "dtype": "float32",
            "shape": (7,),
            "names": {"motors": ["x", "y", "z", "roll", "pitch", "yaw", "gripper"]},
        },
    }


def write_lerobot_dataset(
    root: str | Path,
    *,
    repo_id: str = "local/langgap_demos",
    workers: int = 1,
    image_size: int = IMAGE_SIZE,
    progress: bool = True,
) -> Path:
    """Write the collection at `root` as a LeRobot v3 dataset in `root/lerobot`, both cameras rendered
    `image_size` square; returns that path."""
    if not lerobot_available():
        raise DependencyNotInstalled("LeRobot is not installed; run this in .venv-lerobot (./setup.sh makes it)")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = Path(root)
    manifest = read_manifest(root)
    out = root / LEROBOT_DIR
    if out.exists():
        raise LangGapError(f"{out} exists already; remove it to export again")
    paths = demo_files(root)
    if not paths:
        raise LangGapError(f"{root} holds no demonstrations")
    dataset = LeRobotDataset.create(
        repo_id=repo_id, fps=FPS, features=features(image_size), root=out, robot_type="panda", use_videos=True
    )
    rendered = iter_demos(
        manifest["catalog"], paths, render=True, workers=workers, progress=progress, image_size=image_size
    )
    for demo, frames in rendered:
        actions = demo.labels.astype(np.float32)
        for t in range(demo.length):
            dataset.add_frame(
                {
                    **{feature: frames[camera][t] for camera, feature in CAMERA_FEATURES.items()},
                    "observation.state": demo.robot_states[t],
                    "action": actions[t],
                    "task": demo.instruction,
                }
            )
        dataset.save_episode()
    dataset.finalize()
    return out
