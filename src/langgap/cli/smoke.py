"""`LANGGAP_SMOKE=1`: every command at its smallest, to check that it runs, not what it measures.

The documentation's tests run every command of README.md and docs/ as written; with this variable set, a
command that simulates keeps its meaning but shrinks its work — the first two tasks of its selection, one
episode, init state, demonstration or start, at most two workers, a few training steps — and says so on
stderr, one `note:` line naming each option it changed and how (training keeps the selected tasks its shrunk
collections hold). Nothing is shrunk silently, and what a run
stores is what ran: a shrunk run's spec names the two tasks and one episode.

A parser declares what may shrink with `parser.set_defaults(smoke=(...))`, naming entries of `CAPS` and
`SELECTION` (its task selection, `tasks`).
"""

from __future__ import annotations

import os
import sys

ENV = "LANGGAP_SMOKE"
# option (argparse dest) -> the most it keeps
CAPS = {
    "episodes": 1,
    "repeats": 1,
    "inits": 1,
    "gate_inits": 1,
    "demos": 1,
    "starts": 1,
    "references": 1,
    "steps": 20,
    "workers": 2,
}
SELECTION = "tasks"
TASKS = 2  # a selection keeps its first TASKS tasks
# Training's selection keeps the tasks its collections (`--data`, shrunk themselves) attempted.
COLLECTED = "collected_tasks"


def enabled() -> bool:
    """True when `LANGGAP_SMOKE` asks for shrunk commands."""
    return os.environ.get(ENV, "").lower() in ("1", "true", "yes")


def _flag(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _shrink_selection(args) -> str | None:
    """Narrow `args.tasks` to its first `TASKS` tasks; the note's text, or None when it already is that small."""
    from langgap.catalog.catalog import load_catalog

    given = getattr(args, SELECTION)
    tasks = load_catalog(args.catalog).select(given)
    if len(tasks) <= TASKS:
        return None
    setattr(args, SELECTION, ",".join(t.id for t in tasks[:TASKS]))
    named = "the default selection" if given is None else repr(given)
    return f"task selection {named} -> {getattr(args, SELECTION)} (the first {TASKS} of {len(tasks)} tasks)"


def _shrink_to_collected(args) -> str | None:
    """Narrow a training selection to the tasks its collections attempted; the note's text, or None."""
    if args.tasks is None or not args.data:
        return None
    from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
    from langgap.demos.compact import read_manifest

    selected = [t.id for t in load_catalog(args.catalog or DEFAULT_CATALOG).select(args.tasks)]
    attempted = {task for root in args.data for task in read_manifest(root)["tasks"]}
    kept = [t for t in selected if t in attempted]
    if not kept or len(kept) == len(selected):
        return None
    given, args.tasks = args.tasks, ",".join(kept)
    return f"task selection {given!r} -> {args.tasks} (the {len(kept)} of {len(selected)} its collections attempted)"


def shrink(args) -> list[str]:
    """Shrink the options `args.smoke` names, in place; one description per option changed."""
    changes = []
    for dest in getattr(args, "smoke", ()):
        if dest in (SELECTION, COLLECTED):
            change = _shrink_selection(args) if dest == SELECTION else _shrink_to_collected(args)
            changes += [change] if change else []
            continue
        value, cap = getattr(args, dest), CAPS[dest]
        if value is not None and value > cap:
            setattr(args, dest, cap)
            changes.append(f"{_flag(dest)} {value} -> {cap}")
    return changes


def apply(args) -> None:
    """With `LANGGAP_SMOKE` set, shrink `args` (`shrink`) and say how on stderr."""
    if not enabled():
        return
    changes = shrink(args)
    if changes:
        print(f"note: {ENV} is set, so this command is shrunk: {'; '.join(changes)}", file=sys.stderr, flush=True)
