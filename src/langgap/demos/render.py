"""Stored demonstrations read back in collection order, with camera frames rendered by replaying their states.

Shared by the exports (LeRobot, HDF5): a demonstration's frames exist nowhere but here, so every form of
the collection shows the same pixels. Frames are LangGap's images (`TaskEnv.render`): `IMAGE_SIZE`
square, upright, i.e. the raw MuJoCo render rotated 180 degrees (`raw[::-1, ::-1]`) — the orientation of
`lerobot/libero` and openpi's LIBERO data (LIBERO's own HDF5 files hold the raw, upside-down render).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from langgap.demos.compact import load_demo
from langgap.demos.record import Demo, replay_states

IMAGE_SIZE = 256
# Recorded with exported images (HDF5 attributes) so a reader need not guess.
IMAGE_ORIENTATION = (
    "upright: the raw MuJoCo render rotated 180 degrees (raw[::-1, ::-1]), as lerobot/libero and openpi; "
    "LIBERO's own HDF5 files store the raw render, upside down"
)

# One rendering env per process, for the task being rendered (a collection is ordered by task).
_ENVS: dict = {}


def render_demo(catalog: str, path: str | Path) -> tuple[Demo, dict[str, np.ndarray]]:
    """Replay the stored demonstration at `path` and render every camera at every recorded state.

    Returns the demonstration and, per camera (`langgap.sim.env.CAMERAS`), its (T, H, W, 3) uint8 frames;
    runs in a worker process or here.
    """
    from langgap.catalog.catalog import load_catalog
    from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

    demo = load_demo(Path(path))
    env = _ENVS.get(demo.task_id)
    if env is None:
        close_render_envs()
        env = _ENVS[demo.task_id] = TaskEnv(
            load_catalog(catalog).get(demo.task_id), EnvOptions(cameras=CAMERAS, image_size=IMAGE_SIZE)
        )
    frames = list(replay_states(env, demo, lambda e: [e.render(c) for c in CAMERAS]))
    return demo, {camera: np.stack([f[i] for f in frames]) for i, camera in enumerate(CAMERAS)}


def close_render_envs() -> None:
    """Close this process's rendering env (GL context and simulator)."""
    for env in _ENVS.values():
        env.close()
    _ENVS.clear()


def _render_star(args) -> tuple[Demo, dict[str, np.ndarray]]:
    return render_demo(*args)


def _load(path: Path) -> tuple[Demo, dict[str, np.ndarray]]:
    return load_demo(path), {}


def iter_demos(
    catalog: str, paths: list[Path], *, render: bool, workers: int = 1, progress: bool = True
) -> Iterator[tuple[Demo, dict[str, np.ndarray]]]:
    """Each demonstration of `paths`, in that order, with its frames per camera when `render` (else `{}`).

    Rendering runs in `workers` spawned processes (0: here); the order is that of `paths` whatever their
    number, so an exported dataset does not depend on it.
    """
    items = _iter_demos(catalog, paths, render=render, workers=workers)
    if not progress:
        yield from items
        return
    from tqdm import tqdm

    yield from tqdm(items, total=len(paths), unit="demo", desc="render" if render else "read")


def _iter_demos(
    catalog: str, paths: list[Path], *, render: bool, workers: int
) -> Iterator[tuple[Demo, dict[str, np.ndarray]]]:
    if not render:
        yield from map(_load, paths)
        return
    jobs = [(catalog, str(p)) for p in paths]
    if workers <= 0 or not jobs:
        try:
            yield from map(_render_star, jobs)
        finally:
            close_render_envs()
        return
    # Spawned, not forked: no GL or MuJoCo state may cross into a worker.
    with multiprocessing.get_context("spawn").Pool(min(workers, len(jobs))) as pool:
        yield from pool.imap(_render_star, jobs)
