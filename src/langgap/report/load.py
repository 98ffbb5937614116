"""Reading runs for reports: the stored spec, the gate verdicts the run relies on, and every episode record.

A report reads only the stored run: the feasibility verdicts behind its Oracle % and ⚠ columns are the
snapshot taken when the run was created (store meta `gate`), so a re-gate never changes a stored run's
report. Runs stored before snapshots were kept fall back to the catalog's live verdict file, and say so.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace
from pathlib import Path

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.split_files import load_split
from langgap.catalog.switch_verdicts import SwitchVerdicts, read_switch_verdicts, snapshot_switch_gates
from langgap.catalog.verdicts import GateResult, snapshot_gates
from langgap.errors import CatalogError, LangGapError
from langgap.records import EpisodeRecord, Privilege, privilege
from langgap.report.labels import SPLIT_PARTS
from langgap.store import PROGRESS, RunStore


@dataclass
class Run:
    """One stored run, as reports see it."""

    name: str  # shown in tables (`run_name`)
    path: Path
    spec: dict  # the run spec (`config` in stores written before run specs)
    records: list[EpisodeRecord]
    gates: dict[str, GateResult] = field(default_factory=dict)  # the feasibility verdicts of its tasks
    gate_hashes: list[str] | None = None  # SHA-256 of the verdict files of its snapshot (None: no snapshot)
    switch_gates: SwitchVerdicts = field(default_factory=dict)  # the switch gate's verdicts of its tasks, per K
    planned: int | None = None  # the episodes its spec plans (None: stored before runs recorded it)
    stopped: str | None = None  # why its last `evaluate` call ended before its plan did (None: it did not)

    @property
    def privilege(self) -> Privilege:
        """What the policy was given beyond a policy under test (`goal`: a scripted reference; `state`:
        it read simulator state)."""
        return privilege(self.records)

    @property
    def progress(self) -> str | None:
        """How much of its plan the run holds, and why not all of it (None: it holds every planned episode, or
        was stored before runs recorded their plan and holds some)."""
        stored = len(self.records)
        if self.planned is None:
            return None if stored else "the run is empty: it holds no episode"
        if stored >= self.planned:
            return None
        why = (
            f"it stopped early: {self.stopped}"
            if self.stopped
            else "no stop was recorded (it is still running, or it was killed)"
        )
        state = "incomplete" if stored else "empty"
        return f"the run is {state}: {stored} of {self.planned} planned episodes stored; {why}"

    @property
    def gate_source(self) -> str:
        """Where the run's feasibility verdicts come from, as its report states it."""
        if self.gate_hashes is None:
            return (
                "gate: the catalog's live verdict file (this run was stored before runs kept a snapshot; "
                "a re-gate changes its Oracle % and ⚠)"
            )
        if not self.gate_hashes:
            return "gate: no verdicts recorded when the run was created"
        hashes = ", ".join(h[:12] for h in self.gate_hashes)
        return f"gate: snapshot taken when the run was created (sha256 {hashes})"


def live_gates(spec: dict) -> dict[str, GateResult]:
    """The verdicts in the run's catalog's verdict file now (empty when it has none or cannot be read)."""
    try:
        catalog = load_catalog(spec["catalog"])
    except (KeyError, LangGapError):
        return {}
    return {task.id: task.gate for task in catalog if task.gate is not None}


def live_switch_gates(spec: dict) -> SwitchVerdicts:
    """The switch verdicts in the run's catalog's switch verdict file now (empty when it has none or cannot
    be read)."""
    from langgap.catalog.catalog import registry_path

    try:
        return read_switch_verdicts(registry_path(spec["catalog"]))
    except (KeyError, LangGapError):
        return {}


def run_name(policy: str, label: str) -> str:
    """How reports name a run: its label (its directory's name) with its policy after it, `pi05-ft (openpi)`,
    or the policy's name once when the label is that name, `oracle`."""
    return policy if label == policy else f"{label} ({policy})"


def split_groups(records: list[EpisodeRecord], catalog: str, split: str) -> list[EpisodeRecord]:
    """`records` grouped by a stored split instead of their tasks' own `split` field: each record's `split`
    becomes `trained (NAME)`, `held out (NAME)` or `outside NAME`, which reports show as they show the catalog's
    groups (the store is not touched).

    Args:
        records: A run's episode records.
        catalog: The run's catalog (its name or registry file): the split must be one of its.
        split: `NAME` (its training and held-out tasks) or `NAME:K` (its nested subset of K training tasks
            as the trained part): a shipped split's name or a split file's path (`langgap splits list`).

    Raises:
        CatalogError: No such split, or a split of another catalog or of another version of it.
    """
    parts, outside = _split_parts(catalog, split)
    return [replace(r, split=parts.get(r.task_id, outside)) for r in records]


@functools.cache
def _split_parts(catalog: str, split: str) -> tuple[dict[str, str], str]:
    """The group of each trained and held-out task of `split` in `catalog`, and the group of every other task:
    resolved once for all the runs of a report."""
    name, sep, subset = split.rpartition(":")
    if not (sep and subset.isdigit()):
        name, subset = split, "train"
    tasks = load_catalog(catalog)
    if (of := load_split(name).catalog) != tasks.name:
        raise CatalogError(f"split {name} is of catalog {of}; this run is of {tasks.name}")
    trained, held_out, outside = (part.format(n) for part, n in zip(SPLIT_PARTS, (split, name, name), strict=True))
    parts = {t.id: held_out for t in tasks.select(f"split:{name}:heldout")}
    return parts | {t.id: trained for t in tasks.select(f"split:{name}:{subset}")}, outside


def load_runs(paths: list[str | Path], *, split: str | None = None) -> list[Run]:
    """Read runs from their stores (while they are being written, too).

    Args:
        paths: Run directories (each the `run` of an `evaluate`).
        split: Group each run's episodes by this stored split (`split_groups`) instead of their tasks' own
            split (None: their own).

    Returns:
        One `Run` per path, in order: its name, spec and episode records, and the gate verdicts its report
        reads (those stored with the run when it was created; the catalog's current ones for a run stored
        before snapshots were kept).

    Raises:
        StoreError: A path holds no run store, or one this LangGap cannot read.
        CatalogError: `split` is not a split of a run's catalog.
    """
    runs = []
    for path in paths:
        with RunStore.open(path) as store:
            spec = store.meta("spec") or store.meta("config") or {}
            snapshot = store.meta("gate")
            records = store.records()
            progress = store.meta(PROGRESS) or {}
        if split is not None:
            records = split_groups(records, spec.get("catalog") or DEFAULT_CATALOG, split)
        gates = live_gates(spec) if snapshot is None else snapshot_gates(snapshot)
        hashes = None if snapshot is None else list(snapshot["sha256"])
        # Runs stored before the snapshot kept switch verdicts read the live file, as for the plain ones.
        switch = (snapshot or {}).get("switch")
        switch_gates = live_switch_gates(spec) if switch is None else snapshot_switch_gates(switch)
        name = run_name(str(spec.get("policy", "?")), Path(path).name)
        planned, stopped = progress.get("planned"), progress.get("stopped")
        runs.append(Run(name, Path(path), spec, records, gates, hashes, switch_gates, planned, stopped))
    return runs
