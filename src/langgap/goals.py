"""LangGap's goal language: what a task asks for, evaluated by LangGap itself at every step.

LIBERO's BDDL goals are conjunctions of ground atoms. LangGap's goals add disjunction, negation and
order, so that tasks such as "put the bowl anywhere but on the plate" or "first open the drawer, then
put the bowl on the plate" can be judged on the same scenes:

    (On akita_black_bowl_1 plate_1)                      an atom (a BDDL predicate)
    (And G ...)   (Or G ...)   (Not G)                   conjunction, disjunction, negation
    (Then G1 G2 ...)                                     G1 first held before G2 first held, ..., and all hold now
    (Moved akita_black_bowl_1)                           LangGap's own atom: away from its step-0 place, at rest

A registry stores a goal as a list of expressions, read as their conjunction; a list of atoms is a
LIBERO goal, so every existing registry entry reads as before. A task's BDDL file keeps a plain
conjunction LIBERO can parse: the goal's `witness`, a final state that satisfies it, of LIBERO's atoms
only (`Moved`, which LIBERO does not evaluate, stands in an `Or` after a part LIBERO can state).

`Then` needs the past: `GoalProgress` evaluates a goal step by step and remembers the first step
each sub-goal held. In a single state (`holds_now`) order is ignored: `Then` means all its parts hold.
Nothing here touches the simulator: truth of atoms comes from a function the caller passes.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

from langgap.bddl import Predicate
from langgap.errors import BddlError

Truth = Callable[[Predicate], bool]


@dataclass(frozen=True)
class Atom:
    """One ground predicate."""

    predicate: Predicate

    def __str__(self) -> str:
        return str(self.predicate)


@dataclass(frozen=True)
class And:
    parts: tuple[Goal, ...]

    def __str__(self) -> str:
        return _form("And", self.parts)


@dataclass(frozen=True)
class Or:
    parts: tuple[Goal, ...]

    def __str__(self) -> str:
        return _form("Or", self.parts)


@dataclass(frozen=True)
class Not:
    part: Goal

    def __str__(self) -> str:
        return _form("Not", (self.part,))


@dataclass(frozen=True)
class Then:
    """Every part holds now, and each part first held strictly before the next one first held."""

    parts: tuple[Goal, ...]

    def __str__(self) -> str:
        return _form("Then", self.parts)


Goal = Atom | And | Or | Not | Then
_NARY = {"and": And, "or": Or, "then": Then}


def _form(name: str, parts: tuple[Goal, ...]) -> str:
    return f"({name} {' '.join(str(p) for p in parts)})"


# -- building, parsing, writing -------------------------------------------------------------------


def conjunction(atoms: Iterable[Predicate]) -> And:
    """The goal of a LIBERO task: all of `atoms`."""
    return And(tuple(Atom(p) for p in atoms))


_TOKEN = re.compile(r"\(|\)|[^\s()]+")


def parse_goal(text: str) -> Goal:
    """Parse one expression such as `(Or (On a b) (On a c))`; BddlError names what is wrong."""
    tokens = _TOKEN.findall(text)
    goal, end = _parse(tokens, 0, text)
    if end != len(tokens):
        raise BddlError(f"goal {text!r}: unexpected text after the expression")
    return goal


def _parse(tokens: list[str], i: int, text: str) -> tuple[Goal, int]:
    if i + 1 >= len(tokens) or tokens[i] != "(" or tokens[i + 1] in ("(", ")"):
        raise BddlError(f"goal {text!r}: expected '(Name ...)' at token {i}")
    name = tokens[i + 1]
    head = name.lower()
    i += 2
    if head in _NARY or head == "not":
        parts = []
        while i < len(tokens) and tokens[i] == "(":
            part, i = _parse(tokens, i, text)
            parts.append(part)
        if i >= len(tokens) or tokens[i] != ")":
            raise BddlError(f"goal {text!r}: ({name} ...) takes expressions only, or lacks ')'")
        if head == "not":
            if len(parts) != 1:
                raise BddlError(f"goal {text!r}: Not takes one expression, got {len(parts)}")
            return Not(parts[0]), i + 1
        if not parts:
            raise BddlError(f"goal {text!r}: ({name}) is empty")
        return _NARY[head](tuple(parts)), i + 1
    args = []
    while i < len(tokens) and tokens[i] not in ("(", ")"):
        args.append(tokens[i])
        i += 1
    if i >= len(tokens) or tokens[i] != ")":
        raise BddlError(f"goal {text!r}: an atom's arguments must be names, closed by ')'")
    return Atom(Predicate.of(name, args)), i + 1


def goal_from_strings(expressions: Iterable[str]) -> Goal:
    """A registry's `goal` list: the conjunction of its expressions (a list of atoms is LIBERO's goal, an
    `And` even of one atom; one compound expression is that expression)."""
    parts = tuple(parse_goal(e) for e in expressions)
    if not parts:
        raise BddlError("goal is empty")
    return parts[0] if len(parts) == 1 and not isinstance(parts[0], Atom) else And(parts)


def goal_strings(goal: Goal) -> list[str]:
    """`goal` as a registry list (inverse of `goal_from_strings`): a conjunction's parts, else the goal."""
    return [str(p) for p in goal.parts] if isinstance(goal, And) else [str(goal)]


# -- reading a goal -------------------------------------------------------------------------------


def atoms(goal: Goal) -> tuple[Predicate, ...]:
    """Every atom `goal` mentions, in order of first mention."""
    if isinstance(goal, Atom):
        return (goal.predicate,)
    out: dict[Predicate, None] = {}
    for part in goal.parts if not isinstance(goal, Not) else (goal.part,):
        out.update(dict.fromkeys(atoms(part)))
    return tuple(out)


def plain_atoms(goal: Goal) -> tuple[Predicate, ...] | None:
    """The atoms of a LIBERO-style goal (a conjunction of atoms, or one atom); None for anything richer."""
    if isinstance(goal, Atom):
        return (goal.predicate,)
    if isinstance(goal, And) and all(isinstance(p, Atom) for p in goal.parts):
        return tuple(p.predicate for p in goal.parts)
    return None


def is_ordered(goal: Goal) -> bool:
    """True when `goal` contains a `Then` (its success depends on when sub-goals held)."""
    if isinstance(goal, Then):
        return True
    if isinstance(goal, Atom):
        return False
    return any(is_ordered(p) for p in (goal.parts if not isinstance(goal, Not) else (goal.part,)))


def unordered(goal: Goal) -> Goal:
    """`goal` with every `Then` read as `And`: the same final state, order not asked for."""
    if isinstance(goal, Atom):
        return goal
    if isinstance(goal, Not):
        return Not(unordered(goal.part))
    parts = tuple(unordered(p) for p in goal.parts)
    return And(parts) if isinstance(goal, Then) else type(goal)(parts)


def holds_now(goal: Goal, truth: Truth) -> bool:
    """Whether `goal` holds in one state whose atoms `truth` decides (order ignored)."""
    if isinstance(goal, Atom):
        return bool(truth(goal.predicate))
    if isinstance(goal, Not):
        return not holds_now(goal.part, truth)
    if isinstance(goal, Or):
        return any(holds_now(p, truth) for p in goal.parts)
    return all(holds_now(p, truth) for p in goal.parts)


def witness(goal: Goal) -> tuple[Predicate, ...]:
    """A conjunction of atoms that satisfies `goal` once they hold and no other atom does, in sub-goal order.

    For a LIBERO goal, its atoms; an `Or` contributes its first part. This is what a task's BDDL file
    states as its goal, and what a scripted policy can aim for (with `stages` for the order).
    BddlError if that state does not satisfy the goal (e.g. `(Not X)` with X in the witness), or names an
    atom LIBERO does not evaluate (`Moved`: no BDDL file can state it, no scripted placement aims at it).
    """
    chosen = _witness(goal)
    unique = tuple(dict.fromkeys(chosen))
    if not unique or not holds_now(goal, lambda p: p in unique):
        raise BddlError(f"goal {goal} has no witness of atoms (its first alternatives contradict it)")
    if unstated := [str(p) for p in unique if not p.libero]:
        raise BddlError(f"goal {goal}: its witness needs {', '.join(unstated)}, which LIBERO does not evaluate")
    return unique


def _witness(goal: Goal) -> tuple[Predicate, ...]:
    if isinstance(goal, Atom):
        return (goal.predicate,)
    if isinstance(goal, Not):
        return ()
    if isinstance(goal, Or):
        return _witness(goal.parts[0])
    return tuple(p for part in goal.parts for p in _witness(part))


def stages(goal: Goal) -> tuple[tuple[Predicate, ...], ...]:
    """The witness in the order a policy must reach it: one group of atoms per part of a top-level
    `Then` (inside an `And`, the other parts join the last group); one group for an unordered goal."""
    ordered = [p for p in (goal.parts if isinstance(goal, And) else (goal,)) if isinstance(p, Then)]
    if not ordered:
        return (witness(goal),)
    if len(ordered) > 1:
        raise BddlError(f"goal {goal}: more than one ordered part")
    groups = [witness(part) for part in ordered[0].parts]
    done = {p for g in groups for p in g}
    groups[-1] += tuple(p for p in witness(goal) if p not in done)
    return tuple(groups)


def choices(goal: Goal) -> Iterator[Goal]:
    """Every way to meet `goal` without a disjunction left: each `Or` outside a `Not` replaced by one of
    its parts, first parts first (so the first choice is the one `witness` states)."""
    if isinstance(goal, Atom | Not):
        yield goal
    elif isinstance(goal, Or):
        for part in goal.parts:
            yield from choices(part)
    else:
        for parts in itertools.product(*(tuple(choices(p)) for p in goal.parts)):
            yield type(goal)(parts)


def plans(goal: Goal) -> Iterator[tuple[tuple[Predicate, ...], ...]]:
    """The `stages` of every choice of `goal` that can be met, in `choices`' order (a choice that
    contradicts one of its `Not`s, orders more than one part, or needs an atom only LangGap evaluates,
    has none and is left out)."""
    for choice in choices(goal):
        try:
            yield stages(choice)
        except BddlError:
            continue


# -- evaluation over an episode -------------------------------------------------------------------


class GoalProgress:
    """A goal evaluated step by step, remembering the first step each sub-goal held (what `Then` needs).

    Call `observe(step, truth)` once per step, in step order, from the episode's start (step 0, the
    state the policy first sees); it returns whether the goal holds at that step.
    """

    def __init__(self, goal: Goal):
        self.goal = goal
        self.first: dict[Goal, int] = {}  # sub-goal -> first step it held

    def observe(self, step: int, truth: Truth) -> bool:
        """Evaluate the goal at `step`; every sub-goal is evaluated (no short cut), so its history is complete."""
        return self._eval(self.goal, step, truth)

    @property
    def first_held(self) -> int | None:
        """The first step at which the whole goal held (None: not yet)."""
        return self.first.get(self.goal)

    def _eval(self, goal: Goal, step: int, truth: Truth) -> bool:
        if isinstance(goal, Atom):
            value = bool(truth(goal.predicate))
        elif isinstance(goal, Not):
            value = not self._eval(goal.part, step, truth)
        else:
            values = [self._eval(p, step, truth) for p in goal.parts]
            if isinstance(goal, Or):
                value = any(values)
            elif isinstance(goal, And):
                value = all(values)
            else:  # Then: all hold now, and their first steps are strictly increasing
                firsts = [self.first[p] for p in goal.parts] if all(values) else []
                value = bool(firsts) and all(a < b for a, b in zip(firsts, firsts[1:], strict=False))
        if value:
            self.first.setdefault(goal, step)
        return value
