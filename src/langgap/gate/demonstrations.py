"""A demonstration that shows a task doable: an episode's actions, replayed open-loop from the plan entry.

The oracle's episodes show a task doable when it does them; where it does not, `langgap.gate.search` looks
for another episode that does, and keeps it here. What makes such an episode evidence is that anyone
can replay it: the same task, init state, seed and stepping, the same actions from the first step, and
LangGap's own judge of the goal after each one. A file (NPZ) holds `actions` (T, 7) and `meta` (JSON:
task, catalog, init state, seed, stepping, the step the goal first held, the instruction, who found it
and with which LangGap and physics stack).
"""

from __future__ import annotations

import io
import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from langgap.atomic import write_bytes_atomically
from langgap.catalog.catalog import Catalog, load_catalog, registry_path
from langgap.catalog.task import Task
from langgap.engine.context import task_context
from langgap.engine.rollout import RolloutResult, run_episode
from langgap.errors import LangGapError
from langgap.policies.base import PolicySpec, TaskContext
from langgap.sim.env import EnvOptions, Observation, TaskEnv

FORMAT_VERSION = 1


class DemonstrationError(LangGapError):
    """A stored demonstration is missing, malformed, or does not do its task when replayed."""


@dataclass(frozen=True)
class Demonstration:
    """One episode that did `task_id` from init state `init_index` with `seed`, as its actions."""

    task_id: str
    catalog: str
    init_index: int
    seed: int
    stepping: str
    steps: int  # the step at which the goal first held (the episode's last)
    instruction: str
    found_by: str  # the policy and its configuration that acted
    made_with: dict  # LangGap's code version and the physics stack
    actions: np.ndarray  # (steps, 7)

    def __post_init__(self) -> None:
        actions = np.asarray(self.actions, dtype=np.float64)
        if actions.shape != (self.steps, 7) or not np.all(np.isfinite(actions)) or np.abs(actions).max() > 1.0:
            raise DemonstrationError(
                f"{self.task_id} init {self.init_index}: actions must be ({self.steps}, 7) in [-1, 1]"
            )
        object.__setattr__(self, "actions", actions)

    def save(self, path: str | Path) -> Path:
        """Write the demonstration to `path` (atomically)."""
        meta = {k: v for k, v in asdict(self).items() if k != "actions"} | {"format": FORMAT_VERSION}
        buffer = io.BytesIO()
        np.savez_compressed(buffer, actions=self.actions, meta=np.array(json.dumps(meta, sort_keys=True)))
        path = Path(path)
        write_bytes_atomically(path, buffer.getvalue())
        return path

    @staticmethod
    def load(path: str | Path) -> Demonstration:
        """Read a demonstration `save` wrote; a missing or malformed file is a DemonstrationError."""
        try:
            with np.load(path, allow_pickle=False) as data:
                meta = json.loads(str(data["meta"]))
                actions = data["actions"]
        except (OSError, KeyError, ValueError) as exc:
            raise DemonstrationError(f"cannot read demonstration {path}: {exc}") from None
        if meta.pop("format", None) != FORMAT_VERSION:
            raise DemonstrationError(f"{path}: not a demonstration of format {FORMAT_VERSION}")
        try:
            return Demonstration(**meta, actions=actions)
        except TypeError as exc:
            raise DemonstrationError(f"{path}: {exc}") from None


class ReplayPolicy:
    """Acts a demonstration's actions in order, seeing nothing (open loop)."""

    spec = PolicySpec()

    def __init__(self, actions: np.ndarray):
        self._actions = actions
        self._next = 0

    def config(self) -> dict:
        return {"actions": len(self._actions)}

    def reset(self, context: TaskContext) -> None:
        self._next = 0

    def act(self, observation: Observation) -> np.ndarray:
        if self._next >= len(self._actions):
            raise DemonstrationError(f"its {len(self._actions)} actions end before the goal holds")
        self._next += 1
        return self._actions[self._next - 1]


def replay(env: TaskEnv, demo: Demonstration, catalog: Catalog) -> RolloutResult:
    """Replay `demo` on `env` (built for its task, with its stepping) from its plan entry, as the gate
    runs episodes: reset to the init state with the seed, settle, then the actions."""
    if env.task.id != demo.task_id or env.options.stepping != demo.stepping:
        raise DemonstrationError(f"{demo.task_id} ({demo.stepping}) cannot be replayed on {env.task.id} "
                                 f"({env.options.stepping})")  # fmt: skip
    context = task_context(env.task, catalog, init_index=demo.init_index, seed=demo.seed)
    policy = ReplayPolicy(demo.actions)
    # Its actions run out before the step limit only if the goal never held: `ReplayPolicy` then raises.
    return run_episode(env, policy, context)


def verify(env: TaskEnv, demo: Demonstration, catalog: Catalog) -> None:
    """Raise DemonstrationError unless `demo` replays to its goal at exactly its recorded step."""
    try:
        result = replay(env, demo, catalog)
    except DemonstrationError as exc:
        raise DemonstrationError(f"{demo.task_id} init {demo.init_index}: the replay fails: {exc}") from None
    if not result.success or result.steps != demo.steps:
        found = f"at step {result.steps}" if result.success else f"not within {result.steps} steps"
        raise DemonstrationError(f"{demo.task_id} init {demo.init_index}: the replay reaches the goal {found}, "
                                 f"the demonstration at step {demo.steps}")  # fmt: skip


def save_verified(demo: Demonstration, path: Path, catalog: Catalog) -> None:
    """Store `demo` at `path` only once the file, read back, replays to its goal at its recorded step (`verify`):
    it is written beside `path` and moved over it, so a DemonstrationError leaves whatever `path` held."""
    written = demo.save(path.with_name(f"{path.stem}.new.npz"))
    try:
        with replay_env(catalog.get(demo.task_id), demo.stepping) as env:
            verify(env, Demonstration.load(written), catalog)
    except DemonstrationError:
        written.unlink()
        raise
    written.replace(path)


def replay_env(task: Task, stepping: str) -> TaskEnv:
    """The cheapest environment a replay needs: nothing rendered, nothing privileged."""
    return TaskEnv(task, EnvOptions(stepping=stepping))


def demonstration_path(directory: str | Path, init_index: int) -> Path:
    """Where the demonstration of init state `init_index` lies in a task's demonstration directory."""
    return Path(directory) / f"init-{init_index:02d}.npz"


def stored_demonstrations(directory: str | Path) -> dict[int, Path]:
    """The demonstrations in a task's directory: init state -> file."""
    directory = Path(directory)
    found = {}
    for path in sorted(directory.glob("init-*.npz")) if directory.is_dir() else []:
        try:
            found[int(path.stem.removeprefix("init-"))] = path
        except ValueError:
            continue
    return found


@dataclass(frozen=True)
class ReplayCheck:
    """One demonstration a verdict rests on, replayed: `error` is empty when it reached its goal at its step."""

    task_id: str  # the task whose verdict names it (for an inherited verdict: the source's)
    init_index: int
    steps: int
    error: str
    catalog: str  # the catalog whose gate made the verdict (a name or registry path)
    path: Path  # the file


def verdict_evidence(task: Task, catalog_name: str) -> tuple[str, str, dict[int, Path]]:
    """The catalog and task whose gate run made `task`'s verdict (its own, or the one it takes by `gate_from`),
    and the demonstration files the verdict names: init state -> file (named whether or not it exists)."""
    gate = task.gate
    maker, _, task_id = gate.inherited_from.partition(":") if gate and gate.inherited_from else ("", "", "")
    maker, task_id = maker or catalog_name, task_id or task.id
    if gate is None or not gate.demonstration:
        return maker, task_id, {}
    directory = registry_path(maker).parent / gate.demonstration
    return maker, task_id, {i: demonstration_path(directory, i) for i in gate.demonstrated_inits}


def replay_verdicts(tasks: list[Task], catalog_name: str):
    """Replay every stored demonstration the verdicts of `tasks` rest on, each once (verdicts taken from one
    source share its files), one environment per task and stepping: yields a `ReplayCheck` per file."""
    named: dict[tuple[str, str], dict[int, Path]] = {}
    for task in tasks:
        maker, task_id, files = verdict_evidence(task, catalog_name)
        if files:
            named[(maker, task_id)] = files
    for (maker, task_id), files in named.items():
        catalog = load_catalog(maker)
        envs: dict[str, TaskEnv] = {}
        try:
            for init_index, path in sorted(files.items()):
                yield _replay_check(catalog, maker, task_id, init_index, path, envs)
        finally:
            for env in envs.values():
                env.close()


def _replay_check(catalog: Catalog, maker: str, task_id: str, init_index: int, path: Path, envs: dict) -> ReplayCheck:
    try:
        demo = Demonstration.load(path)
        if (demo.task_id, demo.init_index) != (task_id, init_index):
            raise DemonstrationError(f"{path} holds {demo.task_id} init {demo.init_index}")
        if demo.stepping not in envs:
            envs[demo.stepping] = replay_env(catalog.get(task_id), demo.stepping)
        verify(envs[demo.stepping], demo, catalog)
    except DemonstrationError as exc:
        error = str(exc).removeprefix(f"{task_id} init {init_index}: ")
        return ReplayCheck(task_id, init_index, 0, error, maker, path)
    return ReplayCheck(task_id, init_index, demo.steps, "", maker, path)
