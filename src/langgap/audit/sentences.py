"""The audit's sentence check: does a task's goal accept exactly what its sentence allows?

LangGap's own catalogs (`langgap99`, `full`, `langgap-beyond`) phrase every goal with a handful of sentence
templates. `TEMPLATES` states, per template, what its sentence allows, what the goal checks, and why the two
agree (or by which of LIBERO's conventions). `sentence_findings` puts each task under its template and checks
the goal's form against what the template's sentence allows: a goal that rejects a state the sentence allows is
*narrower* than its sentence, one that accepts a state the sentence forbids is *wider*.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from langgap.audit.findings import Finding
from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import affordances
from langgap.catalog.task import Task
from langgap.goals import And, Atom, Not, Or, Then, plain_atoms
from langgap.vocabulary import Dimension


@dataclass(frozen=True)
class Template:
    """One sentence template: an example, what the sentence allows, what the goal checks, the verdict."""

    example: str
    allows: str
    checks: str
    verdict: str


_LIBERO_PLACE = (
    "LIBERO's own judge: an object is `On` another when they touch and its origin is above and within 3 cm "
    "(xy) of the other's, `On`/`In` a region when its origin is over / inside the region's box"
)
TEMPLATES = {
    "place": Template(
        "pick up the black bowl next to the plate and place it on the cookie box",
        "that object ends on (in) that receiver",
        "(On X Y) or (In X Y)",
        f"agree by convention: {_LIBERO_PLACE}; success is the state, so X still in the hand counts (as in "
        "every LIBERO task); `In` the basket, a drawer, a caddy compartment is LIBERO's region for it",
    ),
    "push": Template(
        "push the plate to the front of the stove",
        "the plate ends at that spot of the table, pushed there",
        "(On plate_1 <table spot>)",
        "agree by convention: LIBERO judges where things end, not how they got there (a plate lifted there counts)",
    ),
    "articulate": Template(
        "open the top drawer of the cabinet; turn on the stove",
        "that part ends in that state",
        "(Open d), (Close d), (Turnon s), (Turnoff s)",
        "agree by convention: LIBERO's joint intervals for open, closed, on and off",
    ),
    "both": Template(
        "put both the alphabet soup and the tomato sauce in the basket",
        "both parts hold at the end",
        "(And A B): both hold",
        "agree (where the sentence orders them, 'put the bowl in the drawer and close it', the other order cannot "
        "end in that state: a closed drawer takes nothing)",
    ),
    "ordering": Template(
        "first turn on the stove, then put the bowl on the plate",
        "A done, then B done, both still done at the end",
        "(Then A B): both hold, and A first held before B first held",
        "agree by convention: the order is the order of first times (a B that held for a moment before A counts "
        "as B first, a part undone and redone keeps its first time)",
    ),
    "not-where": Template(
        "pick up the black bowl … and place it anywhere but on the plate",
        "X set down anywhere (on another receiver, in a drawer, on the bare table) except on Y",
        "(And (Or <X on each other receiver that takes it> (Moved X)) (Not (On X Y)))",
        "agree once the `Or` holds `(Moved X)`: X moved by the hand, away from where it started, resting out of it; "
        "the receivers are LIBERO's placements (the witness the BDDL file states, the oracle's aim)",
    ),
    "not-what": Template(
        "pick up anything but the ketchup and place it in the basket",
        "any other object the receiver takes ends on (in) it; X does not",
        "(And (Or <each other object Y takes, on Y>) (Not (On X Y)))",
        "agree once the `Or` lists every other object Y takes (an object holding another at t0 included: the "
        "sentence allows clearing it first); what Y takes is the catalog's affordance rules (a plate goes into "
        "no bowl, nothing onto a bottle)",
    ),
}
# Which negation template a `langgap-beyond` id's variant names (`beyond.NEGATED_PARTS`' keys).
_NEGATION_VARIANTS = ("not-where", "not-what")


def template_of(task: Task, scene: BddlProblem) -> str:
    """The template `task`'s sentence follows (a key of `TEMPLATES`)."""
    variant = task.id.rpartition("~")[2]
    if task.dimension == Dimension.NEGATION and variant in _NEGATION_VARIANTS:
        return variant
    if isinstance(task.goal, Then):
        return "ordering"
    atoms = plain_atoms(task.goal) or ()
    if len(atoms) != 1:
        return "both"
    (atom,) = atoms
    if affordances.is_articulation(atom):
        return "articulate"
    return "push" if affordances.is_push(atom, scene) else "place"


def _negation_parts(task: Task) -> tuple[tuple[Predicate, ...], Predicate | None]:
    """The alternatives of a negation goal's `Or` and its negated atom (None if the goal has no such form)."""
    parts = task.goal.parts if isinstance(task.goal, And) else (task.goal,)
    ors = [p for p in parts if isinstance(p, Or)]
    nots = [p.part.predicate for p in parts if isinstance(p, Not) and isinstance(p.part, Atom)]
    alternatives = tuple(a.predicate for o in ors for a in o.parts if isinstance(a, Atom))
    return alternatives, nots[0] if nots else None


def _not_where(task: Task, scene: BddlProblem, negated: Predicate | None, alternatives) -> list[Finding]:
    obj = (negated or alternatives[0]).args[0]
    found = []
    if Predicate.of("Moved", (obj,)) not in alternatives:
        named = len({p.args[1] for p in alternatives})
        found.append(
            Finding(
                "goal narrower than its sentence",
                task.id,
                f"{obj} set down elsewhere (the bare table) fails: the goal accepts {named} named places only",
            )
        )
    return found


def _not_what(task: Task, scene: BddlProblem, negated: Predicate | None, alternatives) -> list[Finding]:
    target = (negated or alternatives[0]).args[1]
    allowed = [p for p in affordances.placements_onto(target, scene) if negated is None or p.args[0] != negated.args[0]]
    missing = [str(p) for p in allowed if p not in alternatives]
    if not missing:
        return []
    return [Finding("goal narrower than its sentence", task.id, f"not accepted: {', '.join(missing)}")]


_CHECKS: dict[str, Callable[..., list[Finding]]] = {"not-where": _not_where, "not-what": _not_what}


def sentence_findings(task: Task, scene: BddlProblem) -> list[Finding]:
    """Where `task`'s goal (on `scene`) accepts more or less than its sentence's template allows."""
    template = template_of(task, scene)
    check = _CHECKS.get(template)
    if check is None:
        return []
    alternatives, negated = _negation_parts(task)
    found = []
    if negated is None:
        found.append(Finding("goal wider than its sentence", task.id, "nothing excludes what the sentence negates"))
    if not alternatives:
        return [*found, Finding("goal narrower than its sentence", task.id, "no alternative to the negated goal")]
    return found + check(task, scene, negated, alternatives)


def template_counts(tasks: Iterable[Task], scene_of: Callable[[Task], BddlProblem]) -> dict[str, int]:
    """How many of `tasks` follow each template, in `TEMPLATES`' order (templates with none left out)."""
    counts = dict.fromkeys(TEMPLATES, 0)
    for task in tasks:
        counts[template_of(task, scene_of(task))] += 1
    return {name: n for name, n in counts.items() if n}


def templates_text(counts: dict[str, int]) -> str:
    """Per template used: how many tasks, what the sentence allows, what the goal checks, the verdict."""
    lines = []
    for name, n in counts.items():
        t = TEMPLATES[name]
        lines += [
            f"{name}: {n} task(s), e.g. {t.example!r}",
            f"  sentence allows: {t.allows}",
            f"  goal checks: {t.checks}",
            f"  verdict: {t.verdict}",
        ]
    return "\n".join(lines)
