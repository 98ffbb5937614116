"""What images cost: the render of both cameras by image size, demonstrations/hour with images, and episodes/hour of a
pixel policy (one run, side by side).

1. Both cameras rendered from one state at each `--sizes` (interleaved rounds, medians; reflection pass on, as
   LIBERO renders).
2. `--data DIR` (a collection): its demonstrations exported with images (`export-hdf5 --images`) at the policy's
   size (`--size`, default 96) and at 256, one worker each, one after the other: demonstrations/hour and frames/s.
3. `--checkpoint CKPT` (a small-vla checkpoint): `--episodes` episodes of each of `--tasks` evaluated with it, one
   worker, beside the same plan with `blind` (the oracle, no images): episodes/hour and steps/s.

    .venv/bin/python bench/bench_images.py [--sizes 64,96,128,256] [--data DIR] [--checkpoint CKPT]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from langgap.catalog.catalog import load_catalog
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

TASK = "spatial/s0/black-bowl-1-on-plate"


def render_by_size(sizes: list[int], rounds: int) -> dict[int, float]:
    """Median ms to render both cameras at each size (one environment per size, rounds interleaved)."""
    task = load_catalog().get(TASK)
    envs = {size: TaskEnv(task, EnvOptions(cameras=CAMERAS, image_size=size)) for size in sizes}
    try:
        for env in envs.values():
            env.reset(0, render=False)
            env.settle()
            env.observe()  # warm up: the first render uploads the scene's textures
        times: dict[int, list[float]] = {size: [] for size in sizes}
        for _ in range(rounds):
            for size, env in envs.items():
                start = time.perf_counter()
                env.observe()
                times[size].append(time.perf_counter() - start)
    finally:
        for env in envs.values():
            env.close()
    return {size: statistics.median(t) * 1e3 for size, t in times.items()}


def export_rates(data: str, sizes: list[int]) -> dict[int, tuple[float, float]]:
    """(demonstrations/hour, frames/s) of exporting `data` with images at each size, one worker."""
    from langgap.demos.compact import demo_files, load_demo
    from langgap.demos.hdf5 import write_hdf5

    paths = demo_files(Path(data))
    frames = sum(load_demo(p).length for p in paths)
    rates = {}
    for size in sizes:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            write_hdf5(data, out=tmp, images=True, image_size=size, workers=1, progress=False)
            wall = time.perf_counter() - start
        rates[size] = (len(paths) / wall * 3600, frames / wall)
    return rates


def eval_rates(checkpoint: str, tasks: str, episodes: int) -> dict[str, tuple[float, float]]:
    """(episodes/hour, steps/s) of small-vla and of `blind` on the same plan, one worker each."""
    from langgap.engine.evaluate import evaluate
    from langgap.engine.spec import ExecutionOptions, RunSpec
    from langgap.store import RunStore

    rates = {}
    for policy, policy_args in (("small-vla", {"checkpoint": checkpoint}), ("blind", {})):
        spec = RunSpec.create(policy, policy_args=policy_args, tasks=tasks, episodes=episodes)
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            evaluate(spec, Path(tmp) / "run", ExecutionOptions(workers=1, progress=False))
            wall = time.perf_counter() - start
            with RunStore.open(Path(tmp) / "run") as store:
                records = store.records()
        rates[policy] = (len(records) / wall * 3600, sum(r.steps for r in records) / wall)
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="64,96,128,256", help="render sizes, comma-separated")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--data", help="a collection to export with images")
    parser.add_argument("--size", type=int, default=96, help="the policy's image size (default 96)")
    parser.add_argument("--checkpoint", help="a small-vla checkpoint to evaluate")
    parser.add_argument("--tasks", default="spatial/s0/*", help="its episodes' tasks (default spatial/s0/*)")
    parser.add_argument("--episodes", type=int, default=1, help="init states per task (default 1)")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    rendered = render_by_size(sizes, args.rounds)
    print(f"both cameras rendered from one state ({TASK}, {args.rounds} interleaved rounds, medians):")
    print("| size | ms for both cameras | vs 256 |\n|---|---|---|")
    for size, ms in rendered.items():
        print(f"| {size} | {ms:.1f} | {ms / rendered.get(256, ms):.2f}x |")
    if args.data:
        rates = export_rates(args.data, [args.size, 256])
        print(f"\n{args.data} exported with images, one worker:")
        print("| size | demonstrations/hour | frames/s |\n|---|---|---|")
        for size, (per_hour, per_s) in rates.items():
            print(f"| {size} | {per_hour:.0f} | {per_s:.2f} |")
    if args.checkpoint:
        rates = eval_rates(args.checkpoint, args.tasks, args.episodes)
        print(f"\n{args.tasks}, {args.episodes} episode(s) per task, one worker:")
        print("| policy | episodes/hour | steps/s |\n|---|---|---|")
        for policy, (per_hour, per_s) in rates.items():
            print(f"| {policy} | {per_hour:.0f} | {per_s:.2f} |")


if __name__ == "__main__":
    main()
