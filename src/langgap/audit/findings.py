"""LangGap's checks of tasks, each failure a named finding.

The checks here read files only: a task's BDDL against its source's, its goal against what LIBERO
evaluates and the scene holds, its instruction's form, the init states it ships against its source's, and
duplicates within a scene (tasks read from other benchmarks' packages). The checks that need the simulator
(the t0 state, the goal at t0) are in `langgap.audit.starts`; whether a goal accepts what its sentence allows
(LangGap's own, generated tasks) in `langgap.audit.sentences`. Findings are kept beside the registry in
`<catalog>.audit.json`, with which checks made them, so the gate and the docs read the same list.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap.atomic import write_text_atomically
from langgap.bddl import PREDICATE_ARITY, parse_bddl, read_tree, section_texts, strip_sections
from langgap.catalog import packages
from langgap.catalog.task import PACKAGE_STYLE, Task
from langgap.errors import CatalogError
from langgap.vocabulary import Dimension, InstructionStyle

# Every finding a check can make, with what it means (the audit prints these).
FINDINGS = {
    "unreadable": "the package's BDDL file does not parse, so the task is left out of the catalog",
    "changes the scene": "the BDDL differs from its source's outside what the perturbation changes",
    "not a perturbation": "the variant changes nothing its dimension names (same instruction, or same goal)",
    "done by its source task": "every part of its goal is a part of its source's: doing the source task does it",
    "never satisfiable": "the goal names a predicate LIBERO does not evaluate, or a thing not in the scene",
    "ships other init states": "the init states the package ships for it are not its source's",
    "starts elsewhere": "its t0 state differs from its source's on the same init state (simulator)",
    "goal holds at t0": "its goal already holds when the episode starts (simulator)",
    "duplicate goal": "another task set in the same scene has the same goal",
    "duplicate instruction": "another variant of the same source has the same instruction, compared case-insensitively",
    "instruction is a file name": "the instruction is the BDDL file's name, not the sentence its (:language) has",
    "instruction carries an id": "the instruction carries a perturbation id or a number suffix",
    "instruction is not about the task": "the instruction is an LLM's preamble or commentary, not a request",
    "runner sends another sentence": "its package's runner sends another instruction than its (:language)",
    "runner changes its case": "its package's runner sends its (:language) lowercased",
    "runner does not reach it": "its package's runner does not list the file, so it never runs the task",
    "sentence picks another object": "a referring expression picks another object than the goal names (references)",
    "sentence picks no object": "a referring expression fits no object of the scene (references)",
    "sentence is ambiguous": "a referring expression fits more than one object of the scene (references)",
    "goal narrower than its sentence": "the goal rejects a state its sentence allows (sentence check)",
    "goal wider than its sentence": "the goal accepts a state its sentence does not allow (sentence check)",
}
# The checks, by what they need: `files` reads the packages' files (here), `starts` runs the simulator
# (`langgap.audit.starts`), `sentence` reads a generated task's goal and scene (`langgap.audit.sentences`),
# `references` resolves its sentence on the simulator's scenes (`langgap.audit.reference_check`);
# each makes the findings listed.
_STARTS = ("starts elsewhere", "goal holds at t0")
_SENTENCE = ("goal narrower than its sentence", "goal wider than its sentence")
_REFERENCES = ("sentence picks another object", "sentence picks no object", "sentence is ambiguous")
CHECKS = {
    "files": tuple(name for name in FINDINGS if name not in _STARTS + _SENTENCE + _REFERENCES),
    "starts": _STARTS,
    "sentence": _SENTENCE,
    "references": _REFERENCES,
}
# Sections a variant may change, by dimension; every other byte must be its source's.
MAY_CHANGE = {Dimension.LANGUAGE: (":language",), Dimension.TASK: (":language", ":obj_of_interest", ":goal")}
# Predicates LIBERO evaluates (libero/envs/predicates) that LangGap's goal language does not judge.
_LIBERO_ONLY = {"up", "true", "false", "printjointstate"}


@dataclass(frozen=True)
class Finding:
    """One check's failure on one task."""

    name: str
    task: str
    detail: str

    def __post_init__(self) -> None:
        if self.name not in FINDINGS:
            raise CatalogError(f"unknown finding {self.name!r} (known: {', '.join(FINDINGS)})")


# -- the checks ------------------------------------------------------------------------------------------------


def scene_findings(task_id: str, dimension: str, text: str, source_text: str) -> list[Finding]:
    """`changes the scene` when `text` differs from `source_text` outside the sections `dimension` may change
    (or anywhere outside the sections' text: comments, order); `not a perturbation` when it changes none;
    `done by its source task` when a task variant's goal is a part of its source's."""
    ours, theirs = section_texts(text), section_texts(source_text)
    allowed = MAY_CHANGE[dimension]
    changed = sorted(k for k in ours.keys() | theirs.keys() if ours.get(k) != theirs.get(k) and k not in allowed)
    found = []
    if changed:
        found.append(Finding("changes the scene", task_id, f"differs from its source in {', '.join(changed)}"))
    elif strip_sections(text) != strip_sections(source_text):
        found.append(Finding("changes the scene", task_id, "differs from its source outside its sections"))
    parsed, source = parse_bddl(text), parse_bddl(source_text)
    if dimension == Dimension.LANGUAGE and parsed.language == source.language:
        found.append(Finding("not a perturbation", task_id, "its instruction is its source's"))
    if dimension == Dimension.TASK and set(parsed.goal) == set(source.goal):
        found.append(Finding("not a perturbation", task_id, "its goal is its source's"))
    elif dimension == Dimension.TASK and set(parsed.goal) < set(source.goal):
        # A policy that ignores its instruction and does the source task succeeds: it asks nothing new.
        left = " ".join(str(p) for p in source.goal if p not in parsed.goal)
        found.append(Finding("done by its source task", task_id, f"its goal is its source's without {left}"))
    return found


def goal_findings(task_id: str, text: str) -> list[Finding]:
    """`never satisfiable` for each goal atom LIBERO cannot make true: a predicate it does not evaluate (a typo
    is not silently false), a wrong number of arguments, or a name that is not an object, fixture or region of
    the scene. Read leniently, so that a goal LangGap's parser refuses is still reported atom by atom."""
    goal = section_texts(text).get(":goal")
    if goal is None:
        return [Finding("never satisfiable", task_id, "the file has no (:goal ...) section")]
    form = read_tree(goal)[0][1:]
    atoms = []
    for node in form:
        atoms += node[1:] if isinstance(node, list) and node and str(node[0]).lower() == "and" else [node]
    entities = _entities(text)
    found = []
    for atom in atoms:
        if not isinstance(atom, list) or not atom or any(isinstance(a, list) for a in atom):
            found.append(Finding("never satisfiable", task_id, f"goal part {atom!r} is not a ground atom"))
            continue
        name, args = str(atom[0]), [str(a) for a in atom[1:]]
        shown = f"({' '.join([name, *args])})"
        known = {k.lower(): v for k, v in PREDICATE_ARITY.items()}
        if name.lower() in _LIBERO_ONLY:
            found.append(Finding("never satisfiable", task_id, f"{shown}: LangGap's goal language cannot judge it"))
        elif name.lower() not in known:
            found.append(Finding("never satisfiable", task_id, f"{shown}: LIBERO evaluates no predicate {name!r}"))
        elif len(args) != known[name.lower()]:
            found.append(Finding("never satisfiable", task_id, f"{shown}: {name} takes {known[name.lower()]}"))
        elif missing := [a for a in args if a not in entities]:
            found.append(Finding("never satisfiable", task_id, f"{shown}: {', '.join(missing)} not in the scene"))
    return found


def _entities(text: str) -> set[str]:
    """The names a goal may use in `text` (objects, fixtures, region sites), read without judging its goal."""
    sections = {}
    for item in read_tree(text)[0][1:]:
        if isinstance(item, list) and item and isinstance(item[0], str) and item[0].startswith(":"):
            sections[item[0]] = item[1:]
    names = {str(x) for key in (":objects", ":fixtures") for x in sections.get(key, []) if isinstance(x, str)}
    names.discard("-")
    for entry in sections.get(":regions", []):
        target = next((sub[1] for sub in entry[1:] if isinstance(sub, list) and sub[:1] == [":target"]), None)
        if target is not None:
            names.add(f"{target}_{entry[0]}")
    return names


# An id LIBERO-Plus's file names carry (`_language_3`, `_view_0_0_100_0_0`, `_initstate_0`, ...), as words.
_ID_WORDS = re.compile(r"\b(language|view|initstate|light|table|tb|noise|add|level|camera)[ _]\d+", re.IGNORECASE)
_NUMBER_SUFFIX = re.compile(r"[\s_]\d+\s*$")
# An LLM's reply about the rewriting it was asked for ("Here are 20 variations of the instruction ..."). A reply's
# courtesy before a request ("Sure make sure the butter ends up in the basket") is still a request.
_PREAMBLE = re.compile(
    r"^\s*here (is|are)\b|\bvariations? of (the|this) (given )?instruction|\bas an ai\b", re.IGNORECASE
)


def _words(text: str) -> str:
    return " ".join(re.sub(r"[_\s]+", " ", text).lower().split())


def instruction_findings(task_id: str, instruction: str, file_name: str) -> list[Finding]:
    """Whether `instruction` is a sentence about the task: not the BDDL file's name (`file_name`, as LIBERO's
    benchmark code turns it into words), no perturbation id or number suffix, no LLM preamble."""
    found = []
    stem = Path(file_name).name.removesuffix(".bddl")
    scene_free = re.sub(r"^[A-Z_]*SCENE\d+_", "", stem)  # libero_10's file names start with their scene
    if "_" in instruction or ".bddl" in instruction or _words(instruction) in (_words(stem), _words(scene_free)):
        found.append(Finding("instruction is a file name", task_id, repr(instruction)))
    if _ID_WORDS.search(instruction) or _NUMBER_SUFFIX.search(instruction):
        found.append(Finding("instruction carries an id", task_id, repr(instruction)))
    if _PREAMBLE.search(instruction):
        found.append(Finding("instruction is not about the task", task_id, repr(instruction)))
    return found


def runner_findings(task: Task) -> list[Finding]:
    """What the runner of the package `task` was read from does with it: it sends another sentence than the
    task's `(:language)` (LIBERO-PRO's, made of the file's name), or the same lowercased (LIBERO-Plus's); it does
    not list the task's file (`Origin.registered`). See `langgap.catalog.runner_sentences`."""
    if task.origin is None:
        return []
    found = []
    if task.origin.registered is False:
        found.append(Finding("runner does not reach it", task.id, f"{task.origin.file} is not in its task map"))
    sent, own = task.instruction(PACKAGE_STYLE), task.instruction(InstructionStyle.PAPER)
    if sent.split() == own.lower().split() and sent != own:
        found.append(Finding("runner changes its case", task.id, f"it sends {sent!r}"))
    elif sent != own:
        found.append(Finding("runner sends another sentence", task.id, f"it sends {sent!r}, not {own!r}"))
    return found


def duplicate_findings(tasks: Iterable[Task], scene_of) -> list[Finding]:
    """`duplicate goal` for each task whose scene (`scene_of(task)`: layout and init states) holds another task
    with the same goal, a language variant and its source excepted (they share a goal by design);
    `duplicate instruction` for language variants of one source with the same sentence."""
    tasks = list(tasks)
    found = []
    by_goal: dict[tuple, list[Task]] = {}
    for task in tasks:
        by_goal.setdefault((scene_of(task), task.goal), []).append(task)
    for group in by_goal.values():
        for task in group:
            others = [o.id for o in group if o.id != task.id and not _language_pair(task, o)]
            if others:
                found.append(Finding("duplicate goal", task.id, f"same goal as {', '.join(others)}"))
    by_sentence: dict[tuple, list[Task]] = {}
    for task in tasks:
        if task.dimension == Dimension.LANGUAGE:
            by_sentence.setdefault((task.source, task.instruction(InstructionStyle.PAPER).lower()), []).append(task)
    for group in by_sentence.values():
        for task in group:
            exact = [
                o.id
                for o in group
                if o.id != task.id and o.instruction(InstructionStyle.PAPER) == task.instruction(InstructionStyle.PAPER)
            ]
            cased = [o.id for o in group if o.id != task.id and o.id not in exact]
            if exact:
                found.append(Finding("duplicate instruction", task.id, f"same instruction as {', '.join(exact)}"))
            if cased:
                shown = ", ".join(cased)
                found.append(Finding("duplicate instruction", task.id, f"same instruction but for case as {shown}"))
    return found


def duplicate_counts(tasks: Iterable[Task]) -> dict[str, dict[str, int]]:
    """How many language variants share their sentence with another variant of the same source, and how many
    sentences they share, compared as exact strings and case-insensitively (`{"exact": {"variants": ..,
    "sentences": ..}, "case-insensitive": {...}}`): a runner that lowercases (LIBERO-Plus's) sends the second."""
    counts = {}
    for how, key in (("exact", str), ("case-insensitive", str.lower)):
        groups: dict[tuple, int] = {}
        for task in tasks:
            if task.dimension == Dimension.LANGUAGE:
                sentence = (task.source, key(task.instruction(InstructionStyle.PAPER)))
                groups[sentence] = groups.get(sentence, 0) + 1
        shared = [n for n in groups.values() if n > 1]
        counts[how] = {"variants": sum(shared), "sentences": len(shared)}
    return counts


def duplicate_counts_text(counts: dict[str, dict[str, int]]) -> str:
    """`duplicate_counts` as one line."""
    exact, cased = counts["exact"], counts["case-insensitive"]
    return (
        f"language variants sharing a sentence with another of their source: {exact['variants']} "
        f"({exact['sentences']} sentences) as exact strings, {cased['variants']} ({cased['sentences']} sentences) "
        "case-insensitively"
    )


def _language_pair(a: Task, b: Task) -> bool:
    """Whether `a` and `b` share their goal by design: one is a language variant of the other, or both are
    language variants of one source."""
    if a.dimension == Dimension.LANGUAGE and b.dimension == Dimension.LANGUAGE:
        return a.source == b.source
    return (a.dimension == Dimension.LANGUAGE and a.source == b.id) or (
        b.dimension == Dimension.LANGUAGE and b.source == a.id
    )


def init_findings(task: Task, source_states: np.ndarray) -> list[Finding]:
    """`ships other init states` when the states the package ships for `task` are not `source_states`."""
    shipped = packages.read_states(task.origin.package, task.origin.init_file)
    if shipped.shape == source_states.shape and np.array_equal(shipped, source_states):
        return []
    if shipped.shape != source_states.shape:
        detail = f"{shipped.shape[0]} states of size {shipped.shape[1]}, its source's {source_states.shape}"
    else:
        rows = int(np.any(shipped != source_states, axis=1).sum())
        detail = f"{rows} of {len(shipped)} differ (up to {np.abs(shipped - source_states).max():.3f} in a coordinate)"
    return [Finding("ships other init states", task.id, detail)]


# -- kept beside the registry -----------------------------------------------------------------------------------


def audit_path(registry: str | Path) -> Path:
    registry = Path(registry)
    return registry.with_name(registry.name.removesuffix(".yaml") + ".audit.json")


def read_audit(registry: str | Path) -> tuple[dict, list[Finding]]:
    """What the recorded audit says (`about`: which checks ran, how) and its findings; empty if none recorded."""
    path = audit_path(registry)
    if not path.is_file():
        return {}, []
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        found = [Finding(f["name"], task, f["detail"]) for task, listed in data["tasks"].items() for f in listed]
        return data["about"], found
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CatalogError(f"cannot read audit {path}: {exc}") from None


def record_audit(
    registry: str | Path, check: str, about: dict, findings: list[Finding], checked: Iterable[str]
) -> Path:
    """Record what `check` (a key of CHECKS, run as `about` says) found over the tasks `checked`: it replaces
    that check's earlier findings on those tasks and keeps everything else (every checked task gets an entry,
    an empty list when nothing was found); `about`'s keys replace the check's keys of the same name."""
    old_about, old = read_audit(registry)
    checked = set(checked)
    kept = [f for f in old if not (f.name in CHECKS[check] and f.task in checked)]
    path = audit_path(registry)
    listed = set(json.loads(path.read_text(encoding="utf-8"))["tasks"]) if path.is_file() else set()
    tasks: dict[str, list[dict]] = {task: [] for task in checked | listed}
    for f in sorted(kept + findings, key=lambda f: (f.task, list(FINDINGS).index(f.name), f.detail)):
        tasks[f.task].append({"name": f.name, "detail": f.detail})
    data = {
        "about": old_about | {check: old_about.get(check, {}) | about},
        "tasks": {k: tasks[k] for k in sorted(tasks)},
    }
    write_text_atomically(path, json.dumps(data, indent=1, sort_keys=True) + "\n")
    return path


def audit_text(findings: list[Finding], task_ids: Iterable[str], examples: int = 3) -> str:
    """Per finding among the tasks `task_ids`, how many tasks have it and a few examples; then how many have none."""
    ids = set(task_ids)
    findings = [f for f in findings if f.task in ids]
    lines = []
    for name, meaning in FINDINGS.items():
        hit = [f for f in findings if f.name == name]
        if not hit:
            continue
        lines.append(f"{name}: {len({f.task for f in hit})} task(s) — {meaning}")
        lines += [f"  {f.task}: {f.detail}" for f in hit[:examples]]
    clean = len(ids - {f.task for f in findings})
    lines.append(f"{len(ids)} tasks: {len(ids) - clean} with findings, {clean} with none")
    return "\n".join(lines)
