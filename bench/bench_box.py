"""A VLA-shaped load: what a step costs where users run LangGap, beside what the machine can do at best.

The policy asks for both cameras every `replan` steps, as a VLA does (openpi re-plans every 5 steps), and returns
chunks of stored oracle actions: no planning in the loop, so what is timed is LangGap and the simulator. The
actions are the oracle's own episodes, recorded once per (task, init state) and kept in `--cache`; replayed, every
episode is the oracle's, whatever the worker count or `replan` (the records are compared: any difference is
printed and fails the run).

For each `replan` and worker count it runs a real evaluation (`langgap.engine.evaluate`, worker processes, a
real store) and prints steps/s, episodes/h and where a step's time goes, measured inside every worker by timers
around the functions that do each part (each is timed exclusive of the parts nested in it):
physics (MuJoCo's `mj_*` calls of the stepping), the arm's controller and robosuite's step loop, render (MuJoCo's
offscreen render and read-back), image copy and flip, observation assembly, the policy call, goal watching,
episode start (reset, init state), the store (in the driver) and the rest of the harness. Beside them, the
machine's own ceilings, each measured in 1 and in N processes at once: raw physics (`mj_step` x 25 from a
mid-episode state), render alone (both cameras), and the two together.

It runs unchanged on any machine: software GL (llvmpipe) here, EGL on a GPU box (MUJOCO_GL decides).

    .venv/bin/python bench/bench_box.py [--episodes 2] [--workers 1,2] [--replan 5,1] [--size 256]
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import multiprocessing as mp
import os
import statistics
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from langgap import stack
from langgap.policies.base import PolicySpec, TaskContext
from langgap.sim.env import CAMERAS, Observation

SCENE = "spatial/s0"
# the scene's pick-and-place tasks (its 13th opens a drawer)
DEFAULT_TASKS = ",".join(
    f"{SCENE}/{name}"
    for name in (
        "black-bowl-1-on-plate",
        "black-bowl-2-on-plate",
        "black-bowl-1-on-stove",
        "black-bowl-1-on-cabinet-top",
        "ramekin-on-plate",
        "ramekin-on-cabinet-top",
        "cookie-box-on-plate",
        "cookie-box-on-cabinet-top",
        "ramekin-on-stove",
        "ramekin-on-cookie-box",
        "cookie-box-on-stove",
        "cookie-box-on-ramekin",
    )
)
POLICY = "bench.bench_box:StoredChunks"
PROBE_ENV = "LANGGAP_BENCH_PROBE"  # a folder: every process that builds the policy writes its timers there
CEILING_SECONDS = 4.0  # how long each ceiling loop runs in each process
TARGET_OVERHEAD = 1.25  # all-in per step at 1 worker vs (physics + render)
TARGET_SCALING = 0.9  # N workers vs the machine's N-process ceiling
# the MuJoCo calls of a control step's physics (LangGap's steppings and robosuite's own)
PHYSICS = (
    "mj_forward", "mj_forwardSkip", "mj_checkPos", "mj_checkVel", "mj_checkAcc", "mj_Euler", "mj_implicit", "mj_step",
    "mj_fwdPosition", "mj_fwdVelocity", "mj_sensorPos", "mj_sensorVel",
)  # fmt: skip

# -- the policy --------------------------------------------------------------------------------


class StoredChunks:
    """A VLA-shaped policy: both cameras every `replan` steps, chunks of the oracle's stored actions.

    The episode's actions are found by its instruction and init state (what a policy is told) in `actions`,
    an .npz that `record_actions` wrote."""

    def __init__(self, actions: str = "", replan: int = 5, size: int = 256):
        with np.load(actions) as stored:
            self._stored = {key: stored[key] for key in stored.files}
        self.spec = PolicySpec(cameras=CAMERAS, image_size=size, chunk=replan, replan=replan)
        self._episode: np.ndarray | None = None
        self._next = 0
        if os.environ.get(PROBE_ENV):
            Probe.install(Path(os.environ[PROBE_ENV]))

    def reset(self, context: TaskContext) -> None:
        self._episode = self._stored[actions_key(context.instruction, context.init_index)]
        self._next = 0

    def act(self, observation: Observation) -> np.ndarray:
        with Probe.section("policy call"):
            start = self._next
            self._next = min(start + self.spec.replan, len(self._episode))
            if start >= len(self._episode):  # the oracle's episode ended here: the goal holds, nothing is asked
                raise RuntimeError("stored actions ran out: the replayed episode departed from the oracle's")
            return self._episode[start : self._next]

    def close(self) -> None:
        Probe.dump()


def actions_key(instruction: str, init_index: int) -> str:
    """The key of one episode's actions in the stored file."""
    return hashlib.sha256(f"{instruction}\n{init_index}".encode()).hexdigest()[:24]


# -- timers ----------------------------------------------------------------------------------


class Probe:
    """Exclusive-time timers around named functions, in one process (installed once)."""

    folder: Path | None = None
    totals: dict[str, float] = defaultdict(float)
    counts: dict[str, int] = defaultdict(int)
    stack: list[str] = []
    last = 0.0

    @classmethod
    def enter(cls, label: str) -> None:
        now = time.perf_counter()
        if cls.stack:
            cls.totals[cls.stack[-1]] += now - cls.last
        cls.stack.append(label)
        cls.counts[label] += 1
        cls.last = now

    @classmethod
    def leave(cls) -> None:
        now = time.perf_counter()
        cls.totals[cls.stack.pop()] += now - cls.last
        cls.last = now

    @classmethod
    @functools.cache
    def section(cls, label: str):
        """A context manager timing its body as `label` (when no probe is installed, it times nothing)."""

        class _Section:
            def __enter__(self):
                if cls.folder is not None and cls.stack:
                    cls.enter(label)
                    self.on = True
                else:
                    self.on = False

            def __exit__(self, *exc):
                if self.on:
                    cls.leave()

        return _Section()

    @classmethod
    def wrap(cls, owner, name: str, label: str, *, outermost: bool = False) -> None:
        """Time `owner.name` as `label`; `outermost`: it starts the timed region (an episode)."""
        function = getattr(owner, name)

        @functools.wraps(function)
        def timed(*args, **kwargs):
            if not cls.stack and not outermost:
                return function(*args, **kwargs)
            if not cls.stack:
                cls.last = time.perf_counter()
            cls.enter(label)
            try:
                return function(*args, **kwargs)
            finally:
                cls.leave()

        setattr(owner, name, timed)

    @classmethod
    def install(cls, folder: Path) -> None:
        """Put the timers around the functions each part of a step runs (see the module's docstring)."""
        if cls.folder is not None:
            return
        cls.folder = folder
        import mujoco
        from robosuite.utils.binding_utils import MjSim

        from langgap.engine import episode, rollout, runner, watch
        from langgap.goals import GoalProgress
        from langgap.sim import env, resting

        cls.wrap(runner, "execute_episode", "harness (the rest)", outermost=True)
        for name in PHYSICS:
            cls.wrap(mujoco, name, "physics")
        cls.wrap(env.TaskEnv, "_step_sim", "controller and robosuite's step loop")
        cls.wrap(MjSim, "render", "render")
        cls.wrap(env.TaskEnv, "_render_now", "image copy and flip")
        cls.wrap(env.TaskEnv, "observe", "observation assembly")
        cls.wrap(rollout, "observation_for", "observation assembly")
        cls.wrap(rollout, "as_action_chunk", "observation assembly")
        cls.wrap(env.TaskEnv, "reset", "episode start (reset, init state)")
        for owner, name in ((env.TaskEnv, "predicate_holds"), (resting.Placements, "observe"),
                            (GoalProgress, "observe"), (watch.SceneWatch, "observe")):  # fmt: skip
            cls.wrap(owner, name, "goal watching")
        cls.wrap(env.TaskEnv, "step", "harness (the rest)")  # its own bookkeeping: counted with the harness
        del episode  # imported so that `runner` has resolved its names before they are wrapped

    @classmethod
    def dump(cls) -> None:
        if cls.folder is not None:
            path = cls.folder / f"worker-{os.getpid()}.json"
            path.write_text(json.dumps({"totals": cls.totals, "counts": cls.counts}))


# -- recording the oracle's actions ------------------------------------------------------------


def record_actions(tasks: str, episodes: int, cache: Path) -> Path:
    """The oracle's actions for every (task, init state) of the plan, recorded once and kept in `cache`."""
    from langgap.catalog.catalog import load_catalog
    from langgap.engine.context import task_context
    from langgap.engine.episode import scene_goals
    from langgap.engine.rollout import env_options_for, run_episode
    from langgap.policies import make_policy
    from langgap.sim.env import TaskEnv

    physics = stack.physics_stack(stack.DEFAULT_STEPPING, stack.DEFAULT_SEED_SCHEME)
    name = hashlib.sha256(json.dumps([tasks, episodes, physics], sort_keys=True).encode()).hexdigest()[:16]
    path = cache / f"oracle-actions-{name}.npz"
    if path.exists():
        return path
    catalog = load_catalog()
    oracle = make_policy("oracle", {})
    stored: dict[str, np.ndarray] = {}
    for task in catalog.select(tasks):
        with TaskEnv(task, env_options_for(oracle)) as env:
            for k in range(episodes):
                actions: list[np.ndarray] = []
                context = task_context(task, catalog, init_index=k, seed=k)
                watch = scene_goals(task, catalog)
                result = run_episode(
                    env, oracle, context, watch=watch, on_step=lambda _e, _s, a, kept=actions: kept.append(a)
                )
                print(f"  recorded {task.id} init {k}: {result.steps} steps, success {result.success}", flush=True)
                stored[actions_key(context.instruction, k)] = np.asarray(actions)
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, **stored)
    return path


# -- the machine's ceilings ----------------------------------------------------------------------


def _ceiling_process(task_id: str, size: int, until: float, seconds: float, out) -> None:
    """In one process: ms per raw physics step (25 mj_step), per render of both cameras, and per both together."""
    import mujoco

    from langgap.catalog.catalog import load_catalog
    from langgap.sim.env import EnvOptions, TaskEnv

    task = load_catalog().get(task_id)
    with TaskEnv(task, EnvOptions(cameras=CAMERAS, image_size=size)) as env:
        env.reset(0, render=False)
        rng = np.random.default_rng(0)
        for _ in range(30):  # mid-episode: the arm moving, contacts and controls set
            env.step(np.concatenate([rng.uniform(-0.5, 0.5, 6), [-1.0]]))
        inner = env.robosuite_env
        substeps = int(round(inner.control_timestep / inner.model_timestep))
        model, data = env.sim.model._model, env.sim.data._data

        def physics() -> None:
            for _ in range(substeps):
                mujoco.mj_step(model, data)

        def render() -> None:
            for camera in CAMERAS:
                env._render_now(camera)

        def both() -> None:
            physics()
            render()

        results = {}
        while time.time() < until:  # every process starts its loops together
            time.sleep(0.001)
        for name, work in (("physics", physics), ("render", render), ("both", both)):
            count, start = 0, time.perf_counter()
            while time.perf_counter() - start < seconds:
                work()
                count += 1
            results[name] = (time.perf_counter() - start) / count
    out.put(results)


def ceilings(task_id: str, size: int, processes: int) -> dict[str, float]:
    """Median ms per step of each ceiling loop over `processes` processes running at once."""
    context = mp.get_context("spawn")
    out = context.Queue()
    until = time.time() + 20.0  # after every process has built its environment
    workers = [
        context.Process(target=_ceiling_process, args=(task_id, size, until, CEILING_SECONDS, out))
        for _ in range(processes)
    ]
    for worker in workers:
        worker.start()
    results = [out.get() for _ in workers]
    for worker in workers:
        worker.join()
    return {name: statistics.median(r[name] for r in results) * 1e3 for name in results[0]}


# -- the timed evaluations -----------------------------------------------------------------------


def timed_eval(actions: Path, tasks: str, episodes: int, replan: int, size: int, workers: int) -> dict:
    """One fresh evaluation with worker processes, timed and probed; its records' identity and the probe's totals."""
    from langgap.engine.evaluate import evaluate
    from langgap.engine.spec import ExecutionOptions, RunSpec
    from langgap.store import RunStore

    policy_args = {"actions": str(actions), "replan": str(replan), "size": str(size)}
    spec = RunSpec.create(POLICY, policy_args=policy_args, tasks=tasks, episodes=episodes)
    with tempfile.TemporaryDirectory() as tmp:
        probe = Path(tmp) / "probe"
        probe.mkdir()
        os.environ[PROBE_ENV] = str(probe)
        store_time = [0.0]
        write = RunStore.write

        def timed_write(self, record) -> None:
            started = time.perf_counter()
            write(self, record)
            store_time[0] += time.perf_counter() - started

        RunStore.write = timed_write
        try:
            start = time.perf_counter()
            evaluate(spec, Path(tmp) / "run", ExecutionOptions(workers=workers, progress=False))
            wall = time.perf_counter() - start
        finally:
            RunStore.write = write
            del os.environ[PROBE_ENV]
        with RunStore.open(Path(tmp) / "run") as store:
            records = store.records()
        totals: dict[str, float] = defaultdict(float)
        counts: dict[str, int] = defaultdict(int)
        for path in probe.glob("worker-*.json"):
            dumped = json.loads(path.read_text())
            for label, seconds in dumped["totals"].items():
                totals[label] += seconds
            for label, count in dumped["counts"].items():
                counts[label] += count
    steps = sum(r.steps for r in records)
    totals["store (driver)"] = store_time[0]
    return {
        "wall": wall,
        "steps": steps,
        "episodes": len(records),
        "in_episodes": sum(r.wall_time_s for r in records),
        "totals": dict(totals),
        "calls": sum(counts.values()),
        **compared(records),
    }


def compared(records: list) -> dict:
    """What `same_records` compares of a run's records: their identity, what every run of one plan must store
    alike whatever its worker count or `replan` (each episode's (task, init state) -> its steps, start state,
    outcome, success and the scene goals it reached, with when), and how many are gaps."""
    identity = {(r.task_id, r.init_index): (r.steps, r.t0_hash, r.outcome, r.success, sorted(r.reached.items()))
                for r in records}  # fmt: skip
    return {"identity": identity, "gaps": sum(r.status != "done" for r in records)}


def same_records(run: dict, reference: dict) -> bool:
    """Whether a timed run (`timed_eval`) stored the records whose identity (`compared`) is `reference`, and no
    gap."""
    return run["identity"] == reference and run["gaps"] == 0


def _probe_cost_per_call() -> float:
    """Seconds one timed call adds (a wrapped no-op, timed)."""
    saved = (Probe.folder, Probe.stack)
    Probe.folder, Probe.stack = Path("."), ["x"]

    class Target:
        def nothing(self) -> None:
            pass

    plain = Target()
    Probe.wrap(Target, "nothing", "y")
    n = 200_000
    start = time.perf_counter()
    for _ in range(n):
        plain.nothing()
    cost = (time.perf_counter() - start) / n
    Probe.folder, Probe.stack = saved
    Probe.totals.clear()
    Probe.counts.clear()
    return cost


# -- main ------------------------------------------------------------------------------------


def _arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=DEFAULT_TASKS, help="a task selection (default: 12 of spatial/s0)")
    parser.add_argument("--episodes", type=int, default=2, help="init states per task (default 2)")
    parser.add_argument("--workers", default="", help="worker counts, comma-separated (default: 1, 2, 4 .. CPUs)")
    parser.add_argument("--replan", default="5,1", help="steps between two queries, comma-separated (default 5,1)")
    parser.add_argument("--size", type=int, default=256, help="camera images' height and width (default 256)")
    parser.add_argument("--cache", default=".bench-cache", help="where the oracle's recorded actions are kept")
    return parser.parse_args()  # fmt: skip


def _print_ceilings(ceiling: dict[int, dict[str, float]], size: int) -> None:
    print(f"\nthe machine's ceilings, ms per step, medians over the processes (both cameras at {size}²):")
    print("| processes at once | raw physics (mj_step x 25) | render alone | both together | steps/s, all processes |")
    print("|---|---|---|---|---|")
    for n, c in ceiling.items():
        print(f"| {n} | {c['physics']:.2f} | {c['render']:.2f} | {c['both']:.2f} | {n * 1e3 / c['both']:.0f} |")


def _print_runs(runs: dict[tuple[int, int], dict], ceiling: dict[int, dict[str, float]]) -> bool:
    """The throughput table; whether every run's records are those of the first."""
    reference = next(iter(runs.values()))["identity"]
    print("| replan | workers | steps/s | episodes/h | ms per step in an episode | all-in vs physics + render "
          "| steps/s vs the machine's ceiling | records |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    identical = True
    for (r, n), run in runs.items():
        same = same_records(run, reference)
        identical &= same
        rate = run["steps"] / run["wall"]
        in_step = run["in_episodes"] / run["steps"] * 1e3
        c = ceiling.get(n)  # measured with as many processes at once as there are workers
        if c is None:
            allin = vs_ceiling = "–"
        else:
            floor = c["physics"] + c["render"] / r  # the policy's images every r steps
            allin, vs_ceiling = f"{in_step / floor:.2f}x", f"{rate / (n * 1e3 / floor):.2f}x"
        per_hour = run["episodes"] / run["wall"] * 3600
        print(f"| {r} | {n} | {rate:.1f} | {per_hour:.0f} | {in_step:.1f} | {allin} | {vs_ceiling} | "
              f"{'identical' if same else 'DIFFER'} |")  # fmt: skip
    print("(physics + render: raw physics + render alone / replan, measured with as many processes as workers)")
    return identical


def _print_breakdown(runs: dict[tuple[int, int], dict], per_call: float) -> None:
    labels = sorted({label for run in runs.values() for label in run["totals"]})
    print("\nwhere a step's time goes, ms per policy step (the timers' own cost is in the harness line):")
    print("| part | " + " | ".join(f"replan {r}, {n} w" for r, n in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for label in [*labels, "the timers' own cost"]:
        cells = []
        for run in runs.values():
            seconds = run["calls"] * per_call if label == "the timers' own cost" else run["totals"].get(label, 0.0)
            cells.append(f"{seconds / run['steps'] * 1e3:.2f}")
        print(f"| {label} | " + " | ".join(cells) + " |")


def main() -> None:
    args = _arguments()
    cpus = os.cpu_count() or 1
    powers = {1, *(2**k for k in range(8) if 2**k <= cpus), cpus}
    counts = [int(n) for n in args.workers.split(",")] if args.workers else sorted(powers)
    replans = [int(r) for r in args.replan.split(",")]
    physics = stack.physics_stack(stack.DEFAULT_STEPPING, stack.DEFAULT_SEED_SCHEME)
    print(f"machine: {cpus} CPUs; MUJOCO_GL={os.environ.get('MUJOCO_GL', 'egl')}; physics {physics}")
    print(f"recording the oracle's actions (kept in {args.cache}) ...", flush=True)
    actions = record_actions(args.tasks, args.episodes, Path(args.cache))
    first_task = args.tasks.split(",")[0]
    ceiling = {n: ceilings(first_task, args.size, n) for n in sorted({1, *counts})}
    _print_ceilings(ceiling, args.size)
    per_call = _probe_cost_per_call()
    runs = {(r, n): timed_eval(actions, args.tasks, args.episodes, r, args.size, n) for r in replans for n in counts}
    episodes = len(next(iter(runs.values()))["identity"])
    print(f"\n{episodes} episodes ({args.tasks.count(',') + 1} tasks x {args.episodes} init states), both cameras at "
          f"{args.size}² every `replan` steps, stored oracle actions:")  # fmt: skip
    identical = _print_runs(runs, ceiling)
    _print_breakdown(runs, per_call)
    print(f"\ntargets: all-in per step <= {TARGET_OVERHEAD}x physics + render at 1 worker; "
          f"N workers >= {TARGET_SCALING}x the machine's N-process ceiling")  # fmt: skip
    if not identical:
        raise SystemExit("error: records differ between runs (see the table)")


if __name__ == "__main__":
    main()
