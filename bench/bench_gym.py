"""Throughput of the Gymnasium door beside the harness's own worker pool, on the same work.

    .venv/bin/python bench/bench_gym.py                      # N = 1, 2; 8 noop episodes of one spatial task
    .venv/bin/python bench/bench_gym.py --episodes 16 --stepping fast

The work: `--episodes` episodes of `--task` with the `noop` policy (no camera, never succeeds, so every
episode runs the task's full step limit after LangGap's settle steps). The harness runs it as
`langgap eval --workers N` (spawned worker processes, SQLite store); the Gymnasium door as
`gym.make_vec("LangGap/Task-v0", num_envs=N, vectorization_mode="async")` with spawned workers,
autoresetting until as many episodes have ended. Both are timed end to end (process start, simulator
build, every reset and step, shutdown); policy steps per second are compared (settle steps and
autoreset calls are not counted).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
from bench_harness import timed_run

import langgap.gym  # noqa: F401  (registers LangGap/Task-v0)
from langgap.sim.env import SETTLE_ACTION
from langgap.stack import DEFAULT_STEPPING
from langgap.vocabulary import Stepping, words

TASK = "spatial/s0/black-bowl-1-on-plate"


def harness_steps_per_s(task: str, episodes: int, workers: int, stepping: str) -> tuple[float, int]:
    """Policy steps per second of `langgap eval --policy noop --workers N` (and the steps it ran)."""
    run = timed_run("noop", task, episodes, stepping=stepping, workers=workers)
    steps = sum(record.steps for record in run.records)
    return steps / run.wall_s, steps


def gym_steps_per_s(task: str, episodes: int, num_envs: int, stepping: str) -> tuple[float, int]:
    """Policy steps per second of the async vector env running `episodes` noop episodes (and the steps)."""
    start = time.perf_counter()
    envs = gym.make_vec(
        "LangGap/Task-v0",
        num_envs=num_envs,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},
        task=task,
        stepping=stepping,
    )
    actions = np.tile(SETTLE_ACTION, (num_envs, 1))  # noop's action: hold still, gripper open
    envs.reset(seed=0)
    steps = ended = 0
    resetting = np.zeros(num_envs, dtype=bool)  # Gymnasium 1.x: the step after an episode's end resets it
    while ended < episodes:
        _, _, terminated, truncated, _ = envs.step(actions)
        steps += int((~resetting).sum())
        done = terminated | truncated
        ended += int(done.sum())
        resetting = done
    envs.close()
    return steps / (time.perf_counter() - start), steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default=TASK)
    parser.add_argument("--episodes", type=int, default=8, help="episodes per configuration (a multiple of 2)")
    parser.add_argument("--stepping", choices=words(Stepping), default=DEFAULT_STEPPING)
    args = parser.parse_args()
    print(f"{args.episodes} noop episodes of {args.task}, {args.stepping} stepping, timed end to end")
    print("| N | harness pool steps/s | gym async steps/s | gym / harness |\n|---|---|---|---|")
    for n in (1, 2):
        ours, our_steps = harness_steps_per_s(args.task, args.episodes, n, args.stepping)
        theirs, their_steps = gym_steps_per_s(args.task, args.episodes, n, args.stepping)
        assert our_steps == their_steps, (our_steps, their_steps)  # the same work
        print(f"| {n} | {ours:.0f} | {theirs:.0f} | {theirs / ours:.2f} |")


if __name__ == "__main__":
    main()
