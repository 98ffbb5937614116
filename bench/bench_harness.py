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
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.evaluate import RunSummary, evaluate
from langgap.engine.spec import RESULT_STEPPINGS, ExecutionOptions, RunSpec
from langgap.records import EpisodeRecord
from langgap.sim.env import CAMERAS, SETTLE_ACTION, SETTLE_STEPS, EnvOptions, TaskEnv
from langgap.stack import DEFAULT_STEPPING
from langgap.store import RunStore

SAMPLE_TASKS = (
    "spatial/s0/black-bowl-1-on-plate,spatial/s0/ramekin-on-plate,goal/s7/turn-on-stove,"
    "object/s0/alphabet-soup-in-basket"
)


def timed_eval(
    policy: str,
    tasks: str,
    episodes: int,
    policy_args: dict[str, str] | None = None,
    stepping: str = DEFAULT_STEPPING,
    records: list[EpisodeRecord] | None = None,
    **execution,
) -> tuple[float, RunSummary]:
    """Wall time of one fresh evaluation (spec from the arguments, `execution`: ExecutionOptions fields);
    `records`, if given, receives the stored episodes."""
    spec = RunSpec.create(policy, policy_args=policy_args, tasks=tasks, episodes=episodes, stepping=stepping)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        summary = evaluate(spec, Path(tmp) / "run", ExecutionOptions(progress=False, **execution))
        seconds = time.perf_counter() - start
        if records is not None:
            with RunStore.open(Path(tmp) / "run") as store:
                records.extend(store.records())
        return seconds, summary


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
        options = EnvOptions(cameras=CAMERAS, image_size=256, hard_reset=True, privileged=agent.spec.privileged)
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


def workers(episodes: int, policy: str, stepping: str) -> None:
    one, summary = timed_eval(policy=policy, tasks=SAMPLE_TASKS, episodes=episodes, stepping=stepping, workers=1)
    two, _ = timed_eval(policy=policy, tasks=SAMPLE_TASKS, episodes=episodes, stepping=stepping, workers=2)
    print(
        f"| {policy}, {summary.ran} episodes | 1 worker {one:.0f} s | 2 workers {two:.0f} s | {one / two:.2f}x "
        "(target >= 1.8x) |"
    )


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


def validation(workers: int, run: str | None, stepping: str) -> None:
    from langgap.validate import FULL_INITS, validate

    start = time.perf_counter()
    found = validate(
        "langgap99", "all", inits=FULL_INITS, workers=workers, run=run, resume=run is not None, stepping=stepping
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
    parser.add_argument("--stepping", choices=RESULT_STEPPINGS, default=DEFAULT_STEPPING)
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
