"""Stored demonstrations read back in collection order, with camera frames rendered by replaying their states.

Shared by the exports (LeRobot, HDF5): a demonstration's frames exist nowhere but here, so every form of
the collection shows the same pixels. Frames are LangGap's images (`TaskEnv.render`): `IMAGE_SIZE` (or a policy's size)
square, upright, i.e. the raw MuJoCo render rotated 180 degrees (`raw[::-1, ::-1]`) — the orientation of
`lerobot/libero` and openpi's LIBERO data (LIBERO's own HDF5 files hold the raw, upside-down render).

Rendering a demonstration is a work item (`RenderDemo`) for the engine's scheduler, on local workers:
the demonstration files are read where they lie.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from langgap.demos.compact import load_demo
from langgap.demos.record import Demo, replay_states
from langgap.engine.execute import execute, with_progress
from langgap.engine.runner import RunnerSetup
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import Job, JobHost

if TYPE_CHECKING:
    from langgap.sim.env import TaskEnv

IMAGE_SIZE = 256


def checked_image_size(size: int | None) -> int:
    """`size` if LangGap renders it (`EnvOptions` refuses any other before anything is rendered), `IMAGE_SIZE`
    when None."""
    if size is None:
        return IMAGE_SIZE
    from langgap.sim.env import EnvOptions

    EnvOptions(image_size=size)
    return size


# Recorded with exported images (HDF5 attributes) so a reader need not guess.
IMAGE_ORIENTATION = (
    "upright: the raw MuJoCo render rotated 180 degrees (raw[::-1, ::-1]), as lerobot/libero and openpi; "
    "LIBERO's own HDF5 files store the raw render, upside down"
)


def render_frames(env: TaskEnv, demo: Demo) -> dict[str, np.ndarray]:
    """Replay `demo`'s states on `env` (built for its task with every camera) and render every camera at
    each: per camera (`langgap.sim.env.CAMERAS`), its (T, H, W, 3) uint8 frames."""
    from langgap.sim.env import CAMERAS

    frames = list(replay_states(env, demo, lambda e: [e.render(c) for c in CAMERAS]))
    return {camera: np.stack([f[i] for f in frames]) for i, camera in enumerate(CAMERAS)}


@dataclass(frozen=True)
class RenderDemo(Job):
    """The work item of one stored demonstration rendered; `index` is its place in the requested order."""

    kind: ClassVar[str] = "render"

    index: int
    path: str
    image_size: int = IMAGE_SIZE

    @property
    def task_id(self) -> str:
        # The folder of one task's demonstrations: they share a worker's rendering environment.
        return Path(self.path).parent.as_posix()

    def perform(self, runner: JobHost) -> tuple[int, Demo, dict[str, np.ndarray]]:
        from langgap.sim.env import CAMERAS, EnvOptions

        demo = load_demo(Path(self.path))
        options = EnvOptions(cameras=CAMERAS, image_size=self.image_size)
        env = runner.kept_env(runner.catalog.get(demo.task_id), options)
        return self.index, demo, render_frames(env, demo)


def iter_demos(
    catalog: str,
    paths: list[Path],
    *,
    render: bool,
    workers: int = 1,
    progress: bool = True,
    image_size: int = IMAGE_SIZE,
) -> Iterator[tuple[Demo, dict[str, np.ndarray]]]:
    """Each demonstration of `paths`, in that order, with its frames per camera (`image_size` square) when
    `render` (else `{}`).

    Rendering runs on `workers` local worker processes (0: here), through the engine's scheduler; the
    order is that of `paths` whatever their number, so an exported dataset does not depend on it.
    """
    if not render:
        yield from with_progress(((load_demo(p), {}) for p in paths), len(paths), unit="demo", enabled=progress)
        return
    items = [RenderDemo(i, str(p), image_size) for i, p in enumerate(paths)]
    options = ExecutionOptions(workers=workers, progress=progress)
    waiting: dict[int, tuple[Demo, dict[str, np.ndarray]]] = {}
    next_index = 0
    for index, demo, frames in execute(items, RunnerSetup(catalog=catalog), options, unit="demo"):
        waiting[index] = demo, frames
        while next_index in waiting:  # in the order of `paths`, whichever worker finished first
            yield waiting.pop(next_index)
            next_index += 1
