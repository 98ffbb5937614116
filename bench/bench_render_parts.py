"""Where a render's time goes, and what can be saved without changing a pixel (one run, side by side).

    .venv/bin/python bench/bench_render_parts.py [--rounds 5] [--frames 6] [--threads 0,1,2,default]

Stages: robosuite's `sim.render` of one camera is MuJoCo's `mjv_updateScene` (the scene's geoms,
the camera, the lights), `mjr_render` (returns once llvmpipe has transformed and binned every
triangle in this thread), the wait for llvmpipe's rasterizer threads (`glFinish`), `mjr_readPixels`
(multisample resolve and read-back), then LangGap's upright copy. Timed per stage for 1 and 2
cameras at 128 and 256 px, against the whole `TaskEnv.render` path, and against rendering both
cameras with one scene update (`mjv_updateCamera` + `mjv_makeLights` for the second camera), whose
images are compared pixel for pixel.

Threads: llvmpipe reads `LP_NUM_THREADS` (rasterizer threads; 0 rasterizes in the calling thread)
when it loads. Worker processes, each started with one setting, render both 256² cameras; each
setting runs alone (one worker) and as two workers rendering at once, in interleaved rounds. Every
worker hashes its images: they must agree across settings.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import multiprocessing as mp
import os
import statistics
import time
from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

TASK = "spatial/s0/black-bowl-1-on-plate"
STAGES = ("scene update", "render call", "rasterizer wait", "read-back", "upright copy")
DEFAULT = "default"  # LP_NUM_THREADS unset: llvmpipe starts one rasterizer thread per CPU


def _moving_env(size: int) -> TaskEnv:
    """An env with both cameras, reset and settled, ready to move the arm between rounds."""
    env = TaskEnv(load_catalog().get(TASK), EnvOptions(cameras=CAMERAS, image_size=size))
    env.reset(0)
    env.settle()
    return env


def _move(env: TaskEnv, steps: int = 3) -> None:
    """A few steps of a fixed reach, so each round renders a different arm pose."""
    for _ in range(steps):
        env.step(np.array([0.3, 0.2, -0.2, 0, 0, 0.1, -1.0]))


def _camera(env: TaskEnv, name: str) -> mujoco.MjvCamera:
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
    camera.fixedcamid = env.sim.model.camera_name2id(name)
    return camera


def staged_render(env: TaskEnv, cameras: tuple[str, ...]) -> tuple[dict[str, float], list[np.ndarray]]:
    """Seconds per stage summed over `cameras` (each rendered as robosuite does), and the images."""
    from OpenGL import GL  # after the env chose the GL platform

    context = env.sim._render_context_offscreen
    model, data = env.sim.model._model, env.sim.data._data
    size = env.options.image_size
    viewport = mujoco.MjrRect(0, 0, size, size)
    spent = dict.fromkeys(STAGES, 0.0)
    images = []
    env._make_render_context_current()
    for name in cameras:
        marks = [time.perf_counter()]
        mujoco.mjv_updateScene(
            model, data, context.vopt, context.pert, _camera(env, name), mujoco.mjtCatBit.mjCAT_ALL, context.scn
        )
        marks.append(time.perf_counter())
        mujoco.mjr_render(viewport, context.scn, context.con)
        marks.append(time.perf_counter())
        GL.glFinish()
        marks.append(time.perf_counter())
        raw = np.empty((size, size, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(raw, None, viewport, context.con)
        marks.append(time.perf_counter())
        images.append(np.ascontiguousarray(raw[::-1, ::-1]))
        marks.append(time.perf_counter())
        for stage, start, end in zip(STAGES, marks, marks[1:], strict=False):
            spent[stage] += end - start
    return spent, images


def shared_update_render(env: TaskEnv, cameras: tuple[str, ...]) -> list[np.ndarray]:
    """All `cameras` from one scene update: only the camera and its headlight change between them."""
    context = env.sim._render_context_offscreen
    model, data = env.sim.model._model, env.sim.data._data
    size = env.options.image_size
    viewport = mujoco.MjrRect(0, 0, size, size)
    env._make_render_context_current()
    images = []
    for k, name in enumerate(cameras):
        camera = _camera(env, name)
        if k == 0:
            mujoco.mjv_updateScene(
                model, data, context.vopt, context.pert, camera, mujoco.mjtCatBit.mjCAT_ALL, context.scn
            )
        else:
            mujoco.mjv_updateCamera(model, data, camera, context.scn)
            mujoco.mjv_makeLights(model, data, context.scn)  # the headlight follows the camera
        mujoco.mjr_render(viewport, context.scn, context.con)
        raw = np.empty((size, size, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(raw, None, viewport, context.con)
        images.append(np.ascontiguousarray(raw[::-1, ::-1]))
    return images


def _render_all(env: TaskEnv, cameras: tuple[str, ...]) -> list[np.ndarray]:
    return [env.render(camera) for camera in cameras]


def _timed(function, *args) -> tuple[float, object]:
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def stages(sizes: tuple[int, ...], rounds: int, frames: int) -> None:
    """Print the per-stage table and the one-scene-update comparison."""
    envs = {size: _moving_env(size) for size in sizes}
    cases = [(size, cameras) for size in sizes for cameras in (CAMERAS[:1], CAMERAS)]
    parts: dict[tuple, list[dict[str, float]]] = {case: [] for case in cases}
    whole: dict[tuple, list[float]] = {case: [] for case in cases}
    shared: dict[int, list[float]] = {size: [] for size in sizes}
    differing = dict.fromkeys(sizes, 0)
    try:
        for _ in range(rounds):
            for size, env in envs.items():
                _move(env)
                for _ in range(frames):
                    for case in [c for c in cases if c[0] == size]:
                        parts[case].append(staged_render(env, case[1])[0])
                        whole[case].append(_timed(_render_all, env, case[1])[0])
                    seconds, images = _timed(shared_update_render, env, CAMERAS)
                    shared[size].append(seconds)
                    today = _render_all(env, CAMERAS)
                    differing[size] += sum(int(np.count_nonzero(a != b)) for a, b in zip(images, today, strict=True))
    finally:
        for env in envs.values():
            env.close()
    print("| size | cameras | " + " | ".join(STAGES) + " | sum of stages | `TaskEnv.render` path |")
    print("|---|---|" + "---|" * (len(STAGES) + 2))
    for size, cameras in cases:
        medians = {s: statistics.median(p[s] for p in parts[(size, cameras)]) for s in STAGES}
        total = sum(medians.values())
        real = statistics.median(whole[(size, cameras)])
        cells = " | ".join(f"{1000 * medians[s]:.2f} ms ({medians[s] / total:.1%})" for s in STAGES)
        print(f"| {size}² | {len(cameras)} | {cells} | {1000 * total:.1f} ms | {1000 * real:.1f} ms |")
    for size in sizes:
        two = statistics.median(whole[(size, CAMERAS)])
        one_update = statistics.median(shared[size])
        print(
            f"{size}²: both cameras from one scene update: {1000 * one_update:.1f} ms vs {1000 * two:.1f} ms "
            f"({one_update / two - 1:+.1%}); pixels that differ from today's images: {differing[size]}"
        )


# -- software-renderer threads ---------------------------------------------------------------------


@contextlib.contextmanager
def _lp_threads(setting: str) -> Iterator[None]:
    """LP_NUM_THREADS as `setting` for the processes started inside (spawned children copy it)."""
    before = os.environ.get("LP_NUM_THREADS")
    if setting == DEFAULT:
        os.environ.pop("LP_NUM_THREADS", None)
    else:
        os.environ["LP_NUM_THREADS"] = setting
    try:
        yield
    finally:
        if before is None:
            os.environ.pop("LP_NUM_THREADS", None)
        else:
            os.environ["LP_NUM_THREADS"] = before


def llvmpipe_threads() -> int:
    """Rasterizer threads llvmpipe started in this process (it names them llvmpipe-N)."""
    tasks = Path("/proc/self/task").glob("*/comm")
    return sum(1 for comm in tasks if comm.read_text().startswith("llvmpipe-"))


def _render_worker(connection, size: int) -> None:
    """Render both cameras `n` times per request; answer seconds per frame and a hash of the images."""
    env = _moving_env(size)
    try:
        connection.send(llvmpipe_threads())
        while (n := connection.recv()) is not None:
            digest = hashlib.sha256()
            start = time.perf_counter()
            for _ in range(n):
                for camera in CAMERAS:
                    digest.update(env.render(camera).tobytes())
            connection.send(((time.perf_counter() - start) / n, digest.hexdigest()))
    finally:
        env.close()


def _start_workers(settings: list[str], size: int) -> dict[str, list]:
    """Two idle render workers per thread setting (connection, process); prints the threads each got."""
    context = mp.get_context("spawn")
    workers: dict[str, list] = {}
    started: dict[str, int] = {}
    for setting in settings:
        workers[setting] = []
        for _ in range(2):
            ours, theirs = context.Pipe()
            with _lp_threads(setting):
                process = context.Process(target=_render_worker, args=(theirs, size), daemon=True)
                process.start()
            started[setting] = ours.recv()
            workers[setting].append((ours, process))
    print("llvmpipe rasterizer threads per worker: " + ", ".join(f"{s}: {n}" for s, n in started.items()))
    return workers


def _run(connections: list, frames: int) -> list[tuple[float, str]]:
    for connection in connections:
        connection.send(frames)
    return [connection.recv() for connection in connections]


def threads(settings: list[str], size: int, rounds: int, frames: int) -> None:
    """Print seconds per frame (both cameras) and throughput per thread setting, 1 and 2 workers."""
    workers = _start_workers(settings, size)
    alone: dict[str, list[float]] = {s: [] for s in settings}
    paired: dict[str, list[float]] = {s: [] for s in settings}
    hashes: set[str] = set()
    try:
        for r in range(rounds):
            order = settings[r % len(settings) :] + settings[: r % len(settings)]
            for setting in order:
                connections = [connection for connection, _ in workers[setting]]
                seconds, digest = _run(connections[:1], frames)[0]
                alone[setting].append(seconds)
                hashes.add(digest)
                both = _run(connections, frames)
                paired[setting].append(statistics.mean(s for s, _ in both))
                hashes.update(d for _, d in both)
    finally:
        for pair in workers.values():
            for connection, process in pair:
                connection.send(None)
                process.join()
    one = {s: statistics.median(alone[s]) for s in settings}
    two = {s: statistics.median(paired[s]) for s in settings}
    base = DEFAULT if DEFAULT in settings else settings[0]
    print(f"| LP_NUM_THREADS | 1 worker: ms per frame (2 × {size}²) | 2 workers: ms per frame, each | 2 workers vs 1 |")
    print("|---|---|---|---|")
    for setting in settings:
        print(
            f"| {setting} | {1000 * one[setting]:.0f} ({one[base] / one[setting]:.2f}x {base}'s speed) "
            f"| {1000 * two[setting]:.0f} ({two[base] / two[setting]:.2f}x {base}'s throughput) "
            f"| {2 * one[setting] / two[setting]:.2f}x frames/s |"
        )
    print(f"images identical across settings and workers: {len(hashes) == 1}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--threads", default=f"0,1,2,{DEFAULT}", help="LP_NUM_THREADS settings to compare")
    parser.add_argument("--skip", choices=("stages", "threads"), help="leave one part out")
    args = parser.parse_args()
    print(f"{TASK}; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs at the start")
    if args.skip != "stages":
        stages((128, 256), args.rounds, args.frames)
    if args.skip != "threads":
        threads(args.threads.split(","), 256, args.rounds, args.frames)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
