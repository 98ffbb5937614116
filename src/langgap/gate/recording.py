"""Writing the gate's verdicts beside a catalog's registry, with proofs of impossibility and the searched
demonstrations they rest on."""

from __future__ import annotations

import warnings
from pathlib import Path

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.catalog.verdicts import record_verdicts
from langgap.gate.rows import TaskValidation
from langgap.stack import DEFAULT_STEPPING, physics_stack
from langgap.version import code_version
from langgap.vocabulary import FEASIBLE_RATE


def beside_registry(path: Path, catalog_name: str) -> str:
    """`path` relative to the catalog registry's directory when it lies there (as verdicts name their
    evidence), else as it is."""
    try:
        return path.resolve().relative_to(registry_path(catalog_name).parent.resolve()).as_posix()
    except ValueError:
        return str(path)


def demonstrations_dir(catalog_name: str) -> Path:
    """Where `validate --record` stores a catalog's searched demonstrations: beside its registry file."""
    registry = registry_path(catalog_name)
    return registry.parent / "demonstrations" / registry.stem


def prove_rejected(catalog_name: str, rows: list[TaskValidation], inits: int) -> dict[str, str]:
    """Proofs of impossibility (`langgap.gate.proofs`) for the tasks the oracle did below the gate's rate, read
    from each task's simulator on init states 0..`inits`-1: task id -> the proof's text, for those that
    have one. A task with none stays unproven: the oracle failing it shows nothing about other policies."""
    from langgap.gate.proofs import prove_tasks

    catalog = load_catalog(catalog_name)
    below = {r.id: r for r in rows if r.short}
    found = {}
    for task_id, proof in prove_tasks([catalog.get(i) for i in below], inits).items():
        if below[task_id].successes:  # an episode refutes it: the prover is wrong, not the episodes
            warnings.warn(f"{task_id}: a proof of impossibility, yet the gate did it {below[task_id].successes} "
                          f"time(s); not recorded: {proof.text()}", stacklevel=2)  # fmt: skip
        else:
            found[task_id] = proof.text()
    return found


def provenance(policy: str, inits: int, stepping: str, **rate: float) -> tuple[dict, str]:
    """How a recording's verdicts were made: the verdict file's `about` (policy, init states, the gate's `rate`,
    physics stack, code version) and the `made_by` text each verdict keeps."""
    physics = physics_stack(stepping)
    about = {"policy": policy, "inits": inits, **rate, "physics": physics, "code_version": code_version()}
    return about, f"{policy}, langgap {about['code_version']}, {stepping} stepping"


def record(
    catalog_name: str,
    rows: list[TaskValidation],
    *,
    inits: int,
    policy: str = "oracle",
    stepping: str = DEFAULT_STEPPING,
    proofs: dict[str, str] | None = None,
) -> Path:
    """Record the rows' verdicts beside the catalog's registry file, with the proofs of impossibility
    `proofs` gives (None: those `prove_rejected` finds)."""
    about, made_by = provenance(policy, inits, stepping, feasible_rate=FEASIBLE_RATE)
    if proofs is None:
        proofs = prove_rejected(catalog_name, rows, inits)
    # Each verdict keeps its own stack: a file mixes verdicts of several recordings (and stacks), `about` is the last's.
    verdicts = {r.id: r.verdict(inits, made_by, proofs.get(r.id, ""), about["physics"]) for r in rows}
    return record_verdicts(registry_path(catalog_name), verdicts, about)
