"""Instructions for one-predicate goals, in the two styles a catalog stores.

`libero`: the phrasing of LIBERO's published training data. Public checkpoints were trained on
LIBERO's file-name sentences ("pick up the black bowl between the plate and the ramekin and place
it on the plate"). A generated task must be phrased exactly as the originals phrase the same
object, target and relation, so that it differs from its source sentence only in the words that
change the task. The tables below are those phrasings, read off the 30 originals of
libero_spatial / libero_goal / libero_object (a test re-derives all 30) and, for the libero_10
scenes, off LIBERO-90's tasks in the same scenes ("put the frying pan on the stove", "close the
microwave", "pick up the ketchup and put it in the basket").

`paper`: the LangGap authors' generator templates ("pick up the ... and place it on the ...",
"put the X on the Y", "Pick the X and place it in the basket"), which differ from `libero` in a
few words (the `_PAPER_*` tables). For libero_10 the authors used LIBERO's sentences, so both
styles agree there.
"""

from __future__ import annotations

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import affordances
from langgap.catalog.task import INSTRUCTION_STYLES
from langgap.errors import CatalogError
from langgap.vocabulary import InstructionStyle

# How each suite names object categories (default: the category with spaces).
_NOUNS = {
    "libero_spatial": {
        "akita_black_bowl": "black bowl",
        "glazed_rim_porcelain_ramekin": "ramekin",
        "cookies": "cookie box",
    },
    "libero_goal": {"akita_black_bowl": "bowl"},
    "libero_object": {},
    "libero_10": {
        "akita_black_bowl": "black bowl",
        "cream_cheese": "cream cheese box",
        "chefmate_8_frypan": "frying pan",
        "porcelain_mug": "white mug",
        "white_yellow_mug": "yellow and white mug",
        "red_coffee_mug": "red mug",
        "black_book": "book",
    },
}

# Where something is put, per suite and receiver kind (see `affordances.receiver_kind`).
# `{noun}` is the receiving object's described noun phrase, `{level}` a drawer's level.
_DRAWER_TARGETS = {f"cabinet.{region}": "in the {level} drawer of the cabinet" for region in affordances.DRAWER_LEVEL}
_TARGETS = {
    "libero_spatial": {
        "object": "on {noun}",
        "flat_stove.cook_region": "on the stove",
        "cabinet.top_side": "on the wooden cabinet",
        **{kind: "in the {level} drawer of the wooden cabinet" for kind in _DRAWER_TARGETS},
    },
    "libero_goal": {
        "object": "on {noun}",
        "akita_black_bowl": "in {noun}",
        "flat_stove.cook_region": "on the stove",
        "cabinet.top_side": "on top of the cabinet",
        "wine_rack.top_region": "on the rack",
        "table.stove_front_region": "to the front of the stove",
    },
    "libero_object": {"basket.contain_region": "in the basket"},
    "libero_10": {
        "object": "on {noun}",
        "flat_stove.cook_region": "on the stove",
        "cabinet.top_side": "on top of the cabinet",
        **_DRAWER_TARGETS,
        "wine_rack.top_region": "on the wine rack",
        "basket.contain_region": "in the basket",
        **{f"desk_caddy.{s}_contain_region": f"in the {s} compartment of the caddy" for s in affordances.CADDY_SIDES},
        "table.desk_caddy_right_region": "to the right of the caddy",
        "table.plate_left_region": "to the left of the plate",
        "table.plate_right_region": "to the right of the plate",
        "table.porcelain_mug_front_region": "to the front of the white mug",
        "microwave.heating_region": "in the microwave",
        "microwave.top_side": "on top of the microwave",
    },
}
_PAPER_TARGETS = {
    "libero_spatial": {"cabinet.top_side": "on the cabinet"},
    "libero_goal": {"akita_black_bowl": "on {noun}", "table.stove_front_region": "in front of the stove"},
}

# libero_spatial: how the originals say where an object starts, by its :init table region.
_SPATIAL_TABLE_REGIONS = {
    "main_table_between_plate_ramekin_region": "between the plate and the ramekin",
    "main_table_next_to_ramekin_region": "next to the ramekin",
    "main_table_table_center": "from table center",
    "main_table_next_to_box_region": "next to the cookie box",
    "main_table_next_to_plate_region": "next to the plate",
}
_PAPER_SPATIAL_TABLE_REGIONS = {"main_table_table_center": "from the middle of the table"}
# libero_10 (LIBERO-90 phrasing): instances told apart by an adjective from their :init region.
_INSTANCE_ADJECTIVES = {
    "plate_left_region": "left",
    "plate_right_region": "right",
    "moka_pot_left_init_region": "left",
    "moka_pot_right_init_region": "right",
}

_ARTICULATION = {
    "Turnon": "turn on the {noun}",
    "Turnoff": "turn off the {noun}",
    "Open": "open the {noun}",
    "Close": "close the {noun}",
}
_FIXTURE_NOUNS = {"flat_stove": "stove", "microwave": "microwave"}


def _category_noun(suite: str, category: str) -> str:
    return _NOUNS[suite].get(category, category.replace("_", " "))


def _init_place(obj: str, scene: BddlProblem) -> tuple[str, str]:
    for fact in scene.init:
        if len(fact) == 3 and fact[1] == obj and fact[0].lower() in ("on", "in"):
            return fact[0].lower(), fact[2]
    raise CatalogError(f"{obj!r} has no initial placement to describe")


def _drawer_level(entity: str, scene: BddlProblem) -> str:
    region = affordances.region_of(entity, scene)
    if region is None or region.name not in affordances.DRAWER_LEVEL:
        raise CatalogError(f"{entity!r} is not a drawer of this scene")
    return affordances.DRAWER_LEVEL[region.name]


def _spatial_where(obj: str, scene: BddlProblem, style: str) -> str:
    """How libero_spatial says where `obj` starts, from its :init placement.

    An object "next to X" while another of its category starts "between X and Y" is next to X as well: the
    audit's reference check found "the black bowl next to the ramekin" fitting both bowls of spatial/s0 on 27
    of 50 init states. Such an object is told apart by the other's place, negated ("not between X and Y")."""
    relation, place = _init_place(obj, scene)
    table = _SPATIAL_TABLE_REGIONS | (_PAPER_SPATIAL_TABLE_REGIONS if style == InstructionStyle.PAPER else {})
    if place in table:
        where = table[place]
        if style == InstructionStyle.LIBERO and where.startswith("next to "):
            landmark = where.removeprefix("next to ")
            category = scene.objects[obj]
            for other in (o for o, c in scene.objects.items() if c == category and o != obj):
                theirs = table.get(_init_place(other, scene)[1], "")
                if theirs.startswith("between ") and landmark in theirs:
                    return f"not {theirs}"
        return where
    if relation == "in":
        return f"in the {_drawer_level(place, scene)} drawer of the wooden cabinet"
    # Described as a place the object stands on, in the suite's libero words ("on the wooden cabinet").
    return _target("libero_spatial", InstructionStyle.LIBERO, place, scene)


def _subject(suite: str, obj: str, scene: BddlProblem, style: str) -> str:
    """`the black bowl next to the plate`: the noun phrase of `obj`, described if its category repeats."""
    category = scene.objects[obj]
    noun = _category_noun(suite, category)
    if list(scene.objects.values()).count(category) == 1:
        return f"the {noun}"
    if suite == "libero_spatial":
        return f"the {noun} {_spatial_where(obj, scene, style)}"
    if suite == "libero_10":
        region = affordances.region_of(_init_place(obj, scene)[1], scene)
        if region is not None and region.name in _INSTANCE_ADJECTIVES:
            return f"the {_INSTANCE_ADJECTIVES[region.name]} {noun}"
    raise CatalogError(f"no {suite} phrasing tells {obj!r} apart from the other {noun}s")


def _target(suite: str, style: str, target: str, scene: BddlProblem) -> str:
    kind = affordances.receiver_kind(target, scene)
    table = _TARGETS[suite] | (_PAPER_TARGETS.get(suite, {}) if style == InstructionStyle.PAPER else {})
    phrase = table.get(kind) or (table.get("object") if target in scene.objects else None)
    if phrase is None:
        raise CatalogError(f"no {suite} phrasing for placing something at {target!r}")
    region = affordances.region_of(target, scene)
    level = affordances.DRAWER_LEVEL.get(region.name, "") if region is not None else ""
    noun = _subject(suite, target, scene, style) if target in scene.objects else ""
    return phrase.format(noun=noun, level=level)


def articulated_noun(entity: str, scene: BddlProblem) -> str:
    """What an articulated part is called: `stove`, `microwave`, `top drawer of the cabinet`."""
    if entity in scene.fixtures:
        return _FIXTURE_NOUNS.get(scene.fixtures[entity], scene.fixtures[entity].replace("_", " "))
    return f"{_drawer_level(entity, scene)} drawer of the cabinet"


def _articulation(predicate: Predicate, scene: BddlProblem) -> str:
    (entity,) = predicate.args
    return _ARTICULATION[predicate.name].format(noun=articulated_noun(entity, scene))


def placement_parts(style: str, suite: str, predicate: Predicate, scene: BddlProblem) -> tuple[str, str]:
    """(what, where) of a pick-and-place goal as `style` says them in `suite`: the placed object's noun
    phrase and its destination (`the black bowl next to the plate`, `on the plate`)."""
    obj, target = predicate.args
    kind = affordances.receiver_kind(target, scene) or ""
    if suite == "libero_goal" and kind in _DRAWER_TARGETS:  # libero_goal says "open the drawer and put X inside"
        where = _DRAWER_TARGETS[kind].format(level=_drawer_level(target, scene))
    else:
        where = _target(suite, style, target, scene)
    return _subject(suite, obj, scene, style), where


def _placement(suite: str, style: str, predicate: Predicate, scene: BddlProblem) -> str:
    obj, target = predicate.args
    subject = _subject(suite, obj, scene, style)
    kind = affordances.receiver_kind(target, scene) or ""
    if suite == "libero_spatial":
        return f"pick up {subject} and place it {_target(suite, style, target, scene)}"
    if suite == "libero_goal":
        if kind in _DRAWER_TARGETS:
            return f"open the {_drawer_level(target, scene)} drawer and put {subject} inside"
        verb = "push" if affordances.is_push(predicate, scene) else "put"
        return f"{verb} {subject} {_target(suite, style, target, scene)}"
    if suite == "libero_object":
        verb = "Pick" if style == InstructionStyle.PAPER else "pick up"
        return f"{verb} {subject} and place it {_target(suite, style, target, scene)}"
    # libero_10: LIBERO-90's verbs differ by scene: basket scenes "pick up ... and put it in",
    # the study scene "pick up ... and place it", kitchens and plates "put ...".
    phrase = _target(suite, style, target, scene)
    if kind == "basket.contain_region":
        return f"pick up {subject} and put it {phrase}"
    if kind.startswith("desk_caddy.") or kind == "table.desk_caddy_right_region":
        return f"pick up {subject} and place it {phrase}"
    return f"put {subject} {phrase}"


def instruction(style: str, suite: str, goal: tuple[Predicate, ...] | list[Predicate], scene: BddlProblem) -> str:
    """The `style` sentence for a one-predicate goal on `scene` of `suite`."""
    goal = tuple(goal)
    if style not in INSTRUCTION_STYLES:
        raise CatalogError(f"unknown instruction style {style!r} (known: {', '.join(INSTRUCTION_STYLES)})")
    if suite not in _NOUNS:
        raise CatalogError(f"no phrasing rules for {suite}")
    if len(goal) != 1:
        raise CatalogError(f"phrasing covers one-predicate goals, got {len(goal)}")
    (predicate,) = goal
    if affordances.is_articulation(predicate):
        return _articulation(predicate, scene)
    return _placement(suite, style, predicate, scene)
