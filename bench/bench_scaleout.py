"""Scale-out: the Ray backend's overhead and the shared policy's batching gain, side by side in one run.

    .venv/bin/python bench/bench_scaleout.py ray-overhead [--workers 2] [--policy noop]
    .venv/bin/python bench/bench_scaleout.py batching [--workers 2] [--delay-ms 100] [--episodes 2]
    .venv/bin/python bench/bench_scaleout.py local-batching [--delay-ms 100] [--episodes 4] [--step-ms S] \
        [--worker-counts 1,2,4] [--batches 1,2,4]

Run Ray benchmarks inside a loopback-only network namespace on shared machines, e.g.
`unshare -n sh -c 'ip link set lo up; .venv/bin/python bench/bench_scaleout.py batching'`.

`local-batching` runs the local backend's shared policy (`--backend local --shared-policy`) with
`delay`, a policy whose latency is fixed per batched call (a GPU's nearly is), for every number of
workers and batch limit, and prints episodes/hour beside a model of the pipeline and, from the
environment's cost per step measured here, a projection for a bigger machine with one GPU.
"""

from __future__ import annotations

import argparse
import os

from bench_harness import SAMPLE_TASKS as TASKS
from bench_harness import TimedRun, timed_eval, timed_run

# 220 steps: `noop` and `delay` never succeed, so every episode runs the whole step limit.
BATCH_TASK = "spatial/s0/black-bowl-1-on-plate"
# The projection's assumptions (docs/performance.md, "Projection"): a 16-core box with one H100 running a VLA that
# is queried every step, as in vla-eval's published run (DB-CogACT 7B, LIBERO-Spatial, 50 shards,
# batches of 16: ~486 observations/s, 2,000 episodes in ~18 min, i.e. ~262 queries per episode).
PROJECTED_CORES = 16
PROJECTED_BATCH_MS = 30.0  # one forward pass of a batch of up to 16 (486 obs/s at B=16 bounds it by 33 ms)
PROJECTED_RENDER_MS = 5.0  # two 256x256 cameras per step rendered by the GPU through EGL (not measured here)
PROJECTED_STEPS = 262  # queries (= steps) per episode, from vla-eval's own figures


def ray_overhead(workers: int, policy: str, episodes: int) -> None:
    local, summary = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers)
    on_ray, _ = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers, backend="ray")
    print(
        f"| {policy}, {summary.ran} episodes, {workers} workers | local {local:.1f} s | Ray {on_ray:.1f} s | "
        f"Ray overhead {100 * (on_ray / local - 1):+.1f} % |"
    )


def batching(workers: int, delay_ms: float, episodes: int) -> None:
    results = {}
    for max_batch in (1, workers):
        results[max_batch] = timed_eval(
            policy="delay",
            policy_args={"delay_ms": str(delay_ms)},
            tasks=TASKS,
            episodes=episodes,
            backend="ray",
            workers=workers,
            shared_policy=True,
            max_batch=max_batch,
            max_wait_ms=delay_ms / 2,
        )
    (one, one_run), (many, many_run) = results[1], results[workers]
    print(
        f"| shared policy, {delay_ms:.0f} ms per call, {workers} env actors, {one_run.ran} episodes, "
        f"{one_run.policy_server['queries']} queries | one query per call: {one:.1f} s, "
        f"{one_run.policy_server['calls']} calls | batched (<= {workers}): {many:.1f} s, "
        f"{many_run.policy_server['calls']} calls | gain {one / many:.2f}x |"
    )


def steady_episodes_per_hour(run: TimedRun) -> float:
    """Episodes/hour with start-up (processes, environments, the policy) left out: each worker runs its
    episodes back to back, so the run lasts as long as its busiest worker's episodes."""
    return 3600 * len(run.records) / max(run.busy_s.values())


def pipeline_steps_per_s(workers: int, max_batch: int, cores: int, step_s: float, batch_s: float, wait_s: float):
    """The model: a worker's cycle is its environment step (the workers share the cores) and its query.
    With `max_batch` >= workers every query of a cycle joins one call (waiting `wait_s` when the batch
    cannot fill); otherwise at most `max_batch` queries per call of `batch_s` (the policy's bound)."""
    stepping = step_s * max(1.0, workers / cores)
    if max_batch > workers:
        return workers / (stepping + wait_s + batch_s)
    return min(workers / (stepping + batch_s), max_batch / batch_s)


def local_batching(
    delay_ms: float,
    episodes: int,
    max_wait_ms: float,
    worker_counts: list[int],
    batches: list[int],
    projected_step_ms: float | None,
) -> None:
    cores = os.cpu_count() or 1
    baseline = timed_run(policy="noop", tasks=BATCH_TASK, episodes=episodes, workers=1).records
    step_s = sum(r.wall_time_s for r in baseline) / sum(r.steps for r in baseline)
    steps = round(sum(r.steps for r in baseline) / len(baseline))
    print(
        f"environment alone (noop in its worker): {1000 * step_s:.1f} ms per step, {steps} steps per episode; "
        f"policy: {delay_ms:g} ms per batched call, queries wait up to {max_wait_ms:g} ms; {episodes} episodes "
        f"of {BATCH_TASK} per configuration; {cores} cores"
    )
    print("| workers | max batch | mean batch | episodes/h | vs the first row | model | wall, with start-up |")
    print("|---|---|---|---|---|---|---|")
    reference = None
    for workers in worker_counts:
        for max_batch in batches:
            run = timed_run(
                policy="delay",
                policy_args={"delay_ms": str(delay_ms)},
                tasks=BATCH_TASK,
                episodes=episodes,
                workers=workers,
                shared_policy=True,
                max_batch=max_batch,
                max_wait_ms=max_wait_ms,
            )
            seconds, summary = run.wall_s, run.summary
            rate = steady_episodes_per_hour(run)
            reference = reference or rate
            served = summary.policy_server
            model = pipeline_steps_per_s(workers, max_batch, cores, step_s, delay_ms / 1000, max_wait_ms / 1000)
            print(
                f"| {workers} | {max_batch} | {served['queries'] / served['calls']:.2f} | {rate:.0f} | "
                f"{rate / reference:.2f}x | {3600 * model / steps:.0f} | {seconds:.0f} s |"
            )
    # A shared machine's load slows its steps: the projection can take an idle core's figure instead.
    core_s = step_s if projected_step_ms is None else projected_step_ms / 1000
    render_s, batch_s = PROJECTED_RENDER_MS / 1000, PROJECTED_BATCH_MS / 1000
    projected = 3600 * pipeline_steps_per_s(
        PROJECTED_CORES, PROJECTED_CORES, PROJECTED_CORES, core_s + render_s, batch_s, wait_s=0.0
    )
    projected /= PROJECTED_STEPS
    print(
        f"projection, {PROJECTED_CORES} cores + one GPU ({PROJECTED_CORES} workers, environment {1000 * core_s:.1f} ms "
        f"+ rendering {PROJECTED_RENDER_MS:g} ms per step, batches of {PROJECTED_CORES} in {PROJECTED_BATCH_MS:g} ms, "
        f"{PROJECTED_STEPS} steps per episode): {projected:.0f} episodes/h, 2,000 episodes in "
        f"{60 * 2000 / projected:.0f} min"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("ray-overhead", "batching", "local-batching"))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--policy", default="noop")
    parser.add_argument("--episodes", type=int, default=2)
    parser.add_argument("--delay-ms", type=float, default=100.0, help="the policy's latency per (batched) call")
    parser.add_argument("--max-wait-ms", type=float, help="local-batching: a query's wait (default: half the delay)")
    parser.add_argument("--worker-counts", default="1,2,4", help="local-batching: worker counts to measure")
    parser.add_argument("--batches", default="1,2,4", help="local-batching: batch limits to measure")
    parser.add_argument("--step-ms", type=float, help="local-batching: a core's ms per step for the projection")
    args = parser.parse_args()
    if args.what == "ray-overhead":
        ray_overhead(args.workers, args.policy, args.episodes)
    elif args.what == "batching":
        batching(args.workers, args.delay_ms, args.episodes)
    else:
        local_batching(
            args.delay_ms,
            args.episodes,
            args.delay_ms / 2 if args.max_wait_ms is None else args.max_wait_ms,
            [int(n) for n in args.worker_counts.split(",")],
            [int(n) for n in args.batches.split(",")],
            args.step_ms,
        )


if __name__ == "__main__":
    main()
