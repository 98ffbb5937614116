"""Harness speed, as ratios measured side by side in one run.

    .venv/bin/python bench/bench_harness.py overhead   # harness vs a bare LIBERO loop, same actions (target <= 3 %)
    .venv/bin/python bench/bench_harness.py authors    # oracle episodes/hour vs the authors' evaluator setup (>= 15x)
    .venv/bin/python bench/bench_harness.py workers    # 2 workers vs 1, no rendering (>= 1.8x)
    .venv/bin/python bench/bench_harness.py protocol   # the full protocol: 99 tasks x 20 episodes, oracle, 2 workers
    .venv/bin/python bench/bench_harness.py validate   # langgap validate over all 99 tasks x 50 init states (<= 60 min)

Every mode takes `--stepping exact|fast` (default exact, bit-identical to robosuite's stepping).

The authors' configuration (their evaluator, re-created with LangGap's own pieces): a hard reset every
episode, two 256x256 cameras rendered at every step, one process.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import mujoco
import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.evaluate import RunSummary, evaluate
from langgap.engine.spec import RESULT_STEPPINGS, ExecutionOptions, RunSpec
from langgap.records import EpisodeRecord
from langgap.sim.env import CAMERAS, SETTLE_ACTION, SETTLE_STEPS, EnvOptions, TaskEnv
from langgap.stack import DEFAULT_STEPPING
from langgap.store import RunStore
from langgap.vocabulary import words

SAMPLE_TASKS = (
    "spatial/s0/black-bowl-1-on-plate,spatial/s0/ramekin-on-plate,goal/s7/turn-on-stove,"
    "object/s0/alphabet-soup-in-basket"
)
T = TypeVar("T")


@dataclass
class TimedRun:
    """One timed evaluation: its wall time, the driver process's CPU time, and each worker's time in episodes."""

    wall_s: float
    driver_cpu_s: float
    summary: RunSummary
    records: list[EpisodeRecord]

    @property
    def busy_s(self) -> dict[int, float]:
        """Each worker's time in episodes (the sum of its episodes' wall times)."""
        busy: dict[int, float] = {}
        for record in self.records:
            busy[record.worker] = busy.get(record.worker, 0.0) + record.wall_time_s
        return busy


def timed_run(
    policy: str,
    tasks: str,
    episodes: int,
    policy_args: dict[str, str] | None = None,
    stepping: str = DEFAULT_STEPPING,
    **execution,
) -> TimedRun:
    """One fresh evaluation, timed (spec from the arguments, `execution`: ExecutionOptions fields)."""
    spec = RunSpec.create(policy, policy_args=policy_args, tasks=tasks, episodes=episodes, stepping=stepping)
    with tempfile.TemporaryDirectory() as tmp:
        start, cpu = time.perf_counter(), time.process_time()
        summary = evaluate(spec, Path(tmp) / "run", ExecutionOptions(progress=False, **execution))
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        with RunStore.open(Path(tmp) / "run") as store:
            return TimedRun(wall, cpu, summary, store.records())


def timed_eval(policy: str, tasks: str, episodes: int, **arguments) -> tuple[float, RunSummary]:
    """Wall time and summary of one fresh evaluation (arguments as `timed_run`'s)."""
    run = timed_run(policy, tasks, episodes, **arguments)
    return run.wall_s, run.summary


class ReplayPolicy:
    """Replays a fixed action sequence (shared with the bare loop through an .npy file)."""

    def __init__(self, actions: str = ""):
        from langgap.policies.base import PolicySpec

        self.actions = np.load(actions)
        self.spec = PolicySpec()
        self.t = 0

    def reset(self, context) -> None:
        self.t = 0

    def act(self, observation):
        self.t += 1
        return self.actions[self.t - 1]


def bare_loop(task_id: str, actions: np.ndarray, episodes: int) -> float:
    """LIBERO alone: build, then per episode reset, set init state, settle, apply actions, check success."""
    from langgap.catalog import files

    task = load_catalog().get(task_id)
    from libero.libero.envs.env_wrapper import ControlEnv

    start = time.perf_counter()
    env = ControlEnv(
        bddl_file_name=str(files.task_bddl_path(task)),
        has_offscreen_renderer=False,
        use_camera_obs=False,
        ignore_done=True,
        hard_reset=False,
    )
    init = files.init_states(task)
    for k in range(episodes):
        np.random.seed(k)
        env.reset()
        env.set_init_state(init[k])
        for _ in range(SETTLE_STEPS):
            env.step(SETTLE_ACTION)
        for action in actions:
            env.step(action)
            if env.check_success():
                break
    env.close()
    return time.perf_counter() - start


def overhead(episodes: int, rounds: int) -> None:
    task_id = "spatial/s0/black-bowl-1-on-plate"
    steps = load_catalog().get(task_id).max_steps
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, size=(steps, 7))
    actions[:, 6] = -1
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "actions.npy")
        np.save(path, actions)
        # Alternate the two loops and keep each one's best round: the machine's noise only ever adds time.
        bare, harness = float("inf"), float("inf")
        for _ in range(rounds):
            bare = min(bare, bare_loop(task_id, actions, episodes))
            harness = min(
                harness,
                timed_eval(
                    policy="bench_harness:ReplayPolicy",
                    policy_args={"actions": path},
                    tasks=task_id,
                    episodes=episodes,
                    workers=0,
                )[0],
            )
    print(
        f"| {episodes} episodes x {steps} steps | bare LIBERO {bare:.1f} s | langgap eval (in-process, sibling "
        f"goals, store) {harness:.1f} s | overhead {100 * (harness / bare - 1):+.1f} % (target <= 3 %) |"
    )


def authors(episodes: int, workers: int, policy: str) -> None:
    catalog = load_catalog()
    tasks = catalog.select(SAMPLE_TASKS)
    from langgap.engine.context import task_context
    from langgap.engine.rollout import run_episode
    from langgap.policies import make_policy

    agent = make_policy(policy)
    start = time.perf_counter()
    for task in tasks:
        options = EnvOptions(cameras=CAMERAS, image_size=256, hard_reset=True, privileged=agent.spec.sees_state)
        with TaskEnv(task, options) as env:
            for k in range(episodes):
                # Their loop rendered both cameras at every step, whatever the policy looked at.
                run_episode(
                    env,
                    agent,
                    task_context(task, catalog, init_index=k, seed=k),
                    on_step=lambda e, _s, _a: [e.render(c) for c in CAMERAS],
                )
    theirs = time.perf_counter() - start
    ours, summary = timed_eval(policy=policy, tasks=SAMPLE_TASKS, episodes=episodes, workers=workers)
    per_hour_theirs = len(tasks) * episodes / theirs * 3600
    per_hour_ours = summary.ran / ours * 3600
    print(
        f"| {policy}, {len(tasks)} tasks x {episodes} | authors' setup {per_hour_theirs:.0f} ep/h | LangGap "
        f"({workers} workers) {per_hour_ours:.0f} ep/h | {per_hour_ours / per_hour_theirs:.1f}x (target >= 15x) |"
    )


def _physics_rate(seconds: float) -> float:
    """mj_step calls per second on one LIBERO model, in this process (no harness, no Python control)."""
    env = TaskEnv(load_catalog().get(SAMPLE_TASKS.split(",")[0]), EnvOptions())
    try:
        env.reset(0)
        model, data = env.robosuite_env.sim.model._model, env.robosuite_env.sim.data._data
        steps, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            for _ in range(100):
                mujoco.mj_step(model, data)
            steps += 100
        return steps / (time.perf_counter() - start)
    finally:
        env.close()


def in_processes(measure: Callable[..., T], args: tuple, processes: int) -> list[T]:
    """`measure(*args)` in `processes` fresh processes at once (spawned: nothing inherited); their results."""
    with mp.get_context("spawn").Pool(processes) as pool:
        return pool.starmap(measure, [args] * processes)


def machine_ceiling(seconds: float = 20.0) -> float:
    """How much two processes of raw physics get done against one, on this machine (its own scaling)."""
    one, two = (sum(in_processes(_physics_rate, (seconds,), n)) for n in (1, 2))
    return two / one


def workers(episodes: int, policy: str, stepping: str) -> None:
    ceiling = machine_ceiling()
    runs = {
        n: timed_run(policy=policy, tasks=SAMPLE_TASKS, episodes=episodes, stepping=stepping, workers=n) for n in (1, 2)
    }
    one, two = runs[1], runs[2]
    print(
        f"| {policy}, {one.summary.ran} episodes, {stepping} stepping | 1 worker {one.wall_s:.0f} s | 2 workers "
        f"{two.wall_s:.0f} s | {one.wall_s / two.wall_s:.2f}x (target >= 1.8x) | this machine's own ceiling "
        f"(raw physics, 2 processes vs 1): {ceiling:.2f}x |"
    )
    print("where the time goes | 1 worker | 2 workers")
    for n, run in runs.items():
        busy = sum(run.busy_s.values())
        print(
            f"  {n} worker(s): wall {run.wall_s:.1f} s; in episodes {busy:.1f} s of {n * run.wall_s:.1f} worker-s "
            f"({busy / (n * run.wall_s):.0%}; the rest: start-up, environment builds, hand-overs, idle tail); "
            f"driver CPU {run.driver_cpu_s:.1f} s; per-episode time {busy / run.summary.ran:.2f} s"
        )
    slowdown = (sum(two.busy_s.values()) / two.summary.ran) / (sum(one.busy_s.values()) / one.summary.ran)
    print(f"  an episode takes {slowdown:.2f}x as long with 2 workers as with 1 (both cores busy: caches, memory)")


def protocol(policy: str, run: str | None, stepping: str) -> None:
    directory = Path(run) if run else Path(tempfile.mkdtemp()) / "run"
    start = time.perf_counter()
    summary = evaluate(
        RunSpec.create(policy, tasks="all", episodes=20, stepping=stepping),
        directory,
        ExecutionOptions(workers=2),
        resume=run is not None,
    )
    wall = time.perf_counter() - start
    print(
        f"| full protocol, {policy}, 99 tasks x 20 episodes, 2 workers, {stepping} stepping | {summary.ran} "
        f"episodes run in {wall / 60:.1f} min = {summary.ran / wall * 3600:.0f} episodes/h ({summary.successes} "
        f"successes, {summary.gaps} gaps) | target <= 25 min |"
    )
    with RunStore.open(directory) as store:
        records = store.records()
    if summary.ran < len(records):
        return  # resumed: the wall time covers only part of the episodes
    steps = sum(r.steps + r.settle_steps for r in records)
    busy = TimedRun(wall, 0.0, summary, records).busy_s
    print(
        f"  where the time went: {steps} control steps (settling included); each worker in episodes "
        + ", ".join(f"{b / wall:.0%} of the wall" for b in busy.values())
        + f"; {1e3 * sum(busy.values()) / steps:.1f} ms per control step all in (physics, oracle, goal checks, store)"
    )


def validation(workers: int, run: str | None, stepping: str) -> None:
    from langgap.engine.spec import ExecutionOptions
    from langgap.gate.rows import FULL_INITS
    from langgap.gate.validation import validate

    start = time.perf_counter()
    found = validate(
        "langgap99",
        "all",
        inits=FULL_INITS,
        options=ExecutionOptions(workers=workers),
        run=run,
        resume=run is not None,
        stepping=stepping,
    )
    wall = time.perf_counter() - start
    episodes = sum(row.episodes for row in found.rows)
    print(
        f"| langgap validate, 99 tasks x {FULL_INITS} init states, {workers} workers, {stepping} stepping | "
        f"{episodes} episodes in {wall / 60:.1f} min = {episodes / wall * 3600:.0f} episodes/h | target <= 60 min |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("overhead", "authors", "workers", "protocol", "validate"))
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--policy", default="oracle")
    parser.add_argument("--rounds", type=int, default=3, help="overhead: alternating rounds (best of each)")
    parser.add_argument("--run", help="protocol, validate: keep (and resume) the run here")
    parser.add_argument("--stepping", choices=words(RESULT_STEPPINGS), default=DEFAULT_STEPPING)
    args = parser.parse_args()
    if args.what == "overhead":
        overhead(args.episodes, args.rounds)
    elif args.what == "authors":
        authors(args.episodes, args.workers, args.policy)
    elif args.what == "workers":
        workers(args.episodes, args.policy, args.stepping)
    elif args.what == "protocol":
        protocol(args.policy, args.run, args.stepping)
    else:
        validation(args.workers, args.run, args.stepping)


if __name__ == "__main__":
    main()
