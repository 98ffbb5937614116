"""Environment speed: build, soft/hard reset, and step rate under rendering configurations.

Each configuration is measured in this one run, side by side, so the ratios are comparable even on a
noisy machine. A step with cameras means one physics step plus one render of every camera (what an
image policy queried at every step costs). The steppings themselves (exact, fast, robosuite's own)
are compared with raw physics by bench_step.py.

    .venv/bin/python bench/bench_env.py [--task ID] [--steps N] [--resets N]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

CONFIGS = {
    "no rendering": EnvOptions(),
    "2 cameras 128x128": EnvOptions(cameras=CAMERAS, image_size=128),
    "2 cameras 256x256": EnvOptions(cameras=CAMERAS, image_size=256),
    "2 cameras 256x256, reflection off": EnvOptions(cameras=CAMERAS, image_size=256, reflection=False),
}


def median_reset(env: TaskEnv, resets: int) -> float:
    times = []
    for k in range(resets):
        start = time.perf_counter()
        env.reset(k)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def measure(task, options: EnvOptions, steps: int, resets: int) -> dict[str, float]:
    start = time.perf_counter()
    env = TaskEnv(task, options)
    build = time.perf_counter() - start
    try:
        soft = median_reset(env, resets)
        action = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0])
        start = time.perf_counter()
        for i in range(steps):
            env.step(action if i % 20 < 10 else -action)
            env.observe()
        step_rate = steps / (time.perf_counter() - start)
    finally:
        env.close()
    hard_env = TaskEnv(task, replace(options, hard_reset=True))
    try:
        hard = median_reset(hard_env, resets)
    finally:
        hard_env.close()
    return {
        "build_s": build,
        "soft_reset_s": float(np.median(soft)),
        "hard_reset_s": float(np.median(hard)),
        "steps_per_s": step_rate,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="spatial/s0/black-bowl-1-on-plate")
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--resets", type=int, default=3)
    args = parser.parse_args()
    task = load_catalog().get(args.task)
    results = {name: measure(task, options, args.steps, args.resets) for name, options in CONFIGS.items()}
    base = results["no rendering"]["steps_per_s"]
    print(f"task {task.id}, {args.steps} steps, median of {args.resets} resets")
    print("| configuration | build s | soft reset s | hard reset s | steps/s | vs no rendering |")
    print("|---|---|---|---|---|---|")
    for name, r in results.items():
        print(
            f"| {name} | {r['build_s']:.2f} | {r['soft_reset_s']:.3f} | {r['hard_reset_s']:.2f} | "
            f"{r['steps_per_s']:.1f} | {r['steps_per_s'] / base:.2f}x |"
        )


if __name__ == "__main__":
    main()
