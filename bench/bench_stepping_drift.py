"""The `fast` stepping against the bit-identical `exact` one: state drift and the oracle's verdicts.

Every (task, init state) pair runs the oracle twice in one worker, once per stepping, same seed, and
compares: success and outcome (what the episode did, from every scene goal), the steps taken, and
the largest difference between the two simulator states (time, qpos, qvel) at steps 1, 10, 50 and
at the end of the shorter episode. Prints the verdicts that changed (the claim is: none), the drift
quantiles, and the wall time of each stepping.

    .venv/bin/python bench/bench_stepping_drift.py [--catalog langgap99] [--inits 5] [--workers 2]
        [--tasks SELECTION] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.engine.episode import scene_goals
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies import make_policy
from langgap.records import classify
from langgap.sim.env import TaskEnv
from langgap.vocabulary import Stepping

CHECKPOINTS = (1, 10, 50)


def _episode(catalog_name: str, task_id: str, init: int, stepping: str) -> dict:
    catalog = load_catalog(catalog_name)
    task = catalog.get(task_id)
    policy = make_policy("oracle", {})
    states: list[np.ndarray] = []
    with TaskEnv(task, replace(env_options_for(policy), stepping=stepping)) as env:
        start = time.perf_counter()
        result = run_episode(
            env,
            policy,
            task_context(task, catalog, init_index=init, seed=init),
            watch=scene_goals(task, catalog),
            on_step=lambda env_, _step, _action: states.append(env_.sim_state().copy()),
        )
        seconds = time.perf_counter() - start
    outcome = classify(task.id, task.kind, task.source, result.success, result.reached)
    return {"success": result.success, "outcome": str(outcome), "steps": result.steps, "seconds": seconds}, states


def compare(job: tuple[str, str, int]) -> dict:
    """One task and init state under both steppings."""
    catalog_name, task_id, init = job
    exact, exact_states = _episode(catalog_name, task_id, init, Stepping.EXACT)
    fast, fast_states = _episode(catalog_name, task_id, init, Stepping.FAST)
    n = min(len(exact_states), len(fast_states))
    drift = np.abs(np.array(exact_states[:n]) - np.array(fast_states[:n])).max(axis=1) if n else np.zeros(1)
    return {
        "task": task_id,
        "init": init,
        Stepping.EXACT: exact,
        Stepping.FAST: fast,
        "drift": {str(k): float(drift[k - 1]) for k in CHECKPOINTS if k <= n} | {"end": float(drift[-1])},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--catalog", default="langgap99")
    parser.add_argument("--tasks", default="all", help="task selection (default: all tasks of the catalog)")
    parser.add_argument("--inits", type=int, default=5, help="init states 0..K-1 per task")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", help="write every pair's comparison as JSON")
    args = parser.parse_args()
    tasks = load_catalog(args.catalog).select(args.tasks)
    jobs = [(args.catalog, t.id, k) for t in tasks for k in range(args.inits)]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(compare, jobs))
    wall = time.perf_counter() - start
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f, indent=1)
    changed = [
        r
        for r in rows
        if (r[Stepping.EXACT]["success"], r[Stepping.EXACT]["outcome"])
        != (r[Stepping.FAST]["success"], r[Stepping.FAST]["outcome"])
    ]
    print(f"{len(tasks)} tasks x {args.inits} init states = {len(rows)} pairs, oracle, {wall / 60:.1f} min")
    for stepping in (Stepping.EXACT, Stepping.FAST):
        wins = sum(r[stepping]["success"] for r in rows)
        seconds = sum(r[stepping]["seconds"] for r in rows)
        steps = sum(r[stepping]["steps"] for r in rows)
        print(f"{stepping}: {wins}/{len(rows)} successes, {seconds / steps * 1e3:.1f} ms per step all in")
    exact_s = sum(r[Stepping.EXACT]["seconds"] for r in rows)
    fast_s = sum(r[Stepping.FAST]["seconds"] for r in rows)
    print(f"{Stepping.FAST} vs {Stepping.EXACT}, whole episodes: {exact_s / fast_s:.2f}x")
    same_steps = sum(r[Stepping.EXACT]["steps"] == r[Stepping.FAST]["steps"] for r in rows)
    print(f"verdicts changed (success or outcome): {len(changed)}; same step count: {same_steps}/{len(rows)}")
    for r in changed:
        e, f = r[Stepping.EXACT], r[Stepping.FAST]
        print(
            f"  {r['task']} init {r['init']}: {Stepping.EXACT} {e['outcome']} in {e['steps']}, "
            f"{Stepping.FAST} {f['outcome']} in {f['steps']}"
        )
    print("| state drift (max abs over time, qpos, qvel) | median | 90th pct | max |")
    print("|---|---|---|---|")
    for point in [str(k) for k in CHECKPOINTS] + ["end"]:
        values = np.array([r["drift"][point] for r in rows if point in r["drift"]])
        if len(values):
            q50, q90, top = np.quantile(values, 0.5), np.quantile(values, 0.9), values.max()
            label = f"after step {point}" if point != "end" else "at the end of the shorter episode"
            print(f"| {label} | {q50:.2e} | {q90:.2e} | {top:.2e} |")


if __name__ == "__main__":
    main()
