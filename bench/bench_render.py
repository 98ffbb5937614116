"""Image policies against the renderer, the physical limit on a CPU machine (one run, side by side).

    .venv/bin/python bench/bench_render.py [--task ID] [--steps 60] [--size 256] [--rounds 5] [--png FILE] [--scenes]
                                           [--no-speed]

Rows, in interleaved rounds (medians): a bare render loop (two cameras per iteration, no physics),
with and without the reflection pass; a bare physics loop; the LangGap episode loop (`--steps` steps,
no settling) with an image policy queried at every step (renders its two cameras once per step), the
same with the reflection pass off, a chunked policy that executes 5 actions per query (renders every
5th step), and that policy with the render at reset LangGap used to make (thrown away: the policy
first looks after settling). Renders are counted, not inferred. The "limit" column is what physics +
the renders the policy needs would allow.

Then what the reflection pass changes in the images: both environments take the same actions, and
at several steps both cameras are compared (pixels that differ, mean and max absolute difference) and
the differing pixels attributed to the body drawn there (a segmentation render). `--png` saves
agentview with the pass on, off, and their difference (amplified) side by side; `--scenes` counts the
catalog's scenes that have a surface for the pass to draw; `--no-speed` skips the loop table (docs/reflection.png
is made that way by `python -m tools.docs_pictures reflection`, which stamps it with the code it shows).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from collections import Counter
from pathlib import Path

import mujoco
import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies.base import PolicySpec
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv

TASK = "spatial/s0/black-bowl-1-on-plate"
CHUNK = 5
PHYSICS_STEPS = 100
DIFF_GAIN = 8  # the difference image is amplified, or it would look black


class LookingNoop:
    """Holds still but asks for both cameras, like a VLA would."""

    def __init__(self, size: int, replan: int):
        self.spec = PolicySpec(cameras=CAMERAS, image_size=size, chunk=replan, replan=replan)

    def reset(self, context) -> None:
        pass

    def act(self, observation):
        assert len(observation.images) == len(CAMERAS)
        return np.tile([0, 0, 0, 0, 0, 0, -1.0], (self.spec.chunk, 1))


class ResetRenders(TaskEnv):
    """LangGap before: every reset rendered the cameras, an image no policy saw."""

    def reset(self, init_index, seed=0, *, render=True):
        return super().reset(init_index, seed, render=True)


@dataclasses.dataclass
class Loop:
    """One episode loop measured in every round."""

    label: str
    env: TaskEnv
    replan: int
    rates: list[float] = dataclasses.field(default_factory=list)
    renders_per_step: float = 0.0


def bare_render(env: TaskEnv, iterations: int) -> float:
    """Seconds per camera image, both cameras rendered in turn."""
    start = time.perf_counter()
    for _ in range(iterations):
        for camera in CAMERAS:
            env.render(camera)
    return (time.perf_counter() - start) / (iterations * len(CAMERAS))


def bare_physics(env: TaskEnv) -> float:
    """Seconds per control step of an env that renders nothing, over its task's steps."""
    env.reset(0)
    start = time.perf_counter()
    while not env.truncated:
        env.step(np.array([0, 0, 0, 0, 0, 0, -1.0]))
    return (time.perf_counter() - start) / env.steps


def episode(loop: Loop, size: int) -> None:
    """One episode of `loop`: its steps/s and renders per step."""
    catalog = load_catalog()
    context = task_context(loop.env.task, catalog, init_index=0, seed=0)
    before = loop.env.renders
    start = time.perf_counter()
    run_episode(loop.env, LookingNoop(size, loop.replan), context, settle_steps=0, watch=None)
    loop.rates.append(loop.env.steps / (time.perf_counter() - start))
    loop.renders_per_step = (loop.env.renders - before) / loop.env.steps


def round_ratio(numerators: list[float], denominators: list[float]) -> float:
    """Median over rounds of one round's ratio: load that drifts between rounds cancels out."""
    return statistics.median(n / d for n, d in zip(numerators, denominators, strict=True))


def rendering_env(task, size: int, reflection: bool = True, kind: type[TaskEnv] = TaskEnv) -> TaskEnv:
    return kind(task, env_options_for(LookingNoop(size, 1), reflection=reflection))


def speed(task, size: int, rounds: int, renders: int) -> None:
    """Print the loop table (interleaved rounds, medians)."""
    on, off = rendering_env(task, size), rendering_env(task, size, reflection=False)
    before = rendering_env(task, size, kind=ResetRenders)
    physics = TaskEnv(dataclasses.replace(task, max_steps=PHYSICS_STEPS))
    loops = [
        Loop("image policy, queried every step", on, 1),
        Loop("same, reflection pass off", off, 1),
        Loop(f"chunked policy, {CHUNK} actions per query", on, CHUNK),
        Loop("same, rendering at reset as before", before, CHUNK),
    ]
    render_s: dict[bool, list[float]] = {True: [], False: []}
    step_s: list[float] = []
    try:
        for env in (on, off):
            env.reset(0)
        for _ in range(rounds):
            render_s[True].append(bare_render(on, renders))
            render_s[False].append(bare_render(off, renders))
            step_s.append(bare_physics(physics))
            for loop in loops:
                episode(loop, size)
    finally:
        for env in (on, off, before, physics):
            env.close()
    render, plain, step = (statistics.median(v) for v in (render_s[True], render_s[False], step_s))
    print(
        f"{task.id}, {task.max_steps} steps, 2 cameras {size}x{size}, {rounds} rounds; one render "
        f"{1000 * render:.0f} ms ({1000 * plain:.0f} ms without reflections: "
        f"{round_ratio(render_s[False], render_s[True]):.2f}x), one physics step {1000 * step:.0f} ms"
    )
    print("| loop | renders per step | steps/s | limit (physics + needed renders) | of limit |")
    print("|---|---|---|---|---|")
    print(f"| bare physics, no rendering | 0 | {1 / step:.1f} | – | – |")
    for loop in loops:
        rate = statistics.median(loop.rates)
        limit = 1 / (step + loop.renders_per_step * (plain if loop.env is off else render))
        print(f"| {loop.label} | {loop.renders_per_step:.3f} | {rate:.2f} | {limit:.2f} | {rate / limit:.0%} |")
    print(
        f"chunked policy without the render at reset: {round_ratio(loops[2].rates, loops[3].rates):.3f}x "
        f"the steps/s of before ({loops[3].renders_per_step / loops[2].renders_per_step:.3f}x the renders)"
    )


# -- what the reflection pass changes ------------------------------------------------------------


def segmentation(env: TaskEnv, camera: str) -> np.ndarray:
    """Upright map of the geom id drawn at each pixel (-1: none), the orientation of `env.render`."""
    size = env.options.image_size
    env._make_render_context_current()
    raw = env.sim.render(camera_name=camera, width=size, height=size, segmentation=True)
    ids = np.where(raw[..., 0] == mujoco.mjtObj.mjOBJ_GEOM, raw[..., 1], -1)
    return ids[::-1, ::-1]


def body_of(env: TaskEnv, geom: int) -> str:
    if geom < 0:
        return "background"
    model = env.sim.model._model
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[geom])) or "world"


def side_by_side(with_pass: np.ndarray, without: np.ndarray) -> np.ndarray:
    """Reflection on | off | absolute difference amplified DIFF_GAIN times."""
    difference = np.abs(with_pass.astype(np.int16) - without.astype(np.int16)) * DIFF_GAIN
    return np.concatenate([with_pass, without, np.clip(difference, 0, 255).astype(np.uint8)], axis=1)


def reflection_difference(task, size: int, steps: int, png: Path | None) -> None:
    """Print per camera what turning the reflection pass off changes, over `steps` steps of a reach."""
    envs = [TaskEnv(task, EnvOptions(cameras=CAMERAS, image_size=size, reflection=r)) for r in (True, False)]
    rng = np.random.default_rng(0)
    changed: dict[str, list[np.ndarray]] = {c: [] for c in CAMERAS}
    where: dict[str, Counter] = {c: Counter() for c in CAMERAS}
    try:
        for env in envs:
            env.reset(0)
            env.settle()
        for step in range(steps):
            action = np.concatenate([rng.uniform(-0.5, 0.5, 6), [-1.0]])
            for env in envs:
                env.step(action)
            if step % 5:
                continue
            for camera in CAMERAS:
                with_pass, without = (env.render(camera) for env in envs)
                difference = np.abs(with_pass.astype(np.int16) - without.astype(np.int16))
                changed[camera].append(difference)
                geoms = segmentation(envs[1], camera)[difference.max(axis=2) > 0]
                where[camera].update(body_of(envs[1], g) for g in geoms)
                if png is not None and camera == CAMERAS[0] and step == 0:
                    from PIL import Image

                    Image.fromarray(side_by_side(with_pass, without)).save(png, optimize=True)
    finally:
        for env in envs:
            env.close()
    print(f"reflection pass off vs on, {size}x{size}, {len(changed[CAMERAS[0]])} steps of a reach")
    print("| camera | pixels that differ | mean abs difference (0-255) | max | where (share of differing pixels) |")
    print("|---|---|---|---|---|")
    for camera in CAMERAS:
        stack = np.stack(changed[camera])
        differing = float((stack.max(axis=3) > 0).mean())
        total = sum(where[camera].values())
        top = ", ".join(f"{body} {n / total:.0%}" for body, n in where[camera].most_common(3))
        print(f"| {camera} | {differing:.1%} | {stack.mean():.2f} | {stack.max()} | {top} |")


def reflective_bodies(env: TaskEnv) -> list[str]:
    """Bodies with a surface MuJoCo's reflection pass mirrors the scene in: a visible, opaque plane or
    box whose material reflects (MuJoCo draws the first one's reflection only)."""
    model = env.sim.model._model
    bodies = []
    for geom in range(model.ngeom):
        material = model.geom_matid[geom]
        if (
            model.geom_type[geom] in (mujoco.mjtGeom.mjGEOM_PLANE, mujoco.mjtGeom.mjGEOM_BOX)
            and material >= 0
            and model.mat_reflectance[material] > 0
            and model.geom_group[geom] in (1, 2)  # the groups LIBERO's cameras draw
            and min(model.geom_rgba[geom][3], model.mat_rgba[material][3]) >= 0.995
        ):
            bodies.append(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[geom])))
    return bodies


def reflective_scenes() -> None:
    """Print in how many of the catalog's scenes the reflection pass has a surface to draw."""
    first: dict[tuple[str, str], list[str]] = {}
    for task in load_catalog():
        if (task.suite, task.scene_task) not in first:
            with TaskEnv(task) as env:
                first[(task.suite, task.scene_task)] = reflective_bodies(env)
    surfaces = Counter(bodies[0] for bodies in first.values() if bodies)
    print(
        f"scenes with a reflective surface: {sum(surfaces.values())} of {len(first)} "
        f"({', '.join(f'{body}: {n}' for body, n in surfaces.items())}); in the others the pass draws nothing"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default=TASK)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--steps", type=int, default=60, help="episode length (the task's limit is 220)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--renders", type=int, default=10, help="bare render iterations per round")
    parser.add_argument("--png", type=Path, help="save agentview with reflections on | off | difference")
    parser.add_argument("--scenes", action="store_true", help="also count the scenes with a reflective surface")
    parser.add_argument("--no-speed", action="store_true", help="skip the loop table (only what the pass changes)")
    args = parser.parse_args()
    task = dataclasses.replace(load_catalog().get(args.task), max_steps=args.steps)
    if not args.no_speed:
        speed(task, args.size, args.rounds, args.renders)
    reflection_difference(task, args.size, min(args.steps, 30), args.png)
    if args.scenes:
        reflective_scenes()


if __name__ == "__main__":
    main()
