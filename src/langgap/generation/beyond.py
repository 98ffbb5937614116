"""The `langgap-beyond` catalog: four dimensions beyond the paper's, on the scenes and init states of
LIBERO's 40 originals, generated from their BDDL.

Each original task (a *source*) gets, on its own scene and init states:

* **ordering** — "first A, then B" and "first B, then A" (`(Then A B)`), for two sub-goals that can be
  done in either order: the source's own goal and each articulation of the scene (or, for an
  articulation source, each pick-and-place goal of the scene's other originals), or the two parts of
  a two-part source. Both end in the same state; only the order tells them apart.
* **negation** — the source's sentence with its destination or object negated ("… anywhere but on
  the plate", "anything but the ketchup …"): the object on another receiver it can take or set down
  anywhere else (an `Or` over them and `Moved`) and not on the negated one (`Not`), or any other object
  on the same receiver. A policy that skips "but" does the source task.
* **paraphrase** — the source's goal in each template of `rewording.PARAPHRASES`.
* **attribute_reference** — the source's goal with its object named by an attribute the scene makes
  unique ("the black one", "the container of ketchup").

Ids read `<source's id>~<variant>` (paraphrase, negation, attribute) or `<suite>/s<k>/first-A-then-B`.
The rules below (which sub-goals pair, which receivers a negation offers) are data read off the
scene's affordances; the sentences are `rewording`'s templates over `phrasing`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import affordances, files
from langgap.catalog.naming import SUITE_SHORT, goal_slug
from langgap.catalog.task import INSTRUCTION_STYLES, Task
from langgap.generation import rewording
from langgap.generation.candidates import obj_of_interest
from langgap.generation.generate import BEYOND_CATALOG, source_tasks
from langgap.generation.identity import original_in, same_trial
from langgap.goals import And, Atom, Goal, Not, Or, Then, atoms, plain_atoms
from langgap.stack import SUITES
from langgap.vocabulary import BEYOND_DIMENSIONS, Dimension, Split, TaskKind

# The negation variants: which part of a pick-and-place goal the sentence negates.
NEGATED_PARTS = {"not-where": "where", "not-what": "what"}
# An ordering task asks for two sub-goals one after the other, as LIBERO's two-part tasks do: it gets
# their suite's step limit, not its single-goal source's (220 steps do not fit a bowl and a drawer).
TWO_PART_SUITE = "libero_10"


def generate_beyond(suites: Iterable[str] = SUITES) -> list[Task]:
    """Every `langgap-beyond` task of `suites`: each source, then its new tasks by dimension and id."""
    sources = source_tasks(suites)
    two_part_steps = source_tasks((TWO_PART_SUITE,))[0].max_steps
    tasks: list[Task] = []
    for source in sources:
        scene = files.scene_problem(source)
        new = [
            *_ordering(source, scene, sources, two_part_steps),
            *_negation(source, scene),
            *_paraphrase(source, scene),
            *_attribute(source, scene),
        ]
        new.sort(key=lambda t: (BEYOND_DIMENSIONS.index(t.dimension), t.id))
        new = [_with_verdict_source(t, source) for t in new]
        tasks += [_as_beyond(source), *new]
    return tasks


def _as_beyond(source: Task) -> Task:
    return replace(original_in(source, BEYOND_CATALOG), in_langgap99=True)


def _with_verdict_source(task: Task, source: Task) -> Task:
    """`task`, taking its source's LangGap-99 verdict where its gate trial would repeat the source's."""
    text = files.task_bddl_text(task)
    return replace(task, gate_from=same_trial(task, source, text, starts_from_source=True))


def _task(
    source: Task,
    scene: BddlProblem,
    dimension: str,
    slug: str,
    goal: Goal,
    sentences: dict,
    max_steps: int | None = None,
) -> Task:
    return Task(
        id=f"{SUITE_SHORT[source.suite]}/s{source.scene_index}/{slug}",
        catalog=BEYOND_CATALOG,
        suite=source.suite,
        kind=TaskKind.EXTENDED.value,
        dimension=dimension,
        split=Split.HELDOUT.value,
        source=source.id,
        scene_task=source.scene_task,
        scene_index=source.scene_index,
        goal=goal,
        obj_of_interest=obj_of_interest(atoms(goal), scene),
        instructions=sentences,
        max_steps=source.max_steps if max_steps is None else max_steps,
    )


def _source_slug(source: Task) -> str:
    return source.id.split("/", 2)[2]


def _single_placement(source: Task) -> Predicate | None:
    goal = plain_atoms(source.goal) or ()
    return goal[0] if len(goal) == 1 and not affordances.is_articulation(goal[0]) else None


# -- ordering -------------------------------------------------------------------------------------


def depends(a: Predicate, b: Predicate, scene: BddlProblem) -> bool:
    """True when `a` and `b` cannot be done in either order: two goals acting on the same thing, or a
    placement whose object starts in, or goes onto or into, a part (or a region of a fixture) the other
    articulates. (Two objects into one basket are independent.)"""
    if a.args[0] == b.args[0]:
        return True
    moved = {p.args[0] for p in (a, b) if affordances.is_articulation(p)}
    for p in (a, b):
        if affordances.is_articulation(p):
            continue
        starts = [f[2] for f in scene.init if len(f) == 3 and f[1] == p.args[0] and f[0].lower() in ("on", "in")]
        for place in (p.args[1], *starts):
            region = affordances.region_of(place, scene)
            if place in moved or (region is not None and region.target in moved):
                return True
    return False


def order_pairs(source: Task, scene: BddlProblem, sources: list[Task]) -> list[tuple[Predicate, Predicate]]:
    """The pairs of independent sub-goals the source's scene offers, each in both orders."""
    goal = plain_atoms(source.goal) or ()
    if len(goal) == 2:
        partners = [(goal[0], goal[1])]
    elif len(goal) == 1 and not affordances.is_articulation(goal[0]):
        partners = [(goal[0], p) for p in affordances.articulations(scene)]
    elif len(goal) == 1:
        # An articulation source pairs with the pick-and-place goals of its scene's other originals.
        key = files.scene_key(source)
        placements = set(affordances.placements(scene))
        others = [s for s in sources if s.id != source.id and files.scene_key(s) == key]
        partners = [(goal[0], p) for s in others for p in (plain_atoms(s.goal) or ()) if p in placements]
    else:
        partners = []
    pairs = [(a, b) for a, b in partners if not depends(a, b, scene)]
    return [pair for a, b in pairs for pair in ((a, b), (b, a))]


def _ordering(source: Task, scene: BddlProblem, sources: list[Task], max_steps: int) -> list[Task]:
    out = []
    for a, b in order_pairs(source, scene, sources):
        sentences = {
            style: rewording.ordered(
                rewording.single_goal_sentence(style, source.suite, a, scene),
                rewording.single_goal_sentence(style, source.suite, b, scene),
            )
            for style in INSTRUCTION_STYLES
        }
        slug = f"first-{goal_slug((a,), scene)}-then-{goal_slug((b,), scene)}"
        out.append(_task(source, scene, Dimension.ORDERING.value, slug, Then((Atom(a), Atom(b))), sentences, max_steps))
    return out


# -- negation -------------------------------------------------------------------------------------


def negation_goal(predicate: Predicate, scene: BddlProblem, part: str) -> Goal | None:
    """The goal of `predicate` with its destination (`where`) or object (`what`) negated, and not `predicate`;
    None when the scene offers no named alternative (one is what the task's BDDL file states and the oracle
    aims at).

    "X anywhere but on Y": X on another receiver that takes it, or `(Moved X)` (set down anywhere else, the
    bare table included). A pushed object's named alternatives are pushed too (the plate slides to another
    spot on the table; it cannot be pushed up onto the stove). "anything but X on Y": every other object Y
    takes on Y, one that holds another at t0 included."""
    obj, target = predicate.args
    if part == "where":
        pushed = affordances.is_push(predicate, scene)  # the sentence's verb binds its alternatives too
        alternatives = [
            Atom(p)
            for p in affordances.placements(scene)
            if p.args[0] == obj and p.args[1] != target and affordances.is_push(p, scene) == pushed
        ]
        anywhere = [Atom(Predicate.of("Moved", (obj,)))]
    else:
        alternatives = [Atom(p) for p in affordances.placements_onto(target, scene) if p.args[0] != obj]
        anywhere = []
    if not alternatives:
        return None
    return And((Or((*alternatives, *anywhere)), Not(Atom(predicate))))


def _negation(source: Task, scene: BddlProblem) -> list[Task]:
    predicate = _single_placement(source)
    if predicate is None:
        return []
    out = []
    for variant, part in NEGATED_PARTS.items():
        goal = negation_goal(predicate, scene, part)
        sentences = {s: rewording.negated(s, source.suite, predicate, scene, part) for s in INSTRUCTION_STYLES}
        if goal is not None and all(sentences.values()):
            out.append(
                _task(source, scene, Dimension.NEGATION.value, f"{_source_slug(source)}~{variant}", goal, sentences)
            )
    return out


# -- paraphrase and attribute reference: the source's goal in other words ------------------------------


def _paraphrase(source: Task, scene: BddlProblem) -> list[Task]:
    goal = plain_atoms(source.goal) or ()
    out = []
    for name in rewording.PARAPHRASES:
        sentences = {
            s: rewording.paraphrase(name, s, source.suite, goal, scene, source.instruction(s))
            for s in INSTRUCTION_STYLES
        }
        if all(sentences.values()):
            out.append(
                _task(
                    source, scene, Dimension.PARAPHRASE.value, f"{_source_slug(source)}~{name}", source.goal, sentences
                )
            )
    return out


def _attribute(source: Task, scene: BddlProblem) -> list[Task]:
    predicate = _single_placement(source)
    if predicate is None:
        return []
    sentences = {s: rewording.by_attribute(s, source.suite, predicate, scene) for s in INSTRUCTION_STYLES}
    if not all(sentences.values()):
        return []
    slug = f"{_source_slug(source)}~by-attribute"
    return [_task(source, scene, Dimension.ATTRIBUTE_REFERENCE.value, slug, source.goal, sentences)]
