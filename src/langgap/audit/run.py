"""The audit run: LangGap's checks over a catalog's selected tasks (`audit`), each run now or read as recorded.

A package's tasks get the file checks (`files_findings`: each one's files against its source's, the checks of
`langgap.audit.findings`) and the simulator checks of their starts (`langgap.audit.starts`); a catalog of
LangGap's own sentences, the sentence check (`langgap.audit.sentences`); both, the reference check
(`langgap.audit.reference_check`). A check not run now gives what the recorded audit (`<catalog>.audit.json`)
holds. `langgap tasks audit` prints an `AuditResult`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from langgap.audit.findings import (
    CHECKS,
    Finding,
    duplicate_counts,
    duplicate_findings,
    goal_findings,
    init_findings,
    instruction_findings,
    read_audit,
    record_audit,
    runner_findings,
    scene_findings,
)
from langgap.catalog import files, packages
from langgap.catalog.catalog import DEFAULT_CATALOG, Catalog, load_catalog, registry_path
from langgap.catalog.task import Task
from langgap.errors import CatalogError, ParameterError
from langgap.vocabulary import InstructionStyle

Say = Callable[[str], None]


@dataclass(frozen=True)
class AuditResult:
    """What `audit` found, and how its checks ran.

    Attributes:
        catalog: The audited catalog.
        findings: Every finding among the audited tasks, in the order the checks made them (files, starts,
            sentence, references); a check not run now gives its recorded findings.
        package_ids: The selected tasks read from packages (the file, starts and reference checks').
        unreadable: The package files left out of the catalog because they do not parse (as recorded).
        own_ids: The selected tasks of a catalog of LangGap's own sentences (the sentence and reference checks').
        ran: How each check run now ran (a key of `CHECKS` -> what the recorded audit keeps about it).
        about: What the recorded audit said, before this run, about how its checks ran.
        recorded: The audit file written with `record`, else None.
    """

    catalog: Catalog
    findings: tuple[Finding, ...]
    package_ids: tuple[str, ...]
    unreadable: tuple[str, ...]
    own_ids: tuple[str, ...]
    ran: dict
    about: dict
    recorded: Path | None = None

    @property
    def checked(self) -> tuple[str, ...]:
        """Every audited task: those read from packages, the unreadable files', then LangGap's own."""
        return self.package_ids + self.unreadable + self.own_ids


def audit(
    catalog: str = DEFAULT_CATALOG,
    selection: str | None = "all",
    *,
    starts: int = 0,
    references: int = 0,
    record: bool = False,
    progress: Say | None = None,
) -> AuditResult:
    """Run LangGap's checks on a catalog's selected tasks.

    Args:
        catalog: A shipped catalog's name, or the path of a registry file.
        selection: The tasks (a selection, as `Catalog.select` reads it).
        starts: Also run the simulator checks of the package tasks' starts on init states 0..`starts`-1 (0:
            their recorded findings).
        references: Also resolve each sentence's referring expressions on init states 0..`references`-1 (0:
            the recorded findings).
        record: Record the checks that ran beside the registry (`<catalog>.audit.json`), each replacing its
            earlier findings on the tasks it checked.
        progress: Called with each line said while the checks run (their progress, and how each check ran or
            was recorded), in order; None says nothing.

    Returns:
        The findings and how the checks ran.

    Raises:
        ParameterError: `starts` or `references` is negative, or `starts` is asked of a selection without a
            task read from a package.
        CatalogError: The catalog cannot be read, or the selection holds no task to audit.
    """
    say = progress or (lambda line: None)
    loaded = load_catalog(catalog)
    selected = loaded.select(selection)
    tasks = [t for t in selected if t.origin is not None]
    # A catalog of LangGap's own sentences (LIBERO's originals and generated tasks) gets the sentence check; a
    # package's catalog, the checks of its files (its originals are LIBERO's, checked with langgap99).
    own = [] if any(t.origin is not None for t in loaded) else selected
    for name, value in (("starts", starts), ("references", references)):
        if value < 0:
            raise ParameterError(f"{{{name}}} must be 0 (recorded findings) or a number of init states")
    if not tasks and not own:
        raise CatalogError(f"catalog {loaded.name}: no selected task was read from a package; nothing to audit")
    if not tasks and starts:
        raise ParameterError(
            "catalog {name}: {starts} checks tasks read from a package; none is selected", name=loaded.name
        )
    registry = registry_path(catalog)
    about, recorded = read_audit(registry)
    findings, ran = _sentence_check(own, say) if own else ([], {})
    if tasks:
        findings += files_findings(loaded, tasks) + [f for f in recorded if f.name == "unreadable"]
        ran["files"] = files_about(loaded)
        findings += _starts_check(loaded, tasks, catalog, selection, starts, about, recorded, ran, say)
    findings += _references_check(tasks + own, selection, references, about, recorded, ran, say)
    ids = [t.id for t in tasks]
    unreadable = [f.task for f in findings if f.name == "unreadable"]
    own_ids = [t.id for t in own]
    path = None
    if record:
        checked = {"files": ids + unreadable, "starts": ids, "sentence": own_ids, "references": ids + own_ids}
        for check, how in ran.items():
            path = record_audit(registry, check, how, [f for f in findings if f.name in CHECKS[check]], checked[check])
    return AuditResult(loaded, tuple(findings), tuple(ids), tuple(unreadable), tuple(own_ids), ran, about, path)


def _starts_check(
    catalog: Catalog,
    tasks: list[Task],
    name: str,
    selection: str | None,
    inits: int,
    about: dict,
    recorded: list,
    ran: dict,
    say: Say,
) -> list[Finding]:
    """The simulator checks' findings on package tasks: run now (on `inits` init states, added to `ran`), else as
    recorded."""
    if inits:
        from langgap.audit.starts import SEED, starts_findings

        found = starts_findings(catalog, tasks, inits, progress=say)
        ran["starts"] = {selection: {"inits": inits, "seed": SEED}}
        say(f"starts: checked on init states 0..{inits - 1} (seed {SEED})")
        return found
    if "starts" in about:
        for recorded_on, how in about["starts"].items():
            say(f"starts: recorded for tasks {recorded_on!r} on init states 0..{how['inits'] - 1} (rerun: --starts K)")
        chosen = {t.id for t in tasks}
        return [f for f in recorded if f.name in CHECKS["starts"] and f.task in chosen]
    say(f"starts: not checked (langgap tasks audit --catalog {name} --starts 50)")
    return []


def _references_check(
    tasks: list[Task], selection: str | None, inits: int, about: dict, recorded: list, ran: dict, say: Say
) -> list[Finding]:
    """The reference check's findings: run now (on `inits` init states, added to `ran`), else as recorded."""
    if inits:
        from langgap.audit.reference_check import VIEWS, reference_findings
        from langgap.audit.references import BETWEEN_ENDS, BETWEEN_WIDTH, MARGIN
        from langgap.audit.starts import SEED

        found, checked = reference_findings(tasks, inits, progress=say)
        unread = [f"{task}: {phrase}" for task, phrases in sorted(checked.unread.items()) for phrase in phrases]
        how = {"inits": inits, "seed": SEED, "margin_m": MARGIN, "judged": checked.judged_count}
        how |= {"between_ends": BETWEEN_ENDS, "between_width": BETWEEN_WIDTH, "viewpoints": list(VIEWS)}
        ran["references"] = {selection: how | {"unread": len(unread), "unread_examples": unread[:10]}}
        say(f"references: {checked.judged_count} expression(s) judged on init states 0..{inits - 1} "
            f"from the robot's viewpoint, the camera's (raw render) and in the policy's image (seed {SEED}); "
            f"{len(unread)} expression(s) not read")  # fmt: skip
        return found
    for recorded_on, how in about.get("references", {}).items():
        say(f"references: recorded for tasks {recorded_on!r} on init states 0..{how['inits'] - 1}, "
            f"{how['judged']} expression(s) judged, {how['unread']} not read (rerun: --references K)")  # fmt: skip
    chosen = {t.id for t in tasks}
    return [f for f in recorded if f.name in CHECKS["references"] and f.task in chosen]


def _sentence_check(tasks: list[Task], say: Say) -> tuple[list[Finding], dict]:
    """The sentence check over `tasks` (LangGap's own sentences): its findings, and how many tasks each
    template phrased (said with what each template's sentence allows and its goal checks)."""
    from langgap.audit.sentences import sentence_findings, template_counts, templates_text

    counts = template_counts(tasks, files.scene_problem)
    say(f"sentence: {len(tasks)} task(s) by template")
    say(templates_text(counts))
    findings = [f for t in tasks for f in sentence_findings(t, files.scene_problem(t))]
    return findings, {"sentence": {"templates": counts}}


# -- the file checks ---------------------------------------------------------------------------------------


def files_about(catalog: Catalog) -> dict:
    """How the file checks ran: the packages and versions whose files were read; and how many language variants
    share a sentence, exact and case-insensitively (`duplicate_counts`)."""
    read = sorted({(t.origin.package, t.origin.version) for t in catalog if t.origin is not None})
    return {
        "packages": [f"{package}=={version}" for package, version in read],
        "duplicate instructions": duplicate_counts(catalog),
    }


def files_findings(catalog: Catalog, tasks: list[Task]) -> list[Finding]:
    """LangGap's file checks on `tasks` (read from packages) of `catalog`: each one's BDDL against its source's,
    its goal, its instruction, the init states it ships; then duplicates among all of the catalog's tasks of
    their scenes."""
    found: list[Finding] = []
    checked = [t for t in tasks if t.origin is not None]
    for task in checked:
        text = packages.checked_bytes(task.origin).decode("utf-8")
        source = catalog.get(task.source)
        found += scene_findings(task.id, task.dimension, text, files.task_bddl_text(source))
        found += goal_findings(task.id, text)
        found += instruction_findings(task.id, task.instruction(InstructionStyle.PAPER), task.origin.file)
        found += runner_findings(task)
        found += init_findings(task, files.init_states(source))
    ids = {t.id for t in checked}
    scenes = {t.id: files.scene_key(t) for t in catalog}
    found += [f for f in duplicate_findings(catalog, lambda t: scenes[t.id]) if f.task in ids]
    return found
