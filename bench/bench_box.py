"""A VLA-shaped load: what a step costs where users run LangGap, beside what the machine can do at best.

The policy asks for both cameras every `replan` steps, as a VLA does (openpi re-plans every 5 steps), and returns
chunks of stored oracle actions: no planning in the loop, so what is timed is LangGap and the simulator. The
actions are the oracle's own episodes, recorded once per (task, init state) and kept in `--cache`; replayed, every
episode is the oracle's, whatever the worker count or `replan` (the records are compared: any difference is
printed and fails the run).

For each `replan` and worker count it runs a real evaluation (`langgap.engine.evaluate`, worker processes, a
real store; `bench_harness.timed_run`) and prints steps/s, episodes/h and where a step's time goes inside
episodes, from the standard library's profiler (cProfile) run in every worker: physics (MuJoCo's `mj_*` calls of the
stepping), the arm's controller and robosuite's step loop, render (MuJoCo's offscreen render and read-back), image
copy and flip, observation assembly, the policy call, goal watching, episode start (reset, init state), the store
(in the driver) and the rest of the harness. Each part starts at named functions (`_parts`). A function's own
time (cProfile's exclusive time) counts with the part of the nearest part-starting function above it, so a part is
exclusive of the parts nested in it; a function called under several parts is divided among them in proportion to
its time under each caller (cProfile keeps callers one level up; further up, the same proportion by inclusive time
is assumed). Time outside episodes (start-up, environment builds) is left out. The profiler slows every Python call
a little: its estimated cost, which the times above include, is the table's last line. Beside them, the machine's
own ceilings, each measured in 1 and in N processes at once (`bench_harness.in_processes`): raw physics
(`mj_step` x 25 from a mid-episode state), render alone (both cameras), and the two together.

It runs unchanged on any machine: software GL (llvmpipe) here, EGL on a GPU box (MUJOCO_GL decides).

    .venv/bin/python bench/bench_box.py [--episodes 2] [--workers 1,2] [--replan 5,1] [--size 256]
"""

from __future__ import annotations

import argparse
import cProfile
import hashlib
import json
import os
import pstats
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
PROFILE_ENV = "LANGGAP_BENCH_PROFILE"  # a folder: every process that builds the policy writes its profile there
HARNESS = "harness (the rest)"
PROFILER_COST = "the profiler's own cost (within the lines above)"
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
        self._profile_folder = os.environ.get(PROFILE_ENV)
        self._profile = cProfile.Profile() if self._profile_folder else None
        if self._profile is not None:  # built in a worker, before its first episode: profile all it runs
            self._profile.enable()

    def reset(self, context: TaskContext) -> None:
        self._episode = self._stored[actions_key(context.instruction, context.init_index)]
        self._next = 0

    def act(self, observation: Observation) -> np.ndarray:
        start = self._next
        self._next = min(start + self.spec.replan, len(self._episode))
        if start >= len(self._episode):  # the oracle's episode ended here: the goal holds, nothing is asked
            raise RuntimeError("stored actions ran out: the replayed episode departed from the oracle's")
        return self._episode[start : self._next]

    def close(self) -> None:
        if self._profile is not None:
            self._profile.disable()
            self._profile.dump_stats(Path(self._profile_folder) / f"worker-{os.getpid()}-{id(self)}.prof")


def actions_key(instruction: str, init_index: int) -> str:
    """The key of one episode's actions in the stored file."""
    return hashlib.sha256(f"{instruction}\n{init_index}".encode()).hexdigest()[:24]


# -- where the time goes ---------------------------------------------------------------------


def _key(function) -> tuple[str, int, str]:
    """cProfile's name of a Python function."""
    code = function.__code__
    return code.co_filename, code.co_firstlineno, code.co_name


def _parts() -> tuple[dict[tuple, str], set[tuple]]:
    """The functions each part of a step starts at (cProfile's names -> the part), and those an episode starts at."""
    from robosuite.utils.binding_utils import MjSim

    from langgap.engine import episode, rollout, watch
    from langgap.goals import GoalProgress
    from langgap.policies import policy_class
    from langgap.sim import env, resting

    episodes = (episode.execute_episode, episode.execute_shared)
    starts = {
        # TaskEnv.step's own bookkeeping counts with the harness
        HARNESS: (*episodes, env.TaskEnv.step),
        "controller and robosuite's step loop": (env.TaskEnv._step_sim,),
        "render": (MjSim.render,),
        "image copy and flip": (env.TaskEnv._render_now,),
        "observation assembly": (env.TaskEnv.observe, rollout.observation_for, rollout.as_action_chunk),
        "episode start (reset, init state)": (env.TaskEnv.reset,),
        "goal watching": (env.TaskEnv.predicate_holds, resting.Placements.observe, GoalProgress.observe,
                          watch.SceneWatch.observe),
        "policy call": (policy_class(POLICY).act,),  # as the workers load it, not as this script's __main__
    }  # fmt: skip
    parts = {_key(function): part for part, functions in starts.items() for function in functions}
    parts |= {("~", 0, f"<built-in method mujoco._functions.{name}>"): "physics" for name in PHYSICS}
    return parts, {_key(function) for function in episodes}


def attribute(stats: dict, parts: dict[tuple, str], episodes: set[tuple]) -> tuple[dict[str, float], float]:
    """Seconds of each part inside episodes in cProfile's `stats` (see the module's docstring), and how many calls
    were profiled inside episodes."""
    shares: dict[tuple, dict[str, float]] = {}

    def under(function: tuple) -> dict[str, float]:
        """How `function`'s time divides over the parts it ran under inside episodes (the rest ran outside)."""
        if function in shares:
            return shares[function]
        shares[function] = {}  # a cycle of calls: what loops back adds nothing
        part = parts.get(function)
        if function in episodes:
            found = {part: 1.0}
        else:
            callers = stats[function][4] if function in stats else {}
            weights = {caller: edge[3] for caller, edge in callers.items()}
            if not sum(weights.values()):
                weights = {caller: edge[1] for caller, edge in callers.items()}
            total = sum(weights.values())
            found = defaultdict(float)
            for caller, weight in weights.items():
                for above, share in under(caller).items():
                    found[above] += share * weight / total
            if part is not None:
                found = {part: sum(found.values())}
        shares[function] = dict(found)
        return shares[function]

    seconds: dict[str, float] = defaultdict(float)
    calls = 0.0
    for function, (_, count, own, _, _) in stats.items():
        split = under(function)
        calls += count * sum(split.values())
        for part, share in split.items():
            seconds[part] += own * share
    return dict(seconds), calls


def _profiler_cost_per_call() -> float:
    """Seconds the profiler adds to one call (a no-op called in a loop, with and without it)."""

    def nothing() -> None:
        pass

    def calls() -> None:
        for _ in range(200_000):
            nothing()

    start = time.perf_counter()
    calls()
    plain = time.perf_counter() - start
    start = time.perf_counter()
    cProfile.Profile().runcall(calls)
    return max(0.0, time.perf_counter() - start - plain) / 200_000


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


def _ceiling_process(task_id: str, size: int, until: float, seconds: float) -> dict[str, float]:
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
    return results


def ceilings(task_id: str, size: int, processes: int) -> dict[str, float]:
    """Median ms per step of each ceiling loop over `processes` processes running at once."""
    from bench_harness import in_processes  # bench/ is on the path when this file runs as a script

    until = time.time() + 20.0  # after every process has built its environment
    results = in_processes(_ceiling_process, (task_id, size, until, CEILING_SECONDS), processes)
    return {name: statistics.median(r[name] for r in results) * 1e3 for name in results[0]}


# -- the timed evaluations -----------------------------------------------------------------------


def timed_eval(actions: Path, tasks: str, episodes: int, replan: int, size: int, workers: int) -> dict:
    """One fresh evaluation with worker processes, timed and profiled; its records' identity and each part's time."""
    from bench_harness import timed_run  # bench/ is on the path when this file runs as a script

    from langgap.store import RunStore

    policy_args = {"actions": str(actions), "replan": str(replan), "size": str(size)}
    driver = cProfile.Profile()
    with tempfile.TemporaryDirectory() as profiles:
        os.environ[PROFILE_ENV] = profiles
        try:
            run = driver.runcall(timed_run, POLICY, tasks, episodes, policy_args, workers=workers)
        finally:
            del os.environ[PROFILE_ENV]
        found = [str(path) for path in Path(profiles).glob("worker-*.prof")]
        totals, calls = attribute(pstats.Stats(*found).stats if found else {}, *_parts())
    store = pstats.Stats(driver).stats.get(_key(RunStore.write))
    totals["store (driver)"] = store[3] if store else 0.0  # its inclusive time
    records = run.records
    return {
        "wall": run.wall_s,
        "steps": sum(r.steps for r in records),
        "episodes": len(records),
        "in_episodes": sum(run.busy_s.values()),
        "totals": totals,
        "calls": calls,
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
    print("\nwhere a step's time goes inside episodes, ms per policy step (cProfile; see the module's docstring):")
    print("| part | " + " | ".join(f"replan {r}, {n} w" for r, n in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for label in [*labels, PROFILER_COST]:
        cells = []
        for run in runs.values():
            seconds = run["calls"] * per_call if label == PROFILER_COST else run["totals"].get(label, 0.0)
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
    per_call = _profiler_cost_per_call()
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
