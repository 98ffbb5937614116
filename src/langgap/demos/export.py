"""The LeRobot v3 form of a collection, written with LeRobot's own dataset API.

Schema of `lerobot/libero`: `observation.images.image` (agentview) and `observation.images.image2`
(wrist), 256x256 upright (LangGap's images: the raw render rotated 180 degrees, what LeRobot's
`LiberoProcessorStep` makes of the raw render), `observation.state` 8-D, `action` 7-D (the oracle's
command, without the execution noise of `collect --noise`), the task string (the exact catalog
instruction in the collection's style), fps 20 (the control rate: one frame per action). Frames are
rendered by replaying the recorded states of kept demonstrations.
"""

from __future__ import annotations

import importlib.util
import multiprocessing
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from langgap.demos.compact import LEROBOT_DIR, demo_files, load_demo, read_manifest
from langgap.demos.record import replay_states
from langgap.errors import DependencyNotInstalled, LangGapError

FPS = 20
IMAGE_SIZE = 256
# LangGap camera -> LeRobot feature (the `lerobot/libero` names).
CAMERA_FEATURES = {"agentview": "observation.images.image", "robot0_eye_in_hand": "observation.images.image2"}


def lerobot_available() -> bool:
    """Whether LeRobot's dataset API can be imported here (it lives in .venv-lerobot)."""
    return importlib.util.find_spec("lerobot") is not None


def features() -> dict:
    """The dataset features, as in `lerobot/libero`."""
    image = {"dtype": "video", "shape": (IMAGE_SIZE, IMAGE_SIZE, 3), "names": ["height", "width", "rgb"]}
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


_ENVS: dict = {}


def render_demo(catalog: str, path: str) -> tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Replay one stored demonstration and render both cameras at every step (runs in a worker)."""
    from langgap.catalog.catalog import load_catalog
    from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

    demo = load_demo(Path(path))
    env = _ENVS.get(demo.task_id)
    if env is None:
        for old in _ENVS.values():
            old.close()
        _ENVS.clear()
        env = _ENVS[demo.task_id] = TaskEnv(
            load_catalog(catalog).get(demo.task_id), EnvOptions(cameras=CAMERAS, image_size=IMAGE_SIZE)
        )
    frames = list(replay_states(env, demo, lambda e: [e.render(c) for c in CAMERAS]))
    agentview = np.stack([f[0] for f in frames])
    wrist = np.stack([f[1] for f in frames])
    return demo.instruction, agentview, wrist, demo.robot_states, demo.labels.astype(np.float32)


def _render_star(args):
    return render_demo(*args)


def _rendered(catalog: str, paths: list[Path], workers: int) -> Iterator[tuple]:
    jobs = [(catalog, str(p)) for p in paths]
    if workers <= 0:
        yield from map(_render_star, jobs)
        return
    with multiprocessing.get_context("spawn").Pool(min(workers, len(jobs))) as pool:
        # Ordered: the dataset's episode order is the collection's, whatever the number of workers.
        yield from pool.imap(_render_star, jobs)


def write_lerobot_dataset(
    root: str | Path, *, repo_id: str = "local/langgap_demos", workers: int = 1, progress: bool = True
) -> Path:
    """Write the collection at `root` as a LeRobot v3 dataset in `root/lerobot`; returns that path."""
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
        repo_id=repo_id, fps=FPS, features=features(), root=out, robot_type="panda", use_videos=True
    )
    rendered = _rendered(manifest["catalog"], paths, workers)
    if progress:
        from tqdm import tqdm

        rendered = tqdm(rendered, total=len(paths), unit="demo", desc="render")
    for instruction, agentview, wrist, states, actions in rendered:
        for t in range(len(actions)):
            dataset.add_frame(
                {
                    CAMERA_FEATURES["agentview"]: agentview[t],
                    CAMERA_FEATURES["robot0_eye_in_hand"]: wrist[t],
                    "observation.state": states[t],
                    "action": actions[t],
                    "task": instruction,
                }
            )
        dataset.save_episode()
    dataset.finalize()
    return out
