"""The demonstration search's budget and hit rate, where the oracle is told not to use what it knows.

On each of the paper's two bottom drawers, the oracle with its pressed drag turned off (`drawer=grasp`:
the oracle before it opened these drawers, 0/50 on both) fails every init state. The search
(`langgap.gate.search`) then tries all of its `--budget` candidates on each of the first `--inits` init
states (no early stop), and this prints, per task: how many candidates did the task (the hit rate),
how many the first hit took (the budget a gate needs), and the wall time per candidate episode; then
which kind of candidate hit (grasp / pressed drag / noise only).

    .venv/bin/python bench/bench_search.py [--inits K] [--budget N] [--stepping exact]
"""

from __future__ import annotations

import argparse
import statistics
import time

from langgap.catalog.catalog import load_catalog
from langgap.engine.plan import episode_seed
from langgap.gate.search import search
from langgap.stack import DEFAULT_STEPPING

TASKS = ("goal/s0/open-cabinet-bottom-drawer", "spatial/s2/open-cabinet-bottom-drawer")
DISABLED = {"drawer": "grasp"}


def kind(args: dict[str, str]) -> str:
    drawer = args.get("drawer", "")
    return "pressed drag" if drawer.startswith("press") else "grasp" if drawer else "noise only (grasp)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--inits", type=int, default=5)
    parser.add_argument("--budget", type=int, default=16)
    parser.add_argument("--stepping", default=DEFAULT_STEPPING)
    args = parser.parse_args()
    catalog = load_catalog("langgap99")
    print("| task | init states | candidates | hits | hit rate | first hit at (median, max) | s / candidate |")
    print("|---|---|---|---|---|---|---|")
    kinds: dict[str, list[int]] = {}
    for task_id in TASKS:
        task = catalog.get(task_id)
        firsts, hits, tried, started = [], 0, 0, time.perf_counter()
        for init in range(args.inits):
            result = search(task, catalog, init_index=init, seed=episode_seed(0, init), stepping=args.stepping,
                            budget=args.budget, stop_at_first=False, oracle_args=DISABLED)  # fmt: skip
            outcomes = [ok for _, ok, _ in result.tried]
            tried += len(outcomes)
            hits += sum(outcomes)
            firsts.append(outcomes.index(True) + 1 if any(outcomes) else args.budget + 1)
            for candidate, ok, _ in result.tried:
                kinds.setdefault(kind(candidate.policy_args), [0, 0])
                kinds[kind(candidate.policy_args)][0] += 1
                kinds[kind(candidate.policy_args)][1] += ok
        per = (time.perf_counter() - started) / max(tried, 1)
        found = sum(f <= args.budget for f in firsts)
        first = f"{statistics.median(firsts):g}, {max(firsts)}" + (
            " (none within the budget on some)" if found < len(firsts) else ""
        )
        print(
            f"| {task_id} | {found}/{args.inits} found | {tried} | {hits} | {hits / tried:.0%} | {first} | {per:.1f} |"
        )
    print()
    print("| candidate kind | tried | hits |")
    print("|---|---|---|")
    for name, (count, ok) in sorted(kinds.items()):
        print(f"| {name} | {count} | {ok} |")


if __name__ == "__main__":
    main()
