"""Oracle speed and success: episodes per hour per core (no rendering) and steps per task.

By default a fixed small sample (one task per suite and per skill) over init states 0-2 in one
process, the speed measurement. `--tasks all --inits 0-9` (optionally `--jobs 2`) is the success
sweep of the whole catalog; `--json PATH` also writes every episode.

    .venv/bin/python bench/bench_oracle.py [--tasks SELECTION] [--inits 0-2] [--jobs 1] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import time

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies import make_policy
from langgap.sim.env import TaskEnv

SAMPLE = ",".join(
    [
        "spatial/s0/black-bowl-1-on-plate",
        "spatial/s0/cookie-box-on-cabinet-top",
        "object/s0/alphabet-soup-in-basket",
        "goal/s0/open-cabinet-middle-drawer",
        "goal/s7/turn-on-stove",
        "libero10/s0/alphabet-soup-in-basket+tomato-sauce-in-basket",
    ]
)


def parse_inits(text: str) -> list[int]:
    """`0-9` or `0,3,5` -> init indices."""
    if "-" in text:
        first, last = (int(part) for part in text.split("-"))
        return list(range(first, last + 1))
    return [int(part) for part in text.split(",")]


def run_task(job: tuple[str, str, list[int], int]) -> dict:
    """All episodes of one task in one environment (soft resets): outcomes, steps and wall time."""
    catalog_name, task_id, inits, seed = job
    catalog = load_catalog(catalog_name)
    task = catalog.get(task_id)
    policy = make_policy("oracle")
    episodes = []
    with TaskEnv(task, env_options_for(policy)) as env:
        for init in inits:
            start = time.perf_counter()
            result = run_episode(env, policy, task_context(task, catalog, init_index=init, seed=seed))
            episodes.append(
                {"init": init, "success": result.success, "steps": result.steps, "seconds": time.perf_counter() - start}
            )
    return {"task": task_id, "max_steps": task.max_steps, "episodes": episodes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--catalog", default="langgap99")
    parser.add_argument("--tasks", default=SAMPLE, help="a task selection (default: a fixed sample)")
    parser.add_argument("--inits", default="0-2", help="init states, e.g. 0-9 or 0,5,7")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (one task at a time each)")
    parser.add_argument("--json", help="write every episode to this file")
    args = parser.parse_args()

    tasks = load_catalog(args.catalog).select(args.tasks)
    jobs = [(args.catalog, task.id, parse_inits(args.inits), args.seed) for task in tasks]
    started = time.perf_counter()
    if args.jobs > 1:
        with multiprocessing.get_context("spawn").Pool(args.jobs) as pool:
            results = list(pool.imap(run_task, jobs))
    else:
        results = [run_task(job) for job in jobs]
    wall = time.perf_counter() - started

    print(f"{'task':74s} {'success':>9s} {'mean':>6s} {'max':>5s} {'limit':>5s} {'s/ep':>6s}")
    for result in results:
        episodes = result["episodes"]
        steps = [e["steps"] for e in episodes]
        wins = sum(e["success"] for e in episodes)
        seconds = np.mean([e["seconds"] for e in episodes])
        print(
            f"{result['task']:74s} {wins:>4d}/{len(episodes):<4d} {np.mean(steps):6.1f} {max(steps):5d} "
            f"{result['max_steps']:5d} {seconds:6.2f}"
        )
    every = [e for r in results for e in r["episodes"]]
    per_episode = float(np.mean([e["seconds"] for e in every]))
    print(
        f"\n{len(every)} episodes, {sum(e['success'] for e in every)} successes, "
        f"{np.mean([e['steps'] for e in every]):.1f} steps on average; "
        f"{per_episode:.2f} s per episode in a worker = {3600 / per_episode:.0f} episodes per hour per core "
        f"({len(every) / wall * 3600:.0f} per hour with {args.jobs} worker(s), {wall:.0f} s wall)"
    )
    failures = [(r["task"], e["init"], e["steps"]) for r in results for e in r["episodes"] if not e["success"]]
    if failures:
        print("failed episodes (task, init, steps):")
        for failure in failures:
            print("  ", *failure)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump({"args": vars(args), "results": results}, handle, indent=1)


if __name__ == "__main__":
    main()
