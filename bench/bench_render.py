"""Image policies against the renderer, the physical limit on a CPU machine (one run, side by side).

    .venv/bin/python bench/bench_render.py [--steps 60] [--size 256]

Rows: a bare render loop (two cameras per iteration, no physics); a bare physics loop; the LangGap
episode loop with an image policy queried at every step (renders its two cameras once per step), with
the reflection pass off, and with a chunked policy that executes 5 actions per query (renders every 5th
step). The "limit" column is what physics + the renders the policy needs would allow.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies.base import PolicySpec
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

TASK = "spatial/s0/black-bowl-1-on-plate"


class LookingNoop:
    """Holds still but asks for both cameras, like a VLA would."""

    def __init__(self, size: int, replan: int):
        self.spec = PolicySpec(cameras=CAMERAS, image_size=size, chunk=replan, replan=replan)

    def reset(self, context) -> None:
        pass

    def act(self, observation):
        assert len(observation.images) == len(CAMERAS)
        return np.tile([0, 0, 0, 0, 0, 0, -1.0], (self.spec.chunk, 1))


def bare_render(size: int, iterations: int, reflection: bool = True) -> float:
    task = load_catalog().get(TASK)
    with TaskEnv(task, EnvOptions(cameras=CAMERAS, image_size=size, reflection=reflection)) as env:
        env.reset(0)
        start = time.perf_counter()
        for _ in range(iterations):
            for camera in CAMERAS:
                env.render(camera)
        return (time.perf_counter() - start) / (iterations * len(CAMERAS))


def bare_physics(steps: int) -> float:
    task = load_catalog().get(TASK)
    with TaskEnv(task) as env:
        env.reset(0)
        start = time.perf_counter()
        for _ in range(steps):
            env.step(np.array([0, 0, 0, 0, 0, 0, -1.0]))
        return (time.perf_counter() - start) / steps


def episode_rate(policy: LookingNoop, reflection: bool = True) -> float:
    catalog = load_catalog()
    task = catalog.get(TASK)
    with TaskEnv(task, env_options_for(policy, reflection=reflection)) as env:
        context = task_context(task, catalog, init_index=0, seed=0)
        start = time.perf_counter()
        run_episode(env, policy, context, settle_steps=0, watch=None)
        return env.steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--renders", type=int, default=30)
    args = parser.parse_args()
    render_s = bare_render(args.size, args.renders)
    render_plain_s = bare_render(args.size, args.renders, reflection=False)
    step_s = bare_physics(100)
    every = episode_rate(LookingNoop(args.size, 1))
    plain = episode_rate(LookingNoop(args.size, 1), reflection=False)
    chunked = episode_rate(LookingNoop(args.size, 5))
    limit_every = 1 / (step_s + 2 * render_s)
    limit_plain = 1 / (step_s + 2 * render_plain_s)
    limit_chunked = 1 / (step_s + 2 * render_s / 5)
    print(
        f"{TASK}, 2 cameras {args.size}x{args.size}; one render {1000 * render_s:.0f} ms "
        f"({1000 * render_plain_s:.0f} ms without reflections), one physics step {1000 * step_s:.0f} ms"
    )
    print("| loop | steps/s | limit (physics + needed renders) | of limit |")
    print("|---|---|---|---|")
    print(f"| bare physics, no rendering | {1 / step_s:.1f} | – | – |")
    print(f"| image policy, queried every step | {every:.2f} | {limit_every:.2f} | {every / limit_every:.0%} |")
    print(f"| same, reflection pass off | {plain:.2f} | {limit_plain:.2f} | {plain / limit_plain:.0%} |")
    print(
        f"| chunked policy, 5 actions per query | {chunked:.2f} | {limit_chunked:.2f} | {chunked / limit_chunked:.0%} |"
    )


if __name__ == "__main__":
    main()
