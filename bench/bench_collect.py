"""Demonstration throughput: demos per hour per core, for the compact form and for the LeRobot rendering.

Collects `--demos` demonstrations of each task in this process (one core), then, if LeRobot is
installed, renders them as `langgap collect` does for its LeRobot dataset. Prints demos/hour/core and
what the paper's training split (16 tasks x 150 demonstrations) would take on one core.

    .venv/bin/python bench/bench_collect.py [--tasks SELECTION] [--demos N]
    .venv-lerobot/bin/python bench/bench_collect.py      # also measures rendering for the LeRobot form
"""

from __future__ import annotations

import argparse
import tempfile
import time

from langgap.catalog.catalog import load_catalog
from langgap.demos.collect import CollectConfig, collect
from langgap.demos.compact import demo_files
from langgap.demos.export import lerobot_available
from langgap.demos.render import iter_demos
from langgap.engine.spec import ExecutionOptions

PAPER_DEMOS = 16 * 150


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default="spatial/s0/black-bowl-1-on-plate,spatial/s0/black-bowl-1-on-stove")
    parser.add_argument("--demos", type=int, default=3)
    args = parser.parse_args()
    tasks = tuple(t.id for t in load_catalog().select(args.tasks))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        manifest = collect(
            CollectConfig("langgap99", tasks, args.demos), tmp, ExecutionOptions(workers=0, progress=False)
        )
        simulate = time.perf_counter() - start
        kept = sum(len(s["kept"]) for s in manifest["tasks"].values())
        attempts = sum(s["attempts"] for s in manifest["tasks"].values())
        steps = sum(s["steps"] for s in manifest["tasks"].values())
        rate = kept / simulate * 3600
        print(f"simulate (compact form): {kept} demos ({attempts} attempts, {steps} steps) in {simulate:.1f}s")
        print(f"  {rate:.0f} demos/hour/core, {steps / simulate:.0f} steps/s")
        if lerobot_available():
            start = time.perf_counter()
            frames = sum(
                d.length for d, _ in iter_demos("langgap99", demo_files(tmp), render=True, workers=0, progress=False)
            )
            render = time.perf_counter() - start
            print(
                f"render (LeRobot form): {frames} frames x 2 cameras in {render:.1f}s, {frames / render:.1f} frames/s"
            )
            rate = kept / (simulate + render) * 3600
            print(f"  {rate:.0f} demos/hour/core with rendering (video encoding not included)")
        print(f"paper training split ({PAPER_DEMOS} demos): {PAPER_DEMOS / rate:.1f} core-hours")


if __name__ == "__main__":
    main()
