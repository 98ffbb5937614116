"""Feasibility verdicts of a catalog, kept beside its registry file as `<registry>.gate.json`.

A registry defines tasks; whether a scripted oracle could do them is a measurement that `langgap
validate --record` (or `langgap generate --gate-inits K`) makes and re-makes. Keeping the two apart
means regenerating or editing a registry never loses verdicts, and re-validating never rewrites task
definitions. A verdict names the task id it belongs to; one for an id the registry lacks is ignored.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from langgap.atomic import write_text_atomically
from langgap.catalog.task import GateResult
from langgap.errors import CatalogError


def verdicts_path(registry: str | Path) -> Path:
    registry = Path(registry)
    return registry.with_name(registry.name.removesuffix(".yaml") + ".gate.json")


def read_verdicts(registry: str | Path) -> dict[str, GateResult]:
    """The recorded verdicts for the registry at `registry` (empty if none were recorded)."""
    path = verdicts_path(registry)
    if not path.is_file():
        return {}
    return _parse(path, read_bytes(path))


def read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        raise CatalogError(f"cannot read feasibility verdicts {path}: {exc}") from None


def _parse(path: Path, content: bytes) -> dict[str, GateResult]:
    try:
        data = json.loads(content.decode("utf-8"))
        return {task_id: _verdict(fields) for task_id, fields in data["tasks"].items()}
    except (ValueError, KeyError, TypeError) as exc:
        raise CatalogError(f"cannot read feasibility verdicts {path}: {exc}") from None


def _verdict(fields: dict) -> GateResult:
    # A file written by an older LangGap keeps a `certificate` per verdict (`langgap certify`): an
    # enumeration of 930 grasp poses that found none clear, which called two bottom drawers infeasible
    # until a pressed drag opened them. An enumeration of strategies is not a proof that no policy can
    # do a task, so the key is dropped on reading and never shown.
    fields = {k: v for k, v in fields.items() if k != "certificate"}
    return GateResult(**fields)


@contextmanager
def exclusive(directory: Path) -> Iterator[None]:
    """Hold an exclusive lock on `directory` (the verdict file itself is replaced, so cannot hold one)."""
    directory.mkdir(parents=True, exist_ok=True)
    fd = os.open(directory, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # and with it the lock


def record_verdicts(registry: str | Path, verdicts: dict[str, GateResult], about: dict | None) -> Path:
    """Merge `verdicts` into the registry's verdict file (atomically); `about` describes how they were made
    (None keeps the file's)."""
    path = verdicts_path(registry)
    with exclusive(path.parent):  # read, merge and write as one step: a concurrent recording is not lost
        merged = read_verdicts(registry) | verdicts
        if about is None:
            about = json.loads(path.read_text(encoding="utf-8")).get("about", {}) if path.is_file() else {}
        data = {"about": about, "tasks": {k: asdict(merged[k]) for k in sorted(merged)}}
        write_text_atomically(path, json.dumps(data, indent=1, sort_keys=True) + "\n")
    return path


def snapshot_verdicts(
    registry: str | Path,
    task_ids: Iterable[str],
    previous: dict | None = None,
    inherited: Mapping[str, tuple[Path, str]] | None = None,
) -> dict:
    """What a run relies on from the gate, stored with it so that a re-gate never changes its report: the
    verdicts of `task_ids` (each whole, with its per-init results) and the SHA-256 of each verdict file they
    were read from (none: the catalog has no verdict file). `inherited` maps a task that takes another's
    verdict to that task's registry and `catalog:id`; its verdict is read from there. `previous`, a run's
    earlier snapshot, is kept as it is: only tasks it lacks (a run grown with `--extend`) get verdicts, and
    their files' hashes are added."""
    inherited = dict(inherited or {})
    own = [t for t in task_ids if t not in inherited]
    snapshot = snapshot_file(verdicts_path(registry), own, previous, _parse, asdict)
    labels_by_file: dict[Path, dict[str, str]] = {}
    for task_id, (source_registry, label) in inherited.items():
        labels_by_file.setdefault(verdicts_path(source_registry), {})[task_id] = label
    for path, labels in labels_by_file.items():

        def taken(path: Path, content: bytes, labels: dict[str, str] = labels) -> dict[str, GateResult]:
            verdicts = _parse(path, content)
            sources = {task_id: label.partition(":")[2] for task_id, label in labels.items()}
            return {t: replace(verdicts[s], inherited_from=labels[t]) for t, s in sources.items() if s in verdicts}

        snapshot = snapshot_file(path, labels, snapshot, taken, asdict)
    return snapshot


def snapshot_file(
    path: Path,
    task_ids: Iterable[str],
    previous: dict | None,
    parse: Callable[[Path, bytes], dict[str, Any]],
    dump: Callable[[Any], Any],
) -> dict:
    """`snapshot_verdicts` of any verdict file: `parse` reads its content (task id -> verdict), `dump` turns
    one task's verdict into the data stored."""
    content = read_bytes(path) if path.is_file() else None
    verdicts = parse(path, content) if content is not None else {}
    digest = hashlib.sha256(content).hexdigest() if content is not None else None
    snapshot = previous or {"file": path.name, "sha256": [], "tasks": {}}
    added = {t: dump(verdicts[t]) for t in task_ids if t in verdicts and t not in snapshot["tasks"]}
    hashes = list(snapshot["sha256"])
    if digest is not None and digest not in hashes and (added or previous is None):
        hashes.append(digest)
    return {**snapshot, "sha256": hashes, "tasks": {**snapshot["tasks"], **added}}


def snapshot_gates(snapshot: dict) -> dict[str, GateResult]:
    """The verdicts a run's snapshot (`snapshot_verdicts`) holds."""
    return {task_id: _verdict(fields) for task_id, fields in snapshot["tasks"].items()}
