"""The files behind a task: its scene's BDDL, its generated BDDL and its init states.

Original tasks run LIBERO's shipped BDDL unchanged. An extended task's BDDL is generated from its
source's shipped BDDL by replacing `(:language)`, `(:obj_of_interest)` and `(:goal)` only, and is
written once to the cache directory (`$LANGGAP_CACHE`, default `~/.cache/langgap`). A task read from
another benchmark's package (`Task.origin`) runs that package's BDDL file and init states as shipped
(`catalog/packages.py`). What an environment needs of them is resolved once per task (`task_files`).
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from langgap import stack
from langgap.atomic import write_text_atomically
from langgap.bddl import BddlProblem, parse_bddl, rewrite_task_sections, strip_task_sections
from langgap.catalog import packages
from langgap.catalog.cache import cache_dir
from langgap.catalog.task import Task
from langgap.errors import BddlError
from langgap.goals import atoms, conjunction
from langgap.vocabulary import InstructionStyle, TaskKind


def scene_bddl_path(task: Task) -> Path:
    """LIBERO's shipped BDDL of the task whose scene `task` uses (a package's task: its own file, the scene it
    ships)."""
    if task.origin is not None:
        return packages.loadable_bddl(task.origin, packages.checked_bytes(task.origin))
    return stack.bddl_path(task.suite, task.scene_task)


@functools.lru_cache(maxsize=256)
def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise BddlError(f"cannot read BDDL file {path}: {exc.strerror}") from None


def _scene_text(task: Task) -> tuple[str, str]:
    """The shipped BDDL text of the scene `task` is set in (a package's task: its own file, checked against the
    registry), and the name of the file it was read from."""
    if task.origin is not None:
        return packages.checked_bytes(task.origin).decode("utf-8"), task.origin.file
    path = stack.bddl_path(task.suite, task.scene_task)
    return _read_text(path), str(path)


def scene_problem(task: Task) -> BddlProblem:
    """The parsed scene (objects, fixtures, regions, init) of `task`."""
    text, source = _scene_text(task)
    return parse_bddl(text, source=source)


def scene_key(task: Task) -> str:
    """A hash of the scene `task` is set in (its BDDL without the task sections).

    Tasks with equal keys have the same objects, fixtures and placements; all libero_goal tasks share one.
    """
    return _scene_hash(_scene_text(task)[0])


@functools.lru_cache(maxsize=256)
def _scene_hash(text: str) -> str:
    return hashlib.sha256(strip_task_sections(text).encode("utf-8")).hexdigest()[:16]


def task_bddl_text(task: Task) -> str:
    """The BDDL text of `task`: LIBERO's own for originals, generated for extended tasks."""
    return _task_text(task, *_scene_text(task))


def _task_text(task: Task, scene_text: str, source: str) -> str:
    """`task_bddl_text` from its scene's text, read from `source`."""
    if task.origin is not None:
        shipped = parse_bddl(scene_text, source=source)
        if conjunction(shipped.goal) != task.goal or shipped.language != task.instruction(InstructionStyle.PAPER):
            raise BddlError(f"task {task.id}: registry goal or instruction differs from {source}")
        return scene_text
    if task.kind == TaskKind.ORIGINAL:
        if conjunction(parse_bddl(scene_text, source=source).goal) != task.goal:
            raise BddlError(f"task {task.id}: registry goal {task.goal_strings} differs from LIBERO's BDDL")
        return scene_text
    try:
        # Atoms only the goal language reads (an `Or`'s other parts, a `Not`) must name the scene's things too.
        parse_bddl(scene_text).check_goal(atoms(task.goal))
        return rewrite_task_sections(
            scene_text,
            language=task.instruction(InstructionStyle.PAPER),
            obj_of_interest=task.obj_of_interest,
            goal=task.bddl_goal,
        )
    except BddlError as exc:
        raise BddlError(f"task {task.id}: {exc}") from None


def task_bddl_path(task: Task) -> Path:
    """A BDDL file for `task` that LIBERO can load; generated files are written atomically once."""
    return _bddl_file(task, task_bddl_text(task))


def _bddl_file(task: Task, text: str) -> Path:
    """A file LIBERO can load holding `text`, the checked BDDL of `task`: the shipped file, or one written to the
    cache (a package's extracted from its wheel, an extended task's generated) unless it holds `text` already."""
    if task.origin is not None:
        return packages.loadable_bddl(task.origin, text.encode("utf-8"))
    if task.kind == TaskKind.ORIGINAL:
        return stack.bddl_path(task.suite, task.scene_task)
    path = cache_dir() / "bddl" / task.catalog / f"{task.id}.bddl"
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        write_text_atomically(path, text)  # concurrent workers never see a half-written file
    return path


def _runs_own_states(task: Task) -> bool:
    return task.origin is not None and task.origin.init_runs == "own"


def init_states_path(task: Task) -> Path:
    """The file of the init states `task` starts from."""
    if _runs_own_states(task):  # only LIBERO-PRO's package, installed as LangGap's LIBERO, ships states a task runs
        return packages.pro_site() / task.origin.init_file
    return stack.init_states_path(task.suite, task.scene_task)


def init_states(task: Task) -> np.ndarray:
    """The fixed init states `task` starts from (its scene task's 50 states; a package's task, those it ships)."""
    if _runs_own_states(task):
        return packages.own_init_states(task.origin)
    return stack.load_init_states(task.suite, task.scene_task)


@dataclass(frozen=True)
class TaskFiles:
    """What a LIBERO environment of a task is built and reset from, resolved once (`task_files`).

    Attributes:
        bddl: A BDDL file LIBERO can load (`task_bddl_path`: checked against the registry, a generated one written).
        scene: The key of the scene the task is set in (`scene_key`).
        init_states_file: The file of the init states (`init_states_path`).
        init_states: The fixed init states the task starts from (`init_states`).
    """

    bddl: Path
    scene: str
    init_states_file: Path
    init_states: np.ndarray = field(compare=False, repr=False)

    def same_start(self, other: TaskFiles) -> bool:
        """Whether an environment of `other` starts as one of these: the same scene and the same init states."""
        return (self.scene, self.init_states_file) == (other.scene, other.init_states_file)


def task_files(task: Task) -> TaskFiles:
    """The files an environment of `task` needs, resolved (and checked) in one pass: its scene's file read once."""
    scene_text, source = _scene_text(task)
    text = _task_text(task, scene_text, source)
    return TaskFiles(_bddl_file(task, text), _scene_hash(scene_text), init_states_path(task), init_states(task))
