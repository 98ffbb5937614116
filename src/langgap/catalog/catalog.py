"""Loading a registry file and selecting tasks from it.

A registry (`registry/<name>.yaml`) is the single source of truth for a catalog: ids, suites,
dimensions, splits, sources, goals and instructions. Everything else (BDDL files, init states,
reports) is derived from it.
"""

from __future__ import annotations

import dataclasses
import difflib
import fnmatch
import functools
import hashlib
from collections.abc import Iterable
from importlib import resources
from pathlib import Path

import yaml

from langgap.catalog.naming import SUITE_SHORT
from langgap.catalog.split_files import load_split
from langgap.catalog.switch_verdicts import snapshot_switch_verdicts
from langgap.catalog.task import DIMENSIONS, SPLITS, Origin, Task
from langgap.catalog.verdicts import GateResult, read_verdicts, snapshot_verdicts
from langgap.errors import BddlError, CatalogError, CatalogParameterError, UnknownTaskError
from langgap.goals import goal_from_strings
from langgap.vocabulary import TaskKind

DEFAULT_CATALOG = "langgap99"
_KEYWORDS_HELP = (
    "an id, a glob (spatial/*), paper:N, all, feasible, rejected, langgap99, a suite, kind, dimension or split, "
    "split:NAME:train|heldout|K; "
    "'&' intersects, '!' excludes"
)


class Catalog:
    """An ordered, immutable set of tasks with lookup and selection.

    Args:
        name: The catalog's name (`langgap99`).
        tasks: Its tasks, in catalog order: every task's `source` is an original task of the catalog set in the
            same scene.
        description: One line on what the catalog holds.

    Attributes:
        tasks: The tasks, in catalog order (iterating over the catalog gives the same).

    Raises:
        CatalogError: Two tasks share an id, or a task's source is not an original task of its scene.
    """

    def __init__(self, name: str, tasks: Iterable[Task], description: str = ""):
        self.name = name
        self.description = description
        self.tasks: tuple[Task, ...] = tuple(tasks)
        self._by_id: dict[str, Task] = {}
        self._scene_keys: dict[str, str] = {}  # by task id: `scene_key`, computed the first time it is asked
        for task in self.tasks:
            if task.id in self._by_id:
                raise CatalogError(f"catalog {name}: duplicate task id {task.id}")
            self._by_id[task.id] = task
        for task in self.tasks:
            source = self._by_id.get(task.source)
            if source is None or source.kind != TaskKind.ORIGINAL:
                raise CatalogError(
                    f"catalog {name}: task {task.id} has source {task.source!r}, not an {TaskKind.ORIGINAL} task"
                )
            if (source.suite, source.scene_index, source.scene_task) != (task.suite, task.scene_index, task.scene_task):
                raise CatalogError(f"catalog {name}: task {task.id} does not share the scene of its source")

    def __len__(self) -> int:
        return len(self.tasks)

    def __iter__(self):
        return iter(self.tasks)

    def get(self, task_id: str) -> Task:
        """The task with id `task_id`.

        Args:
            task_id: A task id (`spatial/s0/black-bowl-1-on-plate`).

        Returns:
            The task.

        Raises:
            UnknownTaskError: No task has that id (the message suggests close ones).
        """
        try:
            return self._by_id[task_id]
        except KeyError:
            close = difflib.get_close_matches(task_id, self._by_id, n=3, cutoff=0.6)
            hint = f"; did you mean {', '.join(close)}?" if close else "; see `langgap tasks list`"
            raise UnknownTaskError(f"unknown task {task_id!r} in catalog {self.name}{hint}") from None

    def siblings(self, task: Task) -> tuple[Task, ...]:
        """All tasks on the same scene and init states as `task` (itself and its source included)."""
        return tuple(t for t in self.tasks if t.scene_task == task.scene_task and t.suite == task.suite)

    def scene_mates(self, task: Task) -> tuple[Task, ...]:
        """All tasks set in the same scene layout as `task` (may use other init states, as in libero_goal)."""
        key = self.scene_key(task)
        return tuple(t for t in self.tasks if t.suite == task.suite and self.scene_key(t) == key)

    def scene_key(self, task: Task) -> str:
        """The key of the scene `task` is set in (`langgap.catalog.files.scene_key`), computed once for each of
        the catalog's tasks."""
        from langgap.catalog.files import scene_key

        if self._by_id.get(task.id) is not task:  # not one of ours (a copy with other fields, say): no memo
            return scene_key(task)
        key = self._scene_keys.get(task.id)
        if key is None:
            key = self._scene_keys[task.id] = scene_key(task)
        return key

    def select(self, expression: str | None) -> list[Task]:
        """Tasks matching a selection expression, in catalog order.

        The expression is a comma-separated union of terms; a term is an id, a glob over ids,
        `paper:N`, `all`, `feasible` / `rejected` (a feasibility gate's verdict: rejected tasks are
        unproven or proven infeasible), `langgap99`
        (the paper's tasks), a suite (`libero_spatial` or `spatial`), a kind, a dimension or a
        split, or `split:NAME:PART` (a stored split's `train` or `heldout` tasks, or its nested subset of K
        training tasks: `langgap.catalog.splits`). Terms joined with `&` intersect (`spatial&heldout`); `!`
        before a term excludes its tasks (`original&!spatial/s0/*`; alone, from all tasks). A term matching
        nothing is an error. No expression selects every task a feasibility gate did not reject.

        Args:
            expression: The selection (`spatial/s0/*`, `feasible&heldout`); None or blank: `feasible`.

        Returns:
            The selected tasks, in catalog order.

        Raises:
            UnknownTaskError: A term matches no task, or `paper:N` has no number.
        """
        if expression is None or not expression.strip():
            expression = "feasible"
        chosen: set[str] = set()
        for union_term in expression.split(","):
            union_term = union_term.strip()
            if not union_term:
                continue
            matched: set[str] | None = None
            for term in union_term.split("&"):
                term = term.strip()
                if term.startswith("!"):
                    excluded = self._match_term(term[1:].strip())
                    matched = (set(self._by_id) if matched is None else matched) - excluded
                else:
                    ids = self._match_term(term)
                    matched = ids if matched is None else matched & ids
            if not matched:
                raise UnknownTaskError(f"selection {union_term!r} matches no task in catalog {self.name}")
            chosen |= matched
        return [t for t in self.tasks if t.id in chosen]

    def _match_term(self, term: str) -> set[str]:
        if term in self._by_id:
            return {term}
        if term == "all":
            return set(self._by_id)
        if term.startswith("split:"):
            return self._split_term(term)
        if term in ("feasible", "rejected"):
            # may be empty (a catalog whose every task passed): `feasible&!rejected` still means something
            return {t.id for t in self.tasks if t.feasible == (term == "feasible")}
        if term == "langgap99":
            return {t.id for t in self.tasks if t.in_langgap99} or self._no_match(term)
        if term.startswith("paper:"):
            try:
                number = int(term.split(":", 1)[1])
            except ValueError:
                raise UnknownTaskError(f"paper id must be a number: {term!r}") from None
            return {t.id for t in self.tasks if t.paper_id == number} or self._no_match(term)
        suites = {**{s: s for s in SUITE_SHORT}, **{short: s for s, short in SUITE_SHORT.items()}}
        if term in suites:
            return {t.id for t in self.tasks if t.suite == suites[term]}
        for attribute, values in (("kind", tuple(TaskKind)), ("dimension", DIMENSIONS), ("split", SPLITS)):
            if term in values:
                return {t.id for t in self.tasks if getattr(t, attribute) == term}
        if any(ch in term for ch in "*?["):
            return {t.id for t in self.tasks if fnmatch.fnmatchcase(t.id, term)} or self._no_match(term)
        self.get(term)  # raises with suggestions
        return set()

    def _split_term(self, term: str) -> set[str]:
        """The task ids of the selection term `split:NAME:PART`: the split must be of this catalog, unchanged since it
        was made."""
        name, _, part = term.removeprefix("split:").rpartition(":")
        if not name:
            raise CatalogError(f"{term!r}: a split term reads split:NAME:train, split:NAME:heldout or split:NAME:K")
        split = load_split(name)
        if split.catalog != self.name:
            raise CatalogParameterError(
                "split {name} is of catalog {of}, not {this}: pass {catalog} {of}",
                name=split.name,
                of=split.catalog,
                this=self.name,
            )
        if catalog_hash(split.catalog) != split.catalog_sha256:
            raise CatalogError(
                f"split {split.name}: catalog {split.catalog} changed since it was made: generate it again"
            )
        return set(split.part(part))

    def _no_match(self, term: str) -> set[str]:
        raise UnknownTaskError(f"selection term {term!r} matches no task in catalog {self.name} ({_KEYWORDS_HELP})")


def _task_from_entry(
    catalog: str, entry: dict, defaults: dict, originals: dict[str, dict], verdicts: dict[str, GateResult]
) -> Task:
    try:
        kind = entry["kind"]
        source_id = entry["id"] if kind == TaskKind.ORIGINAL else entry["source"]
        if source_id not in originals:
            raise CatalogError(
                f"catalog {catalog}: task {entry['id']} has source {source_id!r}, not an {TaskKind.ORIGINAL} task"
            )
        scene = originals[source_id]
        suite = entry["suite"]
        return Task(
            id=entry["id"],
            catalog=catalog,
            suite=suite,
            kind=kind,
            dimension=entry.get("dimension", TaskKind.ORIGINAL.value),
            split=entry.get("split", TaskKind.ORIGINAL.value),
            source=source_id,
            scene_task=scene["libero_task"],
            scene_index=int(scene["libero_index"]),
            goal=goal_from_strings(entry["goal"]),
            obj_of_interest=tuple(entry["obj_of_interest"]),
            instructions=dict(entry["instructions"]),
            max_steps=int(entry.get("max_steps", defaults["max_steps"][suite])),
            paper_id=entry.get("paper_id"),
            notes=tuple(entry.get("notes", ())),
            # Every task of the paper's own catalog is in it by definition.
            in_langgap99=bool(entry.get("in_langgap99", catalog == DEFAULT_CATALOG)),
            gate=verdicts.get(entry["id"]),
            origin=Origin(**entry["origin"]) if "origin" in entry else None,
            gate_from=entry.get("gate_from"),
        )
    except TypeError as exc:  # an origin with missing or unknown fields
        raise CatalogError(f"catalog {catalog}: task {entry.get('id', '?')}: bad origin: {exc}") from None
    except KeyError as exc:
        raise CatalogError(f"catalog {catalog}: task {entry.get('id', '?')} lacks field {exc}") from None
    except BddlError as exc:
        raise CatalogError(f"catalog {catalog}: task {entry.get('id', '?')}: {exc}") from None


def load_catalog_file(path: str | Path) -> Catalog:
    """Load a registry YAML file."""
    path = Path(path)
    try:
        # libyaml's loader, where installed, reads the ~850-task `full` registry 5x faster.
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except (OSError, yaml.YAMLError) as exc:
        raise CatalogError(f"cannot read catalog {path}: {exc}") from None
    return catalog_from_data(data, source=str(path), verdicts=read_verdicts(path) | inherited_verdicts(data))


def inherited_verdicts(data: dict) -> dict[str, GateResult]:
    """The verdicts registry `data`'s tasks take by `gate_from`, read from their source catalogs' current
    verdict files (so a re-gate of the source reaches them), each marked with where it comes from."""
    found: dict[str, GateResult] = {}
    files: dict[str, dict[str, GateResult]] = {}
    for entry in data.get("tasks", ()):
        if "gate_from" not in entry:
            continue
        catalog, _, task_id = entry["gate_from"].partition(":")
        if catalog not in files:
            files[catalog] = read_verdicts(registry_path(catalog))
        if task_id in files[catalog]:
            found[entry["id"]] = dataclasses.replace(files[catalog][task_id], inherited_from=entry["gate_from"])
    return found


def registry_path(name: str) -> Path:
    """The registry file behind catalog `name` (a shipped name or a path)."""
    if name.endswith(".yaml") or "/" in name:
        return Path(name)
    if name not in available_catalogs():
        raise CatalogError(f"unknown catalog {name!r} (available: {', '.join(available_catalogs())})")
    return Path(str(resources.files("langgap.catalog") / "registry" / f"{name}.yaml"))


def catalog_from_data(data: dict, *, source: str = "<data>", verdicts: dict[str, GateResult] | None = None) -> Catalog:
    """A catalog from registry data, with feasibility verdicts attached to their tasks."""
    verdicts = verdicts or {}
    if not isinstance(data, dict) or "tasks" not in data or "catalog" not in data:
        raise CatalogError(f"{source}: not a LangGap registry (needs 'catalog' and 'tasks')")
    name = data["catalog"]
    entries = data["tasks"]
    originals = {e["id"]: e for e in entries if e.get("kind") == TaskKind.ORIGINAL}
    tasks = [_task_from_entry(name, e, data, originals, verdicts) for e in entries]
    return Catalog(name, tasks, description=data.get("description", ""))


def available_catalogs() -> list[str]:
    """Names of the registries shipped with the package."""
    folder = resources.files("langgap.catalog") / "registry"
    return sorted(p.name.removesuffix(".yaml") for p in folder.iterdir() if p.name.endswith(".yaml"))


def catalog_hash(name: str) -> str:
    """SHA-256 of catalog `name`'s registry file: two runs on the same hash saw the same tasks, goals and sentences."""
    path = registry_path(name)
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as exc:
        raise CatalogError(f"cannot read catalog {path}: {exc}") from None


def gate_snapshot(name: str, tasks: Iterable[Task], previous: dict | None = None) -> dict:
    """The gate verdicts of `tasks` of catalog `name` with their file's SHA-256, as a run stores them
    (`snapshot_verdicts`; `previous` keeps a run's earlier snapshot and adds only tasks it lacks), and under
    `switch` the same of its switch verdicts (`switch_verdicts`). A task with `gate_from` gets that task's
    verdict, from its catalog's file."""
    tasks, registry = list(tasks), registry_path(name)
    task_ids = [t.id for t in tasks]
    inherited = {
        t.id: (registry_path(t.gate_from.partition(":")[0]), t.gate_from) for t in tasks if t.gate_from is not None
    }
    snapshot = snapshot_verdicts(registry, task_ids, previous, inherited)
    return {**snapshot, "switch": snapshot_switch_verdicts(registry, task_ids, (previous or {}).get("switch"))}


@functools.cache
def load_catalog(name: str = DEFAULT_CATALOG) -> Catalog:
    """A shipped catalog by name (`langgap99`), or a registry file by path.

    Args:
        name: A shipped catalog's name (`available_catalogs` lists them), or the path of a registry YAML file
            (a name that ends in `.yaml` or holds a `/`).

    Returns:
        The catalog, its tasks carrying the feasibility verdicts recorded beside the registry. It is loaded
        once per name: later calls return the same object.

    Raises:
        CatalogError: The name is no shipped catalog, or the registry or its verdicts cannot be read or are
            not valid.
    """
    return load_catalog_file(registry_path(name))
