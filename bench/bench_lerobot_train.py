"""LeRobot fine-tuning on this machine at tiny size: seconds per `lerobot-train` step of the tiny ACT and the tiny
SmolVLA that `langgap experiment run --tiny` rehearses with, measured side by side on one dataset.

Each policy trains twice on the same LeRobot dataset (a LangGap export), for `--short` and for `--long` steps
(saving only at the end), and the time per step is the difference of the two wall times over the difference of
the steps: process start, imports, dataset loading and the checkpoint cancel out. It prints each policy's
per-step time, its start-up cost, and their ratio. A GPU user measures the real policies the same way
(`langgap experiment run … --steps N` twice), since a CPU figure says nothing of a GPU's.

    .venv-lerobot/bin/python bench/bench_lerobot_train.py --dataset DIR/lerobot [--short 2] [--long 22]
        [--batch-size 8] [--threads 2]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time
from pathlib import Path

from langgap.training.lerobot_train import (
    lerobot_train_executable,
    load_experiment,
    load_recipe,
    train_command,
    train_options,
)


def _train_seconds(policy: str, dataset: Path, steps: int, batch: int, threads: int, work: Path) -> float:
    """Wall seconds of one `lerobot-train` run of the tiny `policy` for `steps` steps."""
    out = work / f"{policy}-{steps}"
    tiny = {"tiny_vlm": str(work / "tiny-smolvlm"), "image_size": "64"}
    options = train_options(
        load_experiment("exp1"),
        load_recipe(policy),
        tiny=tiny,
        overrides={"steps": str(steps), "batch_size": str(batch), "save_freq": str(steps), "num_workers": "0"},
    )
    options["policy.device"] = "cpu"
    command = train_command(
        options, dataset_root=str(dataset), repo_id="local/bench", output_dir=str(out), job_name=policy
    )
    command[0] = lerobot_train_executable()
    env = {**os.environ, "OMP_NUM_THREADS": str(threads)}
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env=env)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", required=True, type=Path, help="a LeRobot dataset at 64 px (export-lerobot)")
    parser.add_argument("--short", type=int, default=2)
    parser.add_argument("--long", type=int, default=22)
    parser.add_argument("--batch-size", type=int, default=8)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        subprocess.run(
            [
                Path(lerobot_train_executable()).parent / "langgap",
                "experiment",
                "tiny-smolvlm",
                str(work / "tiny-smolvlm"),
            ],
            check=True,
            capture_output=True,
        )
        per_step = {}
        for policy in ("act", "smolvla"):
            short = _train_seconds(policy, args.dataset, args.short, args.batch_size, args.threads, work)
            long = _train_seconds(policy, args.dataset, args.long, args.batch_size, args.threads, work)
            per_step[policy] = (long - short) / (args.long - args.short)
            startup = short - args.short * per_step[policy]
            print(
                f"tiny {policy}, batch {args.batch_size}, {args.threads} thread(s): "
                f"{per_step[policy] * 1000:.0f} ms/step ({args.short} steps {short:.1f}s, {args.long} steps "
                f"{long:.1f}s; start-up and checkpoint {startup:.1f}s)"
            )
    print(f"smolvla/act per step: {per_step['smolvla'] / per_step['act']:.2f}x")


if __name__ == "__main__":
    main()
