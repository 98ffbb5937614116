"""One control step against the raw physics it is made of, and where an oracle episode's step goes.

Side by side in one process, on one model, in interleaved rounds (so load on a shared machine hits
every row alike), the medians of:
- raw physics: the 25 `mj_step` calls of one control step (LIBERO: 20 Hz control, 2 ms physics),
  on a copy of the simulator's state taken mid-episode;
- LangGap's `exact` stepping (bit-identical to robosuite's), its `fast` stepping (the last bits
  differ) and robosuite's own step, same actions;
then an oracle episode profiled (cProfile) by where its time goes: physics, robosuite's controller
and step loop, LangGap's goal checks (all the scene's goals, every step), the oracle's planning,
and the rest of the harness.

    .venv/bin/python bench/bench_step.py [--task ID] [--steps N] [--rounds R] [--no-profile]
"""

from __future__ import annotations

import argparse
import copy
import cProfile
import pstats
import statistics
import time

import mujoco
import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.engine.episode import scene_goals
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies import make_policy
from langgap.sim.env import EnvOptions, TaskEnv
from langgap.vocabulary import Stepping

TARGET = 2.0  # a control step at most twice the raw physics of its substeps
STEPPING_LABELS = {
    Stepping.EXACT: f"LangGap `{Stepping.EXACT}` (bit-identical)",
    Stepping.FAST: f"LangGap `{Stepping.FAST}` (last bits differ)",
    Stepping.ROBOSUITE: "robosuite's own",
}


def _actions(steps: int) -> list[np.ndarray]:
    """A fixed back-and-forth reach with the gripper closing halfway: contacts, joints, gripper."""
    rng = np.random.default_rng(0)
    return [np.concatenate([rng.uniform(-0.5, 0.5, 6), [1.0 if k > steps // 2 else -1.0]]) for k in range(steps)]


def _time_env_steps(env: TaskEnv, actions: list[np.ndarray], init: int) -> float:
    env.reset(init)
    start = time.perf_counter()
    for action in actions:
        env.step(action)
    return (time.perf_counter() - start) / len(actions)


def _time_raw_steps(model, data, substeps: int, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps * substeps):
        mujoco.mj_step(model, data)
    return (time.perf_counter() - start) / steps


def compare_steps(task, steps: int, rounds: int) -> dict[str, float]:
    """Median seconds per control step of raw physics and of each stepping."""
    actions = _actions(steps)
    envs = {stepping: TaskEnv(task, EnvOptions(stepping=stepping)) for stepping in Stepping}
    try:
        inner = envs[Stepping.EXACT].robosuite_env
        substeps = int(round(inner.control_timestep / inner.model_timestep))
        envs[Stepping.EXACT].reset(0)
        for action in actions[: steps // 2]:  # mid-episode: the arm moving, controls set
            envs[Stepping.EXACT].step(action)
        model, mid = inner.sim.model._model, copy.copy(inner.sim.data._data)
        for env in envs.values():  # warm up (the fast stepping's compiled controller loads here)
            _time_env_steps(env, actions[:2], 0)
        times: dict[str, list[float]] = {"raw": [], **{stepping: [] for stepping in envs}}
        for r in range(rounds):
            times["raw"].append(_time_raw_steps(model, copy.copy(mid), substeps, steps))
            for stepping, env in envs.items():
                times[stepping].append(_time_env_steps(env, actions, r))
    finally:
        for env in envs.values():
            env.close()
    return {name: statistics.median(values) for name, values in times.items()}


# where an oracle episode's time goes: the cumulative time of each entry point (they do not nest)
_ENTRY_POINTS = (
    ("environment step (physics, control)", "langgap/sim/stepping.py", "__call__"),
    ("goal checks (the task's and every scene goal)", "langgap/sim/env.py", "goal_holds"),
    ("observation (incl. privileged state)", "langgap/sim/env.py", "observe"),
    ("oracle planning", "langgap/policies/oracle/policy.py", "act"),
)


def profile_episode(task, catalog, stepping: str) -> tuple[int, float, dict[str, float]]:
    """Steps, seconds per step and each entry point's share of one oracle episode (cProfile)."""
    policy = make_policy("oracle", {})
    watch = scene_goals(task, catalog)
    with TaskEnv(task, env_options_for(policy, stepping=stepping)) as env:
        run_episode(env, policy, task_context(task, catalog, init_index=1, seed=0), watch=watch)  # warm up
        profiler = cProfile.Profile()
        profiler.enable()
        result = run_episode(env, policy, task_context(task, catalog, init_index=0, seed=0), watch=watch)
        profiler.disable()
    stats = pstats.Stats(profiler)
    total = stats.total_tt
    shares = {}
    for name, filename, function in _ENTRY_POINTS:
        shares[name] = sum(
            cumulative
            for (file, _line, func), (_calls, _prim, _own, cumulative, _callers) in stats.stats.items()
            if file.endswith(filename) and func == function
        )
    mujoco_time = sum(
        own for (file, _line, func), (_c, _p, own, _cum, _callers) in stats.stats.items() if "mujoco._functions" in func
    )
    shares["harness and the rest"] = total - sum(shares.values())
    shares["of all: MuJoCo's own functions"] = mujoco_time
    return result.steps, total / max(result.steps, 1), {name: t / total for name, t in shares.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="spatial/s0/black-bowl-1-on-plate")
    parser.add_argument("--steps", type=int, default=60, help="control steps per timed round")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--no-profile", action="store_true", help="skip the profiled oracle episode")
    args = parser.parse_args()
    catalog = load_catalog()
    task = catalog.get(args.task)
    t = compare_steps(task, args.steps, args.rounds)
    print(f"task {task.id}: {args.steps} control steps x {args.rounds} interleaved rounds, medians, no rendering")
    print("| stepping | ms per control step | vs raw physics | target |")
    print("|---|---|---|---|")
    print(f"| raw physics (25 mj_step) | {t['raw'] * 1e3:.2f} | 1.00x | |")
    for stepping in Stepping:
        target = f"≤ {TARGET:.1f}x" if stepping == Stepping.FAST else ""
        print(f"| {STEPPING_LABELS[stepping]} | {t[stepping] * 1e3:.2f} | {t[stepping] / t['raw']:.2f}x | {target} |")
    for stepping in (Stepping.EXACT, Stepping.FAST):
        print(f"{stepping} vs robosuite's own: {t[Stepping.ROBOSUITE] / t[stepping]:.2f}x faster")
    if args.no_profile:
        return
    profiles = {stepping: profile_episode(task, catalog, stepping) for stepping in (Stepping.EXACT, Stepping.FAST)}
    print("\noracle episode (init 0) under cProfile, all in: where a step's time goes")
    print("| where | " + " | ".join(f"`{s}` stepping" for s in profiles) + " |")
    print("|---|" + "---|" * len(profiles))
    steps = " | ".join(f"{p[0]} steps, {p[1] * 1e3:.1f} ms/step" for p in profiles.values())
    print(f"| episode | {steps} |")
    for name in profiles[Stepping.EXACT][2]:
        print(f"| {name} | " + " | ".join(f"{p[2][name]:.0%}" for p in profiles.values()) + " |")


if __name__ == "__main__":
    main()
