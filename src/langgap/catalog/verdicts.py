"""Feasibility verdicts: a verdict on one task (`GateResult`), how each reads wherever it is shown, and a catalog's
verdicts, kept beside its registry file as `<registry>.gate.json`.

A registry defines tasks; whether a scripted oracle could do them is a measurement that `langgap
validate --record` (or `langgap generate --gate-inits K`) makes and re-makes. Keeping the two apart
means regenerating or editing a registry never loses verdicts, and re-validating never rewrites task
definitions. A verdict names the task id it belongs to; one for an id the registry lacks is ignored.
"""

from __future__ import annotations

import dataclasses
import fcntl
import hashlib
import json
import os
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from langgap.atomic import write_text_atomically
from langgap.errors import CatalogError
from langgap.stack import installed_differences
from langgap.vocabulary import CEILING_TARGET, Verdict

# The gate's check that a task's starts come to rest; a verdict's `reason` names the checks it failed, and one
# that failed this one is `Verdict.UNSETTLED`.
SETTLE_CHECK = "scene settles"
# Why a task may take another's verdict: the gate's oracle reads the goal, never the instruction, so two tasks
# with the same scene file outside `(:language)`, the same init states, goal and step limit get the same episodes.
SAME_TRIAL = "the same scene file outside (:language), init states, goal and step limit"


def unproven(successes: int, episodes: int) -> str:
    """How a task the oracle fails, with no proof that a policy cannot do it, reads wherever it is shown."""
    return f"{Verdict.UNPROVEN}: the oracle does not do it ({successes}/{episodes}); no proof that a policy cannot"


def unsettled(successes: int, episodes: int) -> str:
    """How a task rejected because its starts do not come to rest reads wherever it is shown, with what the
    oracle did on it."""
    return f"{Verdict.UNSETTLED}: its starts do not come to rest (the oracle did it {successes}/{episodes})"


def infeasible(proof: str = "") -> str:
    """How a task proven impossible reads wherever it is shown (with the proof, when given)."""
    return f"{Verdict.INFEASIBLE}: a proof that no policy can do it" + (f": {proof}" if proof else "")


def verdict_of(feasible: bool, proof: str, reason: str) -> Verdict:
    """The word for a gate's decision on a task: admitted (`feasible`), rejected with a `proof`, or rejected for
    `reason` (the checks it failed, joined by "; "): its starts do not come to rest, or anything else."""
    if feasible:
        return Verdict.DOABLE
    if proof:
        return Verdict.INFEASIBLE
    return Verdict.UNSETTLED if SETTLE_CHECK in reason.split("; ") else Verdict.UNPROVEN


def verdict_counts(
    verdicts: Iterable[Verdict], always: tuple[Verdict, ...] = (Verdict.DOABLE, Verdict.UNPROVEN)
) -> str:
    """How many of each verdict, in `Verdict`'s order (`3 doable, 1 unproven`): those in `always`, and any other
    that occurs."""
    counts = Counter(verdicts)
    return ", ".join(f"{counts[v]} {v}" for v in Verdict if v in always or counts[v])


@dataclass(frozen=True)
class GateResult:
    """A feasibility gate's verdict on one task: how a scripted oracle did, and whether the task is kept.

    The gate runs init states 0..`inits`-1; `failed_inits` lists those the oracle failed (None in
    verdicts recorded before per-init results were kept), so the oracle's ceiling can be given for
    exactly the init states a run used. `made_by` says which policy, code version and stepping ran the
    gate for this verdict (a file mixes verdicts of several recordings when tasks are re-validated one
    by one; empty in verdicts recorded before it was kept), and `physics` the physics stack and conventions
    it ran on (`langgap.stack.physics_stack`, as results record it; empty: not recorded).

    What a verdict shows: a task is doable when a demonstration did it — the oracle, at the gate's
    rate, or `demonstration`, a stored replayable episode (a path relative to the registry's directory)
    that does a task the oracle fails; it is impossible only by `proof`, an argument that holds for
    every policy, printed with its assumptions (`langgap.gate.proofs`). A task the oracle fails without
    either is *unproven*: nobody has shown it doable or impossible. A task whose starts do not come to
    rest is *unsettled*, whatever the oracle did (`verdict`: the word, `langgap.vocabulary.Verdict`).
    """

    episodes: int
    successes: int
    feasible: bool
    reason: str = ""
    inits: int = 0
    failed_inits: tuple[int, ...] | None = None
    made_by: str = ""
    proof: str = ""
    demonstration: str = ""
    demonstrated_inits: tuple[int, ...] = ()  # init states the oracle failed that a searched episode did
    physics: dict = field(default_factory=dict)
    # `catalog:task id` whose verdict this is, by identity (the task's `gate_from`); empty: the task's own.
    inherited_from: str = ""

    def __post_init__(self) -> None:
        if not 0 <= self.successes <= self.episodes:
            raise CatalogError(f"gate result: {self.successes} successes in {self.episodes} episodes")
        if self.failed_inits is not None:
            object.__setattr__(self, "failed_inits", tuple(self.failed_inits))  # JSON gives a list
        object.__setattr__(self, "demonstrated_inits", tuple(self.demonstrated_inits))
        if self.proof and self.feasible:
            raise CatalogError("gate result: feasible, yet with a proof that the task is impossible")

    @property
    def rate(self) -> float:
        """Oracle success rate (0 when no episode ran)."""
        return self.successes / self.episodes if self.episodes else 0.0

    def oracle_on(self, inits: list[int] | tuple[int, ...]) -> tuple[int, int]:
        """(successes, episodes) of the oracle on the init states `inits` that the gate ran; the gate's
        whole result when it kept no per-init results or ran none of them."""
        covered = [i for i in inits if i < self.inits]
        if self.failed_inits is None or not covered:
            return self.successes, self.episodes
        failed = set(self.failed_inits)
        return sum(i not in failed for i in covered), len(covered)

    @property
    def verdict(self) -> Verdict:
        """The verdict's word (`verdict_of`)."""
        return verdict_of(self.feasible, self.proof, self.reason)

    def capped_because(self, successes: int, episodes: int) -> str | None:
        """Why the task is marked ⚠ beside a policy's results, given the oracle's `successes` in `episodes`
        on the init states in question (None: it is not), led by its verdict's word: proven infeasible, its
        starts do not come to rest, or an oracle below `CEILING_TARGET` — which shows only that the oracle does
        not do it, not that no policy can (an admitted task too: the gate admits at a lower rate)."""
        verdict = self.verdict
        if verdict is Verdict.INFEASIBLE:
            return infeasible()
        if verdict is Verdict.UNSETTLED:
            return unsettled(successes, episodes)
        if not episodes or successes / episodes >= CEILING_TARGET:
            return None
        if verdict is Verdict.UNPROVEN:
            return unproven(successes, episodes)
        if self.demonstrated:
            return f"{verdict} by a searched demonstration; the oracle does {successes}/{episodes} of these init states"
        return f"{verdict}, but the oracle does only {successes}/{episodes} of these init states"

    @property
    def demonstrated(self) -> bool:
        """True when a stored demonstration, not the oracle's rate, is what makes the task doable."""
        return self.feasible and bool(self.demonstration)

    @property
    def evidence(self) -> str:
        """How the verdict is shown, led by its word: by the oracle's episodes or a searched demonstration
        (doable), a proof (infeasible), starts that do not come to rest (unsettled), or not at all (unproven);
        an inherited verdict says whose it is."""
        if self.inherited_from:
            own = dataclasses.replace(self, inherited_from="").evidence
            return f"{own} — the verdict of {self.inherited_from}: {SAME_TRIAL}"
        verdict = self.verdict
        if verdict is Verdict.INFEASIBLE:
            return infeasible(self.proof)
        if verdict is Verdict.DOABLE:
            made_by = f"made by {self.made_by}" if self.made_by else "recorded before who made it was kept"
            text = f"{verdict}: oracle {self.successes}/{self.episodes} init states ({made_by})"
            if self.demonstrated:
                shown = ", ".join(map(str, self.demonstrated_inits)) or "?"
                text += f"; searched demonstration on init state(s) {shown}: {self.demonstration}"
            return text
        if verdict is Verdict.UNSETTLED:
            text = unsettled(self.successes, self.episodes)
        elif self.oracle_short:
            text = unproven(self.successes, self.episodes)
        else:
            text = f"{verdict}: the gate's checks fail (the oracle did it {self.successes}/{self.episodes}); no proof "
            text += "that a policy cannot"
        if self.demonstration and self.demonstrated_inits:
            shown = ", ".join(map(str, self.demonstrated_inits))
            text += f"; a searched demonstration does init state(s) {shown}: {self.demonstration}"
        if self.reason and self.reason != f"oracle {self.successes}/{self.episodes}":
            text += f"; the gate's reason: {self.reason}"
        return text

    @property
    def oracle_short(self) -> bool:
        """Whether the verdict was rejected for the oracle's rate (its reason names the oracle's count; a verdict
        rejected with no reason recorded is taken to be)."""
        return not self.feasible and (not self.reason or any(c.startswith("oracle ") for c in self.reason.split("; ")))

    @property
    def other_stack(self) -> list[str]:
        """How the physics stack the verdict was made on differs from the installed one (empty: it does not;
        `langgap.stack.installed_differences`)."""
        return installed_differences(self.physics)

    @property
    def capped(self) -> bool:
        """True when the task is marked ⚠ on the init states the gate ran (`capped_because`)."""
        return self.capped_because(self.successes, self.episodes) is not None


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
