"""Demonstrations with camera images, read from a collection's HDF5 form (`langgap export-hdf5 DIR --images`),
for training a policy that sees pixels (`small-vla`)."""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap.demos.compact import HDF5_DIR
from langgap.demos.hdf5 import IMAGE_KEYS, require_h5py
from langgap.errors import LangGapError


@dataclass
class ImageDemo:
    """One demonstration as a pixel policy is trained on it: row t is what was seen before action t."""

    task_id: str
    instruction: str
    images: np.ndarray  # (T, 2, S, S, 3) uint8: agentview, then the wrist camera (`langgap.sim.env.CAMERAS`)
    states: np.ndarray  # (T, 8) float32: LangGap's 8-D state
    labels: np.ndarray  # (T, 7) the demonstrator's clean commands: the training targets

    @property
    def image_size(self) -> int:
        return self.images.shape[2]


def pack_images(demos: list[ImageDemo]) -> np.ndarray:
    """Every demonstration's images, in order, as one (frames, 2, S, S, 3) array; each demonstration's `images`
    becomes its view into that array. Training samples across demonstrations, so it needs one array; re-pointing
    each demonstration as it is copied holds the frames in memory once, not twice (peak: the array plus one
    demonstration's images)."""
    packed = np.empty((sum(len(d.images) for d in demos), *demos[0].images.shape[1:]), np.uint8)
    start = 0
    for demo in demos:
        end = start + len(demo.images)
        packed[start:end] = demo.images
        demo.images = packed[start:end]
        start = end
    return packed


def _missing_images(root: Path) -> LangGapError:
    return LangGapError(
        f"{root} has no demonstrations with images: run `langgap export-hdf5 {root} --images --image-size N` first"
    )


def load_image_demos(roots: Iterable[str | Path], tasks: Iterable[str] | None = None) -> list[ImageDemo]:
    """The demonstrations (with images) of every collection in `roots`, from its HDF5 form (`<root>/hdf5`), in
    file and demonstration order; only `tasks`' files are read when given. Every image has one size."""
    h5py = require_h5py()
    wanted = None if tasks is None else set(tasks)
    demos: list[ImageDemo] = []
    for root in map(Path, roots):
        paths = sorted((root / HDF5_DIR).glob("*_demo.hdf5"))
        if not paths:
            raise _missing_images(root)
        for path in paths:
            with h5py.File(path, "r") as f:
                data = f["data"]
                task_id = str(data.attrs["langgap_task_id"])
                if wanted is not None and task_id not in wanted:
                    continue
                instruction = json.loads(data.attrs["problem_info"])["language_instruction"]
                for name in sorted(data, key=lambda n: int(n.split("_")[1])):
                    group = data[name]
                    if any(key not in group["obs"] for key in IMAGE_KEYS.values()):
                        raise _missing_images(root)
                    images = np.stack([group["obs"][key][()] for key in IMAGE_KEYS.values()], axis=1)
                    states = group["robot_states"][()].astype(np.float32)
                    demos.append(ImageDemo(task_id, instruction, images, states, group["labels"][()]))
    sizes = {demo.image_size for demo in demos}
    if len(sizes) > 1:
        raise LangGapError(f"the collections' images differ in size ({sorted(sizes)}): export them at one size")
    return demos
