"""The protocol card: what determines a run's numbers, from its stored spec and episode records.

Runs are compared episode by episode only when their protocols (`PROTOCOL_ITEMS`) agree; the rest
of the card says what the policy was and what it saw.
"""

from __future__ import annotations

from collections.abc import Iterable

from langgap.catalog.task import PACKAGE_STYLE
from langgap.records import Privilege
from langgap.report.load import Run

# What determines a run's numbers besides the policy: runs compared episode by episode must agree on these.
PROTOCOL_ITEMS = (
    "catalog",
    "catalog hash",
    "instruction style",
    "step limits",
    "settle steps",
    "init states",
    "seeds",
    "physics",
)
# The card's `privileged` item: what the policy was given beyond a policy under test.
PRIVILEGE_CARD = {
    Privilege.GOAL: "told the goal (a scripted reference)",
    Privilege.STATE: "reads simulator state (not told the goal)",
    Privilege.NONE: "no",
}
# The protocol card: the protocol, then what the policy was and saw.
CARD_ITEMS = (
    *PROTOCOL_ITEMS,
    "conditions",
    "policy",
    "policy arguments",
    "policy config hash",
    "privileged",
    "cameras",
    "code version",
)


def _joined(values: Iterable) -> str:
    return ", ".join(str(v) for v in values) or "–"


def _indices(values: list[int]) -> str:
    """`0–19` for a contiguous range, else the list."""
    values = sorted(values)
    if values and values == list(range(values[0], values[-1] + 1)) and len(values) > 2:
        return f"{values[0]}–{values[-1]}"
    return _joined(values)


def _seeds(spec: dict) -> str:
    if "seed" not in spec:
        return "?"
    repeats = spec.get("repeats", 1)
    return f"run seed {spec['seed']} + init index" + (f", {repeats} repeats" if repeats > 1 else "")


def _style(spec: dict) -> str:
    """The instruction style, saying what `package` sends."""
    style = str(spec.get("style", "?"))
    return f"{style} (the benchmark runner's task.language)" if style == PACKAGE_STYLE else style


def protocol_card(run: Run) -> dict[str, str]:
    """What determines a run's numbers, as shown at the top of its report (from its spec and records)."""
    spec, records = run.spec, [r for r in run.records if r.judged] or run.records
    inits = spec.get("inits") or sorted({r.init_index for r in records})
    steps = {r.suite: r.max_steps for r in records}
    cameras = {(tuple(r.cameras), r.image_size) for r in records}
    return {
        "catalog": str(spec.get("catalog", "?")),
        "catalog hash": str(spec.get("catalog_hash", "?"))[:12],
        "instruction style": _style(spec),
        "step limits": _joined(f"{suite} {n}" for suite, n in sorted(steps.items())),
        "settle steps": _joined(sorted({r.settle_steps or "?" for r in records}, key=str)),  # 0: not recorded
        "init states": _indices(list(inits)),
        "seeds": _seeds(spec),
        "physics": _joined(f"{k} {v}" for k, v in sorted(spec.get("physics", {}).items())),
        "conditions": _joined(spec.get("conditions") or sorted({r.condition for r in records})),
        "policy": str(spec.get("policy", "?")),
        "policy arguments": _joined(f"{k}={v}" for k, v in sorted(spec.get("policy_args", {}).items())),
        "policy config hash": _joined(sorted({r.policy_config_hash for r in records if r.policy_config_hash})),
        "privileged": PRIVILEGE_CARD[run.privilege],
        "cameras": _joined(
            f"{', '.join(c) or 'none'}" + (f" at {size} px" if size else "") for c, size in sorted(cameras)
        ),
        "code version": _joined(sorted({r.code_version for r in records})),
    }
