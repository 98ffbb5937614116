"""Whether a sentence's referring expressions pick the objects its goal names, on one scene layout.

An instruction such as "pick up the black bowl between the plate and the ramekin and place it on the plate"
refers to objects by category ("the black bowl"), attribute ("the left moka pot") and relation ("between the
plate and the ramekin", "next to", "on", "in the top drawer of", "on the right of", "from table center").
Where the scene holds one object of a category, the category picks it; where it holds several, the rest of
the expression must. This module reads the expressions (`mentions`) and resolves each against the objects'
positions at t0 (`Layout`), from a viewpoint (`View`: the robot's; the agentview camera's, as its raw,
unrotated render shows it, whose left and right are the robot's mirrored; or the image a policy is given, that
render rotated 180°, whose left is the robot's left again), and says whether it picks the object the goal
names, another, none, or more than one (ambiguous). It reads the LIBERO phrasings LangGap's catalogs use; a
sentence it cannot read is `unread`, never a verdict.

The rules, with `MARGIN` (2 cm) as the distance below which two objects fit a comparison equally well:

- *left / right / front / back* before the noun: the object farthest that way among its category;
- *left of / right of / in front of / behind X*: the objects on that side of X by more than `MARGIN`
  (several: the nearest to X, if nearer than the next by more than `MARGIN`);
- *between X and Y*: the objects whose centre projects on the segment from X to Y (within `BETWEEN_ENDS` of
  its length past either end) and lies off it by at most `BETWEEN_WIDTH` of its length, the nearest to it;
  none fits: neither (nothing picked); *not between*: the others (all of them when none is between);
- *next to / beside / near X*: the nearest to X;
- *on / in / from X* (a support: an object, the stove, the cabinet's top or a drawer): those for which
  LIBERO's `On` / `In` holds (the simulator decides, `Layout.supports`);
- *from / at table center*: the nearest to the table's centre region.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from langgap.bddl import BddlProblem
from langgap.goals import And, Atom, Goal, Not, Or, Then

MARGIN = 0.02
# How far past either landmark and how far off the segment joining them an object may stand and still be between
# them, as fractions of the segment's length: a bowl level with the ramekin but 10 cm to its side (LIBERO-PRO's
# spatial/s0 states) is beside it, not between it and the plate.
BETWEEN_ENDS = 0.05
BETWEEN_WIDTH = 0.25
# How a sentence names a category besides its type's words, by type.
NOUNS = {
    "akita_black_bowl": ("black bowl", "akita black bowl", "bowl"),
    "glazed_rim_porcelain_ramekin": ("ramekin", "glazed rim porcelain ramekin"),
    "cookies": ("cookie box", "cookies box", "box of cookies"),
    "plate": ("plate",),
    "moka_pot": ("moka pot",),
    "porcelain_mug": ("white mug",),
    "white_yellow_mug": ("yellow and white mug", "yellow-white mug", "white and yellow mug"),
    "red_coffee_mug": ("red mug", "red coffee mug"),
    "cream_cheese": ("cream cheese box", "cream cheese"),
    "chefmate_8_frypan": ("frying pan", "frypan", "pan"),
    "black_book": ("black book", "book"),
    "wooden_cabinet": ("wooden cabinet", "cabinet"),
    "flat_stove": ("stove",),
    "wine_rack": ("wine rack", "rack"),
    "desk_caddy": ("caddy", "desk caddy"),
}
# Viewpoint words: an adjective before the noun, or a side of a landmark.
SIDES = {"left": ("right", -1.0), "right": ("right", 1.0), "front": ("forward", -1.0), "back": ("forward", 1.0)}
PICK_VERBS = {"pick", "grab", "take", "lift", "get", "grasp", "fetch", "retrieve", "remove"}
# "arrange X on Y", "have X on Y", "X belongs on Y" say where X goes as "put" does (LIBERO-Plus's rewordings).
PLACE_VERBS = {"put", "place", "set", "move", "push", "drop", "bring", "stack", "position", "arrange", "have",
               "belong"}  # fmt: skip
_DRAWERS = ("top", "middle", "bottom")
_DRAWER_WORDS = {"drawer", "layer", "shelf", "compartment"}


@dataclass(frozen=True)
class View:
    """A viewpoint: where it looks from, and its right and forward directions (unit vectors, horizontal)."""

    name: str
    right: np.ndarray
    forward: np.ndarray


@dataclass(frozen=True)
class Layout:
    """One scene at t0: each entity's position (objects, fixtures, region sites), the (object, receiver) pairs
    for which LIBERO's `On` or `In` holds, and the table's centre (None: the scene names none)."""

    positions: dict[str, np.ndarray]
    supports: frozenset[tuple[str, str]] = frozenset()
    table_center: np.ndarray | None = None


@dataclass(frozen=True)
class Mention:
    """A referring expression: its words, its category, a side adjective, a relation (`between`, `not
    between`, `next to`, `left of` …, `support`, `center`) with its landmarks (categories, or a region's
    entity), its role in the sentence (`object` moved, `target` it goes to, `landmark` of another mention,
    `excluded` after "but"), and whether words the reader does not follow come after it (`unread`)."""

    text: str
    category: str
    start: int
    plural: bool = False
    side: str | None = None
    relation: str | None = None
    landmarks: tuple[str, ...] = ()
    role: str = "object"
    unread: bool = False
    phrase: str = ""  # the words of the whole expression (side, noun, relation)


@dataclass
class _Lexicon:
    phrases: list[tuple[tuple[str, ...], str]] = field(default_factory=list)  # longest first

    def match(self, words: list[str], i: int) -> tuple[str, int, bool] | None:
        """(category, words used, plural) of the longest phrase at `words[i]`."""
        for phrase, category in self.phrases:
            n = len(phrase)
            got = words[i : i + n]
            if len(got) < n or got[:-1] != list(phrase[:-1]):
                continue
            if got[-1] == phrase[-1]:
                return category, n, False
            if got[-1] in (phrase[-1] + "s", phrase[-1] + "es"):
                return category, n, True
        return None


def lexicon(scene: BddlProblem) -> _Lexicon:
    """The words naming each category of `scene` (a word two categories share names neither)."""
    categories = set(scene.objects.values()) | set(scene.fixtures.values())
    named: dict[tuple[str, ...], set[str]] = {}
    for category in categories:
        for noun in (*NOUNS.get(category, ()), category.replace("_", " ")):
            named.setdefault(tuple(noun.split()), set()).add(category)
    phrases = [(phrase, next(iter(cats))) for phrase, cats in named.items() if len(cats) == 1]
    return _Lexicon(sorted(phrases, key=lambda p: -len(p[0])))


def words_of(sentence: str) -> list[str]:
    """The sentence's words, lowercased, punctuation dropped (a hyphenated word kept whole)."""
    return re.findall(r"[a-z]+(?:-[a-z]+)?", sentence.lower())


# Words that say more about which object is meant: after a mention the reader leaves unrelated, they make it
# `unread` rather than ambiguous.
CUES = {
    "between", "next", "beside", "near", "left", "right", "front", "behind", "center", "centre", "middle",
    "closest", "nearest", "farthest", "which", "that", "located", "situated", "sitting", "resting", "one",
    "top", "drawer", "from", "instead", "its", "currently", "nearby", "there",
}  # fmt: skip
_VERBS = PICK_VERBS | PLACE_VERBS | {"open", "close", "turn"}
# Words of a relative clause between a noun and where it is ("the bowl that is on …", "positioned on …").
_FILLERS = {"that", "thats", "which", "is", "currently", "positioned", "located", "situated", "sitting", "resting",
            "lying", "placed", "you", "see", "presently", "now"}  # fmt: skip
_ANAPHORA = {"that", "this", "same", "said"}
# What may follow a noun to say where it is; after a placing verb's object, the first few say where it goes.
_LOCATION_WORDS = {"on", "in", "at", "from", "off", "inside", "atop", "between", "next", "beside", "near", "by",
                   "adjacent", "close", "left", "right", "front", "behind", "closest", "nearest", "to", "onto",
                   "into"}  # fmt: skip
_TARGET_WORDS = {"on", "in", "into", "onto", "to", "inside", "atop"}


def _verb(word: str) -> str | None:
    """The verb `word` is a form of (`placed` → `place`), or None."""
    for cut in (0, 1, 2, 3):
        stem = word[: len(word) - cut] if cut else word
        if stem in _VERBS and (cut == 0 or word[len(stem) :] in ("s", "d", "ed", "ing", "es")):
            return stem
    return None


def _nouns(words: list[str], lex: _Lexicon) -> list[tuple[int, int, str, bool]]:
    """(start, end, category, plural) of every category named, left to right, longest first."""
    found, i = [], 0
    while i < len(words):
        hit = lex.match(words, i)
        if hit:
            found.append((i, i + hit[1], hit[0], hit[2]))
            i += hit[1]
        else:
            i += 1
    return found


def mentions(sentence: str, scene: BddlProblem) -> list[Mention]:
    """The referring expressions of `sentence` naming `scene`'s categories, in order, with their side adjective,
    relation and role. A relative clause ("the bowl that is on the plate", "the bowl positioned on …") says
    where the object is, whatever the verb; a later "that bowl" names the same one (`role` `landmark`)."""
    words = words_of(sentence)
    found = _nouns(words, lexicon(scene))
    out: list[Mention] = []
    landmarks: set[int] = set()
    for k, (start, end, category, plural) in enumerate(found):
        if k in landmarks:
            continue
        if set(words[max(0, start - 2) : start]) & _ANAPHORA and any(m.category == category for m in out):
            out.append(Mention(" ".join(words[start:end]), category, start, plural, role="landmark"))
            continue
        role = _role(words, start, out)
        after = end
        while after < len(words) and words[after] in _FILLERS:
            after += 1
        placing = after == end and role != "target" and _clause_verb(words, start) in PLACE_VERBS
        relation, marks, used = _relation(words, after, found, k, scene, placing)
        landmarks |= used
        side = _side_before(words, start)
        follows = words[after] if after < len(words) else ""
        unexplained = follows in _LOCATION_WORDS and not (placing and follows in _TARGET_WORDS)
        later_cue = any(w in CUES for w in words[end:])
        unread = relation is None and side is None and (unexplained or later_cue)
        plural = plural or bool({"both", "each", "every", "all"} & set(words[max(0, start - 2) : start]))
        last = max([after, *(found[i][1] for i in used)])
        if relation == "support" and not used:  # a drawer named without its cabinet's words
            last = next((i + 1 for i in range(after, min(len(words), after + 8)) if words[i] in _DRAWER_WORDS), after)
        phrase = " ".join(words[start - bool(side) : last])
        out.append(
            Mention(" ".join(words[start:end]), category, start, plural, side, relation, marks, role, unread, phrase)
        )
        for index in sorted(used):
            s, e, cat, pl = found[index]
            out.append(Mention(" ".join(words[s:e]), cat, s, pl, _side_before(words, s), role="landmark"))
    return sorted(out, key=lambda m: m.start)


def _side_before(words: list[str], start: int) -> str | None:
    return words[start - 1] if start and words[start - 1] in SIDES else None


def _clause_start(words: list[str], start: int) -> int:
    """Where the clause holding word `start` begins: at the last verb after "and" / "then" / "after" / a comma's
    word before it."""
    for i in range(start - 1, 0, -1):
        if words[i - 1] in ("and", "then", "after", "while", "you") and _verb(words[i]):
            return i
    return 0


def _clause_verb(words: list[str], start: int) -> str | None:
    """The last verb before word `start` in its clause."""
    verbs = [v for w in words[_clause_start(words, start) : start] if (v := _verb(w))]
    return verbs[-1] if verbs else None


def _role(words: list[str], start: int, earlier: list[Mention]) -> str:
    """`excluded` after "but" / "except"; `target` for a placing verb's destination (the word before the noun
    phrase a preposition, its object named earlier or a pronoun); else `object`."""
    before = words[max(0, start - 3) : start]
    if "but" in before or "except" in before:
        return "excluded"
    i = start - 1
    while i >= 0 and (words[i] in ("the", "a", "an") or words[i] in SIDES):
        i -= 1
    if i < 0 or words[i] not in _TARGET_WORDS:
        return "object"
    clause = _clause_start(words, start)
    placing = any(_verb(w) in PLACE_VERBS for w in words[clause:start])
    named = any(m.role in ("object", "excluded") for m in earlier) or "it" in words[clause:start]
    return "target" if placing and named else "object"


def _relation(words: list[str], end: int, found, k: int, scene: BddlProblem, placing: bool):
    """The relation following a mention ending at `end`: (kind, landmarks, indices of the mentions used as
    landmarks). A placing verb's object takes only `from` (what follows it is where it goes)."""
    nxt = [(i, f) for i, f in enumerate(found) if i > k]
    negated = words[end : end + 1] == ["not"]
    end += negated
    rest = words[end : end + 10]

    def landmark_at(offset: int):
        position = end + offset
        for i, f in nxt:
            if f[0] == position or (f[0] == position + 1 and position < len(words) and words[position] in ("the", "a")):
                return i, f
        return None

    def after(*prefix: str) -> int | None:
        return len(prefix) if tuple(rest[: len(prefix)]) == prefix else None

    near = {w.removesuffix("s") for w in rest[:6]}
    if rest[:1] and rest[0] in ("from", "at", "in", "on") and "table" in near and {"center", "centre", "middle"} & near:
        return "center", (), {i for i, f in nxt[:1] if words[f[0]].startswith("table")}
    if placing:
        return _support(rest, landmark_at, scene, nxt) if rest[:1] in (["from"], ["off"]) else (None, (), set())
    if rest[:1] == ["between"] and (first := landmark_at(1)):
        second = next(((i, f) for i, f in nxt if i > first[0]), None)
        if second and "and" in words[first[1][1] : second[1][0]]:
            return ("not between" if negated else "between"), (first[1][2], second[1][2]), {first[0], second[0]}
    for phrase in (("next", "to"), ("beside",), ("near",), ("close", "to"), ("adjacent", "to"), ("by",)):
        if (n := after(*phrase)) and (hit := landmark_at(n)):
            return "next to", (hit[1][2],), {hit[0]}
    for side in SIDES:
        for phrase in (("on", "the", side, "of"), ("to", "the", side, "of"), (side, "of"), ("in", side, "of")):
            if (n := after(*phrase)) and (hit := landmark_at(n)):
                return f"{side} of", (hit[1][2],), {hit[0]}
    if (n := after("in", "front", "of")) and (hit := landmark_at(n)):
        return "front of", (hit[1][2],), {hit[0]}
    if (n := after("behind")) and (hit := landmark_at(n)):
        return "back of", (hit[1][2],), {hit[0]}
    return _support(rest, landmark_at, scene, nxt)


def _support(rest: list[str], landmark_at, scene: BddlProblem, nxt):
    """`support`: the mention is on or in something (an object, the stove, the cabinet's top or a drawer)."""
    if not rest or rest[0] not in ("on", "in", "from", "inside", "atop", "off"):
        return None, (), set()
    cabinet = next((name for name, cat in scene.fixtures.items() if cat == "wooden_cabinet"), None)
    drawer = next((level for level in _DRAWERS if level in rest[:5]), None) if _DRAWER_WORDS & set(rest[:6]) else None
    if drawer and cabinet:
        used = {i for i, f in nxt[:1] if f[2] == "wooden_cabinet"}
        return "support", (f"{cabinet}_{drawer}_region",), used
    lead = 4 if rest[1:4] == ["the", "top", "of"] else 3 if rest[1:3] == ["top", "of"] else 1
    hit = landmark_at(lead)
    if hit is None:
        return None, (), set()
    category = hit[1][2]
    fixture = next((name for name, cat in scene.fixtures.items() if cat == category), None)
    regions = {r.name: r.entity for r in scene.regions if r.target == fixture}
    for part in ("cook_region", "top_side"):
        if fixture and part in regions:
            return "support", (regions[part],), {hit[0]}
    return "support", (category,), {hit[0]}


# -- resolution -----------------------------------------------------------------------------------------------


def instances(category: str, scene: BddlProblem) -> list[str]:
    """The entities of `category` in `scene` (objects, then fixtures), in name order."""
    return sorted(n for n, c in {**scene.objects, **scene.fixtures}.items() if c == category)


def _single(category: str, side: str | None, scene: BddlProblem, layout: Layout, view: View) -> tuple[str, ...]:
    """What a landmark picks: its category's one instance, or the one its side adjective picks."""
    found = instances(category, scene) if category in {**scene.objects, **scene.fixtures}.values() else [category]
    if len(found) > 1 and side:
        return _extreme(found, side, layout, view)
    return tuple(found)


def _extreme(candidates: list[str], side: str, layout: Layout, view: View) -> tuple[str, ...]:
    axis, sign = SIDES[side]
    score = {c: sign * float(layout.positions[c][:2] @ getattr(view, axis)[:2]) for c in candidates}
    best = max(score.values())
    return tuple(c for c in candidates if best - score[c] < MARGIN)


def _nearest(candidates: list[str], distance: Callable[[str], float]) -> tuple[str, ...]:
    if not candidates:
        return ()
    d = {c: distance(c) for c in candidates}
    best = min(d.values())
    return tuple(c for c in candidates if d[c] - best < MARGIN)


def _xy(layout: Layout, entity: str) -> np.ndarray:
    return layout.positions[entity][:2]


def resolve(mention: Mention, scene: BddlProblem, layout: Layout, view: View) -> tuple[str, ...]:
    """The entities `mention` picks on `layout` seen from `view` (all of them when it says nothing that tells
    them apart)."""
    candidates = instances(mention.category, scene)
    if mention.side:
        candidates = list(_extreme(candidates, mention.side, layout, view))
    if mention.relation is None:
        return tuple(candidates)
    if mention.relation == "center":
        if layout.table_center is None:
            return tuple(candidates)
        return _nearest(candidates, lambda c: float(np.linalg.norm(_xy(layout, c) - layout.table_center[:2])))
    if mention.relation == "support":
        receiver = mention.landmarks[0]
        if receiver == "table":  # everything stands on the table: it tells nothing apart
            return tuple(candidates)
        receivers = instances(receiver, scene) or [receiver]
        return tuple(c for c in candidates if any((c, r) in layout.supports for r in receivers))
    marks = []
    for landmark in mention.landmarks:
        picked = _single(landmark, None, scene, layout, view)
        if len(picked) != 1:
            return ()
        marks.append(picked[0])
    candidates = [c for c in candidates if c not in marks]
    if mention.relation in ("between", "not between"):
        a, b = (_xy(layout, m) for m in marks)
        fits = [c for c in candidates if is_between(_xy(layout, c), a, b)]
        between = _nearest(fits, lambda c: _segment(_xy(layout, c), a, b)[1])
        if mention.relation == "between":
            return between
        return tuple(c for c in candidates if c not in between) if len(between) <= 1 else ()
    if mention.relation == "next to":
        return _nearest(candidates, lambda c: float(np.linalg.norm(_xy(layout, c) - _xy(layout, marks[0]))))
    side = mention.relation.removesuffix(" of")
    axis, sign = SIDES[side]
    direction = getattr(view, axis)[:2]
    fits = [c for c in candidates if sign * float((_xy(layout, c) - _xy(layout, marks[0])) @ direction) > MARGIN]
    return _nearest(fits, lambda c: float(np.linalg.norm(_xy(layout, c) - _xy(layout, marks[0]))))


def _segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Where `p` projects on the segment a→b (0 at a, 1 at b) and its distance from the line."""
    ab = b - a
    t = float((p - a) @ ab / (ab @ ab))
    return t, float(np.linalg.norm(p - (a + t * ab)))


def is_between(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether `p` is between `a` and `b`: it projects on the segment a→b, `BETWEEN_ENDS` of its length past
    an end at most, and lies off it by `BETWEEN_WIDTH` of its length at most."""
    t, off = _segment(p, a, b)
    return -BETWEEN_ENDS <= t <= 1.0 + BETWEEN_ENDS and off <= BETWEEN_WIDTH * float(np.linalg.norm(b - a))


# -- what the goal names --------------------------------------------------------------------------------------


def signed_atoms(goal: Goal, positive: bool = True) -> list[tuple[bool, tuple[str, ...]]]:
    """Every atom of `goal` with whether it is asked for (True) or forbidden (under a `Not`)."""
    if isinstance(goal, Atom):
        return [(positive, (goal.predicate.name, *goal.predicate.args))]
    if isinstance(goal, Not):
        return signed_atoms(goal.part, not positive)
    parts: Iterable[Goal] = goal.parts if isinstance(goal, And | Or | Then) else ()
    return [atom for part in parts for atom in signed_atoms(part, positive)]


def expected_entity(mention: Mention, mentions_: list[Mention], goal: Goal, scene: BddlProblem) -> str | None:
    """The entity of `mention`'s category that the goal names in its role (None: the goal names none, or
    several, in that role): a moved object is a first argument, a target the second argument of the atom whose
    moved object the clause names, an excluded object one under `Not`."""
    if mention.plural or mention.role == "landmark":
        return None
    wanted = mention.role != "excluded"
    binary = [args for sign, args in signed_atoms(goal) if sign == wanted and len(args) == 3]
    if mention.role == "target":
        objects = [m for m in mentions_ if m.role == "object"]
        earlier = [m for m in objects if m.start < mention.start]
        subject = earlier[-1] if earlier else next(iter(objects), None)  # "place it on X after you pick up Y"
        if subject is None:
            return None
        subjects = set(instances(subject.category, scene))
        found = {a[2] for a in binary if a[1] in subjects and scene_category(a[2], scene) == mention.category}
    else:
        found = {args[1] for args in binary if scene_category(args[1], scene) == mention.category}
    return next(iter(found)) if len(found) == 1 else None


def outcome(picked: tuple[str, ...], expected: str | None) -> str:
    """What an expression that picked `picked` did: `goal's` (the goal's object `expected`), `other`, `none`,
    `ambiguous` (several), or `unchecked` (the goal names none in its role)."""
    if len(picked) > 1:
        return "ambiguous"
    if not picked:
        return "none"
    if expected is None:
        return "unchecked"
    return "goal's" if picked[0] == expected else "other"


def scene_category(entity: str, scene: BddlProblem) -> str | None:
    return {**scene.objects, **scene.fixtures}.get(entity)
