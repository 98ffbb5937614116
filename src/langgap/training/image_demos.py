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


def _missing_images(root: Path) -> LangGapError:
    return LangGapError(
        f"{root} has no demonstrations with images: run `langgap export-hdf5 {root} --images --image-size N` first"
    )


@dataclass
class ImageDemos:
    """Demonstrations with images and their frames in one array, the array training samples from; each
    demonstration's `images` is its view into it, so every frame is in memory once."""

    demos: list[ImageDemo]
    frames: np.ndarray  # (all frames, 2, S, S, 3) uint8, the demonstrations' images in order


def load_image_demos(roots: Iterable[str | Path], tasks: Iterable[str] | None = None) -> ImageDemos:
    """The demonstrations (with images) of every collection in `roots`, from its HDF5 form (`<root>/hdf5`), in
    file and demonstration order; only `tasks`' files are read when given. Every image has one size.

    A first pass reads the files' shapes, a second copies each camera's images into their place in one array:
    building it from per-demonstration arrays would hold the frames twice while it is built, and the allocator
    keeps much of that memory after they are freed."""
    h5py = require_h5py()
    wanted = None if tasks is None else set(tasks)
    found: list[tuple[Path, list[tuple[str, int]]]] = []  # each file to read, with its demonstrations' lengths
    sizes: set[int] = set()
    for root in map(Path, roots):
        paths = sorted((root / HDF5_DIR).glob("*_demo.hdf5"))
        if not paths:
            raise _missing_images(root)
        for path in paths:
            with h5py.File(path, "r") as f:
                data = f["data"]
                if wanted is not None and str(data.attrs["langgap_task_id"]) not in wanted:
                    continue
                lengths = []
                for name in sorted(data, key=lambda n: int(n.split("_")[1])):
                    obs = data[name]["obs"]
                    if any(key not in obs for key in IMAGE_KEYS.values()):
                        raise _missing_images(root)
                    sizes.update(obs[key].shape[1] for key in IMAGE_KEYS.values())
                    lengths.append((name, len(data[name]["labels"])))
                found.append((path, lengths))
    if len(sizes) > 1:
        raise LangGapError(f"the collections' images differ in size ({sorted(sizes)}): export them at one size")
    total = sum(length for _, lengths in found for _, length in lengths)
    size = sizes.pop() if sizes else 0
    frames = np.empty((total, len(IMAGE_KEYS), size, size, 3), np.uint8)
    demos: list[ImageDemo] = []
    start = 0
    for path, lengths in found:
        with h5py.File(path, "r") as f:
            data = f["data"]
            task_id = str(data.attrs["langgap_task_id"])
            instruction = json.loads(data.attrs["problem_info"])["language_instruction"]
            for name, length in lengths:
                group, images = data[name], frames[start : start + length]
                for camera, key in enumerate(IMAGE_KEYS.values()):
                    # Read whole, then copied: HDF5 scattering into the strided slice directly is ~10x slower.
                    images[:, camera] = group["obs"][key][()]
                states = group["robot_states"][()].astype(np.float32)
                demos.append(ImageDemo(task_id, instruction, images, states, group["labels"][()]))
                start += length
    return ImageDemos(demos, frames)
