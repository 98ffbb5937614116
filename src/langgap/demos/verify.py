"""`verify-demos`: replay each demonstration's actions from its start and check the task succeeds."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.demos.compact import demo_files, load_demo, read_manifest
from langgap.demos.record import Demo, start_episode
from langgap.errors import LangGapError, SimulationError
from langgap.sim.env import TaskEnv


@dataclass(frozen=True)
class Verdict:
    """One demonstration's replay: `ok` when its actions reach the goal at its last step, and not earlier."""

    path: str
    task_id: str
    seed: int
    steps: int
    success_step: int | None  # first step at which the goal held (None: never)
    error: str = ""

    @property
    def ok(self) -> bool:
        return not self.error and self.success_step == self.steps


def verify_demo(env: TaskEnv, path: Path) -> Verdict:
    """Replay the demonstration in `path` open-loop on `env` (built for its task)."""
    try:
        demo = load_demo(path)
    except LangGapError as exc:
        return Verdict(str(path), "?", -1, 0, None, str(exc))
    return replay_demo(env, demo, path=str(path))


def replay_demo(env: TaskEnv, demo: Demo, *, path: str = "") -> Verdict:
    """Replay `demo`'s actions open-loop on `env` (built for its task) from its recorded start and scene.

    Only what a replay needs is read (`actions`, `states[0]`, `body_pos`/`body_quat`, `scene_hash`), so a
    `Demo` rebuilt from another form of the demonstration (e.g. an exported HDF5 file) is checked the same way.
    """
    common = dict(path=path, task_id=demo.task_id, seed=demo.seed, steps=demo.length)
    try:
        start_episode(env, demo)
    except SimulationError as exc:
        return Verdict(**common, success_step=None, error=str(exc))
    for step, action in enumerate(demo.actions, start=1):
        if not np.all(np.isfinite(action)) or np.abs(action).max() > 1.0:
            return Verdict(**common, success_step=None, error=f"action {step} is not in [-1, 1]")
        if env.step(action):
            return Verdict(**common, success_step=step)
    return Verdict(**common, success_step=None)


def verify_collection(root: str | Path) -> list[Verdict]:
    """Replay every demonstration of a collection; one env per task."""
    root = Path(root)
    catalog = load_catalog(read_manifest(root)["catalog"])
    verdicts: list[Verdict] = []
    env: TaskEnv | None = None
    try:
        for path in demo_files(root):
            task_id = path.parent.relative_to(root / "demos").as_posix()
            if env is None or env.task.id != task_id:
                if env is not None:
                    env.close()
                env = TaskEnv(catalog.get(task_id))
            verdicts.append(verify_demo(env, path))
    finally:
        if env is not None:
            env.close()
    return verdicts
