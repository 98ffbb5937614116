"""The audit's simulator checks of tasks read from packages: each starts from its source's state, and its goal
does not hold at the start.

A task and its source are started from the same init state with the same seed (0), and their t0 state hashes
(`TaskEnv.state_hash`: the MuJoCo state and the fixture placements) compared; after the settle steps, the
task's goal is judged in the state a policy first sees. Tasks whose BDDL files are identical outside
`(:language)` and that load the same init states file share one simulator: LIBERO reads `(:language)` only as
a string, so their starts are the same states (a test builds a language variant's own simulator to show it).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable

from langgap.audit.findings import Finding
from langgap.bddl import strip_sections
from langgap.catalog import files
from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task

SEED = 0


def _start_group(task: Task) -> tuple[str, str]:
    """Tasks with equal keys start from the same states: the BDDL without `(:language)`, and the init states file."""
    scene = strip_sections(files.task_bddl_text(task), (":language",))
    return hashlib.sha256(scene.encode("utf-8")).hexdigest(), str(files.init_states_path(task))


def inits_text(inits: list[int], of: int) -> str:
    """`init state(s) 0–3, 7 (5 of 10)`: runs of consecutive init states as ranges."""
    runs: list[list[int]] = []
    for index in inits:
        if runs and index == runs[-1][-1] + 1:
            runs[-1].append(index)
        else:
            runs.append([index])
    shown = ", ".join(str(r[0]) if len(r) == 1 else f"{r[0]}–{r[-1]}" for r in runs)
    return f"init state(s) {shown} ({len(inits)} of {of})"


def starts_findings(
    catalog: Catalog, tasks: list[Task], inits: int, progress: Callable[[str], None] = lambda _: None
) -> list[Finding]:
    """`starts elsewhere` and `goal holds at t0` for the package tasks among `tasks`, on init states 0..`inits`-1."""
    from langgap.sim.env import TaskEnv

    checked = [t for t in tasks if t.origin is not None]
    everyone = {t.id: t for t in checked} | {t.source: catalog.get(t.source) for t in checked}
    groups: dict[tuple[str, str], list[Task]] = {}
    for task in everyone.values():
        groups.setdefault(_start_group(task), []).append(task)
    hashes: dict[str, list[str]] = {}  # task id -> t0 hash per init state
    holds: dict[str, list[int]] = {}  # task id -> init states whose start satisfies its goal
    for number, members in enumerate(groups.values(), 1):
        progress(f"[{number}/{len(groups)}] {members[0].id} and {len(members) - 1} other(s)")
        with TaskEnv(members[0]) as env:
            count = min(inits, len(env.init_states))
            for index in range(count):
                env.reset(index, seed=SEED, render=False)
                t0 = env.t0_hash or ""
                env.settle()
                for task in members:
                    hashes.setdefault(task.id, []).append(t0)
                    if env.goal_holds(task.goal):
                        holds.setdefault(task.id, []).append(index)
    found = []
    for task in checked:
        ours, theirs = hashes[task.id], hashes[task.source]
        differing = [i for i, (a, b) in enumerate(zip(ours, theirs, strict=True)) if a != b]
        if differing:
            found.append(
                Finding(
                    "starts elsewhere", task.id, f"t0 differs from its source's on {inits_text(differing, len(ours))}"
                )
            )
        if task.id in holds:
            found.append(Finding("goal holds at t0", task.id, f"on {inits_text(holds[task.id], len(ours))}"))
    return found
