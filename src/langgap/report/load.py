"""Reading runs for reports: the stored spec and every episode record of each run."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from langgap.records import EpisodeRecord, Privilege, privilege
from langgap.store import RunStore


@dataclass
class Run:
    """One stored run, as reports see it."""

    name: str  # shown in tables: the policy and the run directory's name
    path: Path
    spec: dict  # the run spec (`config` in stores written before run specs)
    records: list[EpisodeRecord]

    @property
    def privilege(self) -> Privilege:
        """What the policy was given beyond a policy under test (`goal`: a scripted reference; `state`:
        it read simulator state)."""
        return privilege(self.records)


def load_runs(paths: list[str | Path]) -> list[Run]:
    """Read runs from their stores (while they are being written, too)."""
    runs = []
    for path in paths:
        with RunStore.open(path) as store:
            spec = store.meta("spec") or store.meta("config") or {}
            records = store.records()
        runs.append(Run(f"{spec.get('policy', '?')} ({Path(path).name})", Path(path), spec, records))
    return runs
