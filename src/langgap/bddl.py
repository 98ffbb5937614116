"""Reading LIBERO BDDL problems and rewriting the three sections a LangGap task changes.

A LangGap extended task is its source task's BDDL with new `(:language)`, `(:obj_of_interest)`
and `(:goal)` sections; every other byte is kept. The rewrite therefore works on the text (spans
found by paren matching), not by re-printing a parse tree.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from langgap.errors import BddlError

# Goal predicates LIBERO evaluates (and LangGap reads), with their arity. Spelled as LIBERO's BDDL files spell them.
PREDICATE_ARITY = {"On": 2, "In": 2, "Open": 1, "Close": 1, "Turnon": 1, "Turnoff": 1}
# Predicates only LangGap evaluates (`langgap.sim.resting`): a goal may use them, a BDDL file never states them.
# (Moved o): `o` lies away from where it was at step 0 and rests there, out of the hand ("anywhere but ...").
LANGGAP_PREDICATES = {"Moved": 1}
_ARITY = PREDICATE_ARITY | LANGGAP_PREDICATES
_CANONICAL = {name.lower(): name for name in _ARITY}


@dataclass(frozen=True)
class Predicate:
    """One ground predicate such as `(On akita_black_bowl_1 plate_1)`."""

    name: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return f"({self.name} {' '.join(self.args)})"

    @classmethod
    def parse(cls, text: str) -> Predicate:
        """Parse `(Name arg ...)`; raises BddlError on unknown names or a wrong arity."""
        tokens = _tokenize(text)
        if len(tokens) < 3 or tokens[0] != "(" or tokens[-1] != ")" or "(" in tokens[1:] or ")" in tokens[1:-1]:
            raise BddlError(f"not a ground predicate: {text!r}")
        return cls.of(tokens[1], tokens[2:-1])

    @classmethod
    def of(cls, name: str, args: list[str] | tuple[str, ...]) -> Predicate:
        canonical = _CANONICAL.get(name.lower())
        if canonical is None:
            known = ", ".join(_ARITY)
            raise BddlError(f"unknown predicate {name!r} (known: {known})")
        if len(args) != _ARITY[canonical]:
            raise BddlError(f"predicate {canonical} takes {_ARITY[canonical]} argument(s), got {list(args)}")
        return cls(canonical, tuple(args))

    @property
    def libero(self) -> bool:
        """Whether LIBERO evaluates this predicate (else only LangGap does: `LANGGAP_PREDICATES`)."""
        return self.name in PREDICATE_ARITY

    def as_libero(self) -> tuple[str, ...]:
        """The lower-cased tuple form LIBERO's parser produces (`('on', 'a', 'b')`)."""
        if not self.libero:
            raise BddlError(f"{self}: LIBERO does not evaluate {self.name} (only LangGap does)")
        return (self.name.lower(), *self.args)


@dataclass(frozen=True)
class Region:
    name: str
    target: str

    @property
    def entity(self) -> str:
        """The name predicates use for this region (`<target>_<region>`)."""
        return f"{self.target}_{self.name}"


@dataclass(frozen=True)
class BddlProblem:
    """The parts of a BDDL problem that LangGap reasons about."""

    problem_name: str
    language: str
    objects: dict[str, str]  # instance -> category
    fixtures: dict[str, str]
    regions: tuple[Region, ...]
    obj_of_interest: tuple[str, ...]
    init: tuple[tuple[str, ...], ...] = field(repr=False)
    goal: tuple[Predicate, ...]

    @property
    def entities(self) -> set[str]:
        """Every name a goal predicate may refer to: objects, fixtures and region sites."""
        return set(self.objects) | set(self.fixtures) | {r.entity for r in self.regions}

    def check_goal(self, goal: tuple[Predicate, ...] | list[Predicate]) -> None:
        """Raise BddlError if a goal names something that is not in this scene."""
        if not goal:
            raise BddlError("goal is empty")
        known = self.entities
        for predicate in goal:
            missing = [a for a in predicate.args if a not in known]
            if missing:
                raise BddlError(f"goal {predicate} names {', '.join(missing)}, which is not in the scene")


# --- parsing -----------------------------------------------------------------------------------

_TOKEN = re.compile(r"\(|\)|[^\s()]+")


def _tokenize(text: str) -> list[str]:
    return _TOKEN.findall(text)


def _tree(tokens: list[str]) -> list:
    stack: list[list] = [[]]
    for token in tokens:
        if token == "(":
            stack.append([])
        elif token == ")":
            if len(stack) == 1:
                raise BddlError("unbalanced parentheses: unexpected ')'")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    if len(stack) != 1:
        raise BddlError("unbalanced parentheses: missing ')'")
    return stack[0]


def _section_spans(text: str) -> dict[str, tuple[int, int]]:
    """Character spans of the top-level `(:name ...)` sections inside `(define ...)`."""
    spans: dict[str, tuple[int, int]] = {}
    depth = 0
    start = -1
    for match in re.finditer(r"[()]", text):
        if match.group() == "(":
            depth += 1
            if depth == 2:
                start = match.start()
        else:
            if depth == 2:
                head = re.match(r"\(\s*(:[\w-]+)", text[start:])
                if head:
                    spans[head.group(1)] = (start, match.end())
            depth -= 1
            if depth < 0:
                raise BddlError("unbalanced parentheses: unexpected ')'")
    if depth != 0:
        raise BddlError("unbalanced parentheses: missing ')'")
    return spans


def _typed_list(items: list) -> dict[str, str]:
    """`a b - type c - type2` -> {a: type, b: type, c: type2}."""
    out: dict[str, str] = {}
    pending: list[str] = []
    i = 0
    while i < len(items):
        if items[i] == "-":
            if i + 1 >= len(items) or not pending:
                raise BddlError("malformed typed list")
            for name in pending:
                out[name] = items[i + 1]
            pending = []
            i += 2
        else:
            pending.append(items[i])
            i += 1
    if pending:
        raise BddlError(f"untyped names {pending}")
    return out


def parse_bddl(text: str, *, source: str = "<bddl>") -> BddlProblem:
    """Parse a LIBERO BDDL problem. Raises BddlError with the file name on any malformation."""
    try:
        return _parse(text)
    except BddlError as exc:
        raise BddlError(f"{source}: {exc}") from None


def _parse(text: str) -> BddlProblem:
    spans = _section_spans(text)
    top = _tree(_tokenize(text))
    if len(top) != 1 or not isinstance(top[0], list) or not top[0] or top[0][0] != "define":
        raise BddlError("not a (define (problem ...) ...) form")
    sections: dict[str, list] = {}
    problem_name = ""
    for item in top[0][1:]:
        if isinstance(item, list) and item and item[0] == "problem" and len(item) == 2:
            problem_name = item[1]
        elif isinstance(item, list) and item and isinstance(item[0], str) and item[0].startswith(":"):
            sections[item[0]] = item[1:]
    for required in (":language", ":objects", ":fixtures", ":goal", ":init"):
        if required not in sections or required not in spans:
            raise BddlError(f"missing section ({required} ...)")
    if not problem_name:
        raise BddlError("missing (problem NAME)")

    lang_start, lang_end = spans[":language"]
    language = re.sub(r"^\(\s*:language\s*", "", text[lang_start:lang_end])[:-1].strip()

    regions = []
    for entry in sections.get(":regions", []):
        if not isinstance(entry, list) or not entry or not isinstance(entry[0], str):
            raise BddlError("malformed (:regions ...)")
        target = next((sub[1] for sub in entry[1:] if isinstance(sub, list) and sub[:1] == [":target"]), None)
        if target is None:
            raise BddlError(f"region {entry[0]} has no (:target ...)")
        regions.append(Region(entry[0], target))

    goal_items = sections[":goal"]
    if len(goal_items) != 1 or not isinstance(goal_items[0], list) or not goal_items[0]:
        raise BddlError("goal must be one (And ...) form")
    goal_form = goal_items[0]
    conjuncts = goal_form[1:] if str(goal_form[0]).lower() == "and" else [goal_form]
    goal = tuple(_predicate_from_tree(c) for c in conjuncts)
    init = tuple(tuple(str(x) for x in item) for item in sections[":init"] if isinstance(item, list))

    problem = BddlProblem(
        problem_name=problem_name,
        language=language,
        objects=_typed_list(sections[":objects"]),
        fixtures=_typed_list(sections[":fixtures"]),
        regions=tuple(regions),
        obj_of_interest=tuple(str(x) for x in sections.get(":obj_of_interest", [])),
        init=init,
        goal=goal,
    )
    problem.check_goal(goal)
    return problem


def _predicate_from_tree(node) -> Predicate:
    if not isinstance(node, list) or not node or any(isinstance(x, list) for x in node):
        raise BddlError(f"goal conjunct is not a ground predicate: {node!r}")
    predicate = Predicate.of(node[0], node[1:])
    if not predicate.libero:
        raise BddlError(f"goal conjunct {predicate}: LIBERO does not evaluate {predicate.name}, no BDDL file states it")
    return predicate


def read_bddl(path: str | Path) -> BddlProblem:
    """Read and parse a BDDL file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise BddlError(f"cannot read BDDL file {path}: {exc.strerror}") from None
    return parse_bddl(text, source=str(path))


# --- rewriting ---------------------------------------------------------------------------------


def rewrite_task_sections(
    text: str,
    *,
    language: str,
    obj_of_interest: tuple[str, ...] | list[str],
    goal: tuple[Predicate, ...] | list[Predicate],
) -> str:
    """Return `text` with only `(:language)`, `(:obj_of_interest)` and `(:goal)` replaced.

    The new goal is checked against the scene first, so a goal naming an object that is not in
    the scene is rejected here rather than at simulation time.
    """
    scene = parse_bddl(text)
    scene.check_goal(tuple(goal))
    if "(" in language or ")" in language or "\n" in language:
        raise BddlError(f"instruction must be one line without parentheses: {language!r}")
    spans = _section_spans(text)
    if ":obj_of_interest" not in spans:
        raise BddlError("source BDDL has no (:obj_of_interest ...) section to replace")
    interest = "".join(f"\n    {name}" for name in obj_of_interest)
    replacements = {
        ":language": f"(:language {language})",
        ":obj_of_interest": f"(:obj_of_interest{interest}\n  )",
        ":goal": f"(:goal\n    (And {' '.join(str(p) for p in goal)})\n  )",
    }
    out = text
    for key, (start, end) in sorted(spans.items(), key=lambda kv: kv[1][0], reverse=True):
        if key in replacements:
            out = out[:start] + replacements[key] + out[end:]
    return out


def strip_task_sections(text: str) -> str:
    """`text` without the three task sections: what must stay byte-identical across same-scene tasks."""
    return strip_sections(text, (":language", ":obj_of_interest", ":goal"))


def strip_sections(text: str, names: tuple[str, ...] | None = None) -> str:
    """`text` without its top-level sections named in `names` (`(":language",)`; None: all of them)."""
    spans = _section_spans(text)
    out = text
    for key, (start, end) in sorted(spans.items(), key=lambda kv: kv[1][0], reverse=True):
        if names is None or key in names:
            out = out[:start] + out[end:]
    return out


def section_texts(text: str) -> dict[str, str]:
    """Each top-level section of `text` (`":goal"` -> `"(:goal ...)"`), as written."""
    return {name: text[start:end] for name, (start, end) in _section_spans(text).items()}


def read_tree(text: str) -> list:
    """`text` as nested lists of tokens (for reading forms LangGap's parser refuses)."""
    return _tree(_tokenize(text))
