"""The generated catalogs. `full`: every candidate same-scene task of LIBERO's suites, from their BDDL
(`langgap-beyond`, the dimensions beyond the paper's, is generated in `beyond`).

For each original task (the sources: LangGap-99's 40 originals), every one-predicate goal its scene
affords (`candidates`) becomes a task on the source's scene and init states, with an id from
`naming`, both instruction styles from `phrasing`, and a dimension relative to the source. A
candidate that is one of the paper's tasks keeps the paper's id, strings, dimension and split.

Physical feasibility is not decided here: the feasibility gate (`langgap.gate`) runs the scripted
oracle on the written catalog and records its verdicts beside the registry (`catalog/verdicts.py`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from importlib import resources
from pathlib import Path

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import files
from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.naming import SUITE_SHORT, task_id
from langgap.catalog.task import DIMENSIONS, INSTRUCTION_STYLES, Task
from langgap.errors import CatalogError
from langgap.generation import phrasing
from langgap.generation.candidates import candidate_goals, dimension, obj_of_interest
from langgap.generation.registry_writer import registry_text
from langgap.goals import conjunction
from langgap.stack import SUITES
from langgap.vocabulary import InstructionStyle, Split, TaskKind

FULL_CATALOG = "full"
FULL_DESCRIPTION = "Every candidate same-scene task of LIBERO's scenes, generated from their BDDL (langgap generate)."


BEYOND_CATALOG = "langgap-beyond"
BEYOND_DESCRIPTION = (
    "LIBERO's 40 originals, each with tasks beyond the paper's dimensions on its scene and init states: "
    "ordering, negation, paraphrase and attribute reference (langgap generate --catalog langgap-beyond)."
)
# The catalogs `langgap generate` writes, with their descriptions.
GENERATED = {FULL_CATALOG: FULL_DESCRIPTION, BEYOND_CATALOG: BEYOND_DESCRIPTION}


def default_registry_path(catalog: str = FULL_CATALOG) -> Path:
    """Where the shipped registry of generated catalog `catalog` lives inside the package."""
    return Path(str(resources.files("langgap.catalog") / "registry" / f"{catalog}.yaml"))


def resolve_suites(names: Iterable[str]) -> list[str]:
    """Suite names (`libero_goal` or `goal`) in the canonical order; CatalogError on an unknown one."""
    short = {s: suite for suite, s in SUITE_SHORT.items()}
    wanted = set()
    for name in names:
        suite = short.get(name, name)
        if suite not in SUITES:
            raise CatalogError(f"unknown suite {name!r} (known: {', '.join(SUITES)})")
        wanted.add(suite)
    return [s for s in SUITES if s in wanted]


def source_tasks(suites: Iterable[str] = SUITES) -> list[Task]:
    """The originals of LangGap-99 in `suites` (the sources of generated tasks), in suite and scene order."""
    suites = resolve_suites(suites)
    paper = load_catalog(DEFAULT_CATALOG)
    return sorted(
        (t for t in paper if t.kind == TaskKind.ORIGINAL and t.suite in suites),
        key=lambda t: (suites.index(t.suite), t.scene_index),
    )


def generate_tasks(suites: Iterable[str] = SUITES) -> list[Task]:
    """Every candidate task of `suites`, originals first within each scene; deterministic."""
    published = {
        (t.suite, t.scene_task, t.goal): t for t in load_catalog(DEFAULT_CATALOG) if t.kind == TaskKind.EXTENDED
    }
    return [task for source in source_tasks(suites) for task in _scene_tasks(source, published)]


def _scene_tasks(source: Task, published: dict[tuple, Task]) -> list[Task]:
    """The source itself, then its scene's extended candidates by dimension and id."""
    scene = files.scene_problem(source)
    extended = []
    for goal in candidate_goals(scene, source.bddl_goal):
        if (goal,) == source.bddl_goal:
            continue
        task = _extended_task(source, (goal,), scene)
        paper_task = published.get((task.suite, task.scene_task, task.goal))
        extended.append(_as_published(task, paper_task) if paper_task else task)
    extended.sort(key=lambda t: (DIMENSIONS.index(t.dimension), t.id))
    return [dataclasses.replace(source, catalog=FULL_CATALOG, in_langgap99=True), *extended]


def _extended_task(source: Task, goal: tuple[Predicate, ...], scene: BddlProblem) -> Task:
    return Task(
        id=task_id(source.suite, source.scene_index, goal, scene),
        catalog=FULL_CATALOG,
        suite=source.suite,
        kind=TaskKind.EXTENDED.value,
        dimension=dimension(goal[0], source.bddl_goal, scene),
        split=Split.HELDOUT.value,
        source=source.id,
        scene_task=source.scene_task,
        scene_index=source.scene_index,
        goal=conjunction(goal),
        obj_of_interest=obj_of_interest(goal, scene),
        instructions={style: phrasing.instruction(style, source.suite, goal, scene) for style in INSTRUCTION_STYLES},
        max_steps=source.max_steps,
    )


def _as_published(task: Task, paper_task: Task) -> Task:
    """`task` as the paper published it: its strings, dimension, split, id number and notes."""
    notes = paper_task.notes
    if paper_task.dimension != task.dimension:
        notes += (f"the dimension rule gives {task.dimension}; the paper's label {paper_task.dimension} is kept",)
    return dataclasses.replace(
        task,
        instructions={
            InstructionStyle.LIBERO.value: task.instruction(InstructionStyle.LIBERO),
            InstructionStyle.PAPER.value: paper_task.instruction(InstructionStyle.PAPER),
        },
        dimension=paper_task.dimension,
        split=paper_task.split,
        paper_id=paper_task.paper_id,
        notes=notes,
        in_langgap99=True,
    )


def write_registry(tasks: list[Task], path: str | Path, catalog: str = FULL_CATALOG) -> Path:
    """Write `tasks` as the registry YAML of generated catalog `catalog` at `path` (parent folders are created)."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(registry_text(catalog, GENERATED[catalog], tasks), encoding="utf-8")
    except OSError as exc:
        raise CatalogError(f"cannot write registry {path}: {exc.strerror}") from None
    return path
