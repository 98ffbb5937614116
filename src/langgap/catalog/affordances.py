"""What a LIBERO scene affords: which objects can be moved, what can receive them, what articulates.

Everything here is read off a parsed BDDL scene (`BddlProblem`), so the same rules apply to every
suite. A *receiver* is an object (a plate, a bowl, ...) or a region of a fixture or object (the
stove's cook region, a drawer, the basket's inside, a named spot on the table). Its *kind* is the
object's category, or `<owner kind>.<region name>` for a region (`flat_stove.cook_region`,
`cabinet.top_region`, `table.stove_front_region`), and `RECEIVES` says, per kind, which object
categories it takes and with which predicate. Sizes quoted in the comments were measured in the
simulator (axis-aligned extent of each object's collision geometry).
"""

from __future__ import annotations

from dataclasses import dataclass

from langgap.bddl import BddlProblem, Predicate, Region

# Fixture categories that play the same role get one kind, so the rules below name them once.
_OWNER_KIND = {
    "wooden_cabinet": "cabinet",
    "white_cabinet": "cabinet",
    "table": "table",
    "kitchen_table": "table",
    "living_room_table": "table",
    "study_table": "table",
}

_BOWL = "akita_black_bowl"
_RAMEKIN = "glazed_rim_porcelain_ramekin"
_COOKIE_BOX = "cookies"
# Bowl (10.7 cm), ramekin (8.9 cm) and cookie box (8.3 x 6.2 cm) stack on each other in any order:
# LIBERO's own scenes put the bowl on the ramekin and on the box, the paper the ramekin on the box
# and the box on the ramekin.
_SMALL_DISHES = frozenset({_BOWL, _RAMEKIN, _COOKIE_BOX})
_GROCERIES = frozenset(
    {
        "alphabet_soup",
        "bbq_sauce",
        "butter",
        "chocolate_pudding",
        "cream_cheese",
        "ketchup",
        "milk",
        "orange_juice",
        "salad_dressing",
        "tomato_sauce",
    }
)
_MUGS = frozenset({"porcelain_mug", "white_yellow_mug", "red_coffee_mug"})
_COOKWARE = frozenset({"chefmate_8_frypan", "moka_pot"})
# What goes on a plate: everything smaller that is food or tableware (the paper stands the wine
# bottle on it). The plate itself (13.8 cm) is wider than every other dish, so it only goes on
# fixtures and table spots; cookware and books on a plate are not kitchen tasks.
_ON_A_PLATE = _SMALL_DISHES | _GROCERIES | _MUGS | {"wine_bottle"}
# What is set down on a counter-like surface (stove top, cabinet top, a drawer, a table spot).
_TABLETOP = _ON_A_PLATE | {"plate", "black_book"}


@dataclass(frozen=True)
class Rule:
    """A receiver kind takes these object categories, and the goal uses this predicate."""

    predicate: str
    takes: frozenset[str]


_DRAWERS = ("top_region", "middle_region", "bottom_region")
CADDY_SIDES = ("back", "front", "left", "right")
DRAWER_LEVEL = {"top_region": "top", "middle_region": "middle", "bottom_region": "bottom"}

RECEIVES: dict[str, Rule] = {
    # Objects that receive. A bowl also takes cream cheese (LIBERO-Goal's "put the cream cheese in
    # the bowl"). Bottles go on no dish but the plate: a 16 cm bottle in a bowl or on a ramekin topples.
    "plate": Rule("On", _ON_A_PLATE),
    _BOWL: Rule("On", _SMALL_DISHES | {"cream_cheese"}),
    _RAMEKIN: Rule("On", _SMALL_DISHES),
    _COOKIE_BOX: Rule("On", _SMALL_DISHES),
    # Fixture surfaces.
    "flat_stove.cook_region": Rule("On", _TABLETOP | _COOKWARE),
    "cabinet.top_side": Rule("On", _TABLETOP),
    "microwave.top_side": Rule("On", _ON_A_PLATE),
    # Containers. A rack holds bottles; caddy compartments are book-sized (a mug does not fit); a
    # basket holds groceries (LIBERO never puts dishes in one); the microwave heats dishes and mugs.
    **{f"cabinet.{drawer}": Rule("In", _TABLETOP) for drawer in _DRAWERS},
    "wine_rack.top_region": Rule("On", frozenset({"wine_bottle"})),
    "basket.contain_region": Rule("In", _GROCERIES),
    **{f"desk_caddy.{side}_contain_region": Rule("In", frozenset({"black_book"})) for side in CADDY_SIDES},
    "microwave.heating_region": Rule("In", _SMALL_DISHES | _MUGS),
}

# Table regions that name a place rather than a spawn area, with the category they are relative
# to. Nothing is put relative to itself ("the white mug to the front of the white mug").
TABLE_SPOTS = {
    "stove_front_region": "flat_stove",
    "porcelain_mug_front_region": "porcelain_mug",
    "plate_left_region": "plate",
    "plate_right_region": "plate",
    "desk_caddy_right_region": "desk_caddy",
}
_TABLE_SPOT_TAKES = _TABLETOP | _COOKWARE

# Articulated fixtures: (predicate that holds when on/open, predicate that makes it off/closed).
# Cabinet drawers articulate per drawer region, the others as a whole.
_ARTICULATED = {"flat_stove": ("Turnon", "Turnoff"), "microwave": ("Open", "Close")}
_DRAWER_ACTIONS = ("Open", "Close")


def region_of(entity: str, scene: BddlProblem) -> Region | None:
    """The region whose predicate name is `entity`, if it is one."""
    return next((r for r in scene.regions if r.entity == entity), None)


def category(entity: str, scene: BddlProblem) -> str:
    """An object's or fixture's category; a region stands for itself (each drawer is its own thing)."""
    return scene.objects.get(entity) or scene.fixtures.get(entity) or entity


def receiver_kind(entity: str, scene: BddlProblem) -> str | None:
    """`plate`, `flat_stove.cook_region`, `table.stove_front_region`, ...; None if `entity` receives nothing."""
    if entity in scene.objects:
        return scene.objects[entity]
    region = region_of(entity, scene)
    if region is None:
        return None
    owner = scene.objects.get(region.target) or scene.fixtures.get(region.target)
    if owner is None:
        return None  # a region of something the scene lacks (LIBERO-Goal's bowl_drainer regions)
    return f"{_OWNER_KIND.get(owner, owner)}.{region.name}"


def _init_facts(scene: BddlProblem) -> set[tuple[str, ...]]:
    return {(fact[0].lower(), *fact[1:]) for fact in scene.init}


def _stacks(scene: BddlProblem) -> tuple[set[str], set[str]]:
    """Objects that hold another at t0, and objects that stand on or in another at t0."""
    stacked = [f for f in scene.init if len(f) == 3 and f[0].lower() in ("on", "in") and f[2] in scene.objects]
    return {f[2] for f in stacked}, {f[1] for f in stacked}


def _table_spot_rule(region: Region, scene: BddlProblem) -> Rule | None:
    anchor = TABLE_SPOTS.get(region.name)
    used_at_init = any(len(f) == 3 and f[2] == region.entity for f in scene.init)
    if anchor is None or used_at_init or anchor not in {*scene.objects.values(), *scene.fixtures.values()}:
        return None  # a spawn area, or a spot relative to something absent
    return Rule("On", _TABLE_SPOT_TAKES - {anchor})


def receivers(scene: BddlProblem) -> list[tuple[str, Rule]]:
    """Every entity of `scene` that can receive something, with its rule, in BDDL order.

    An object already in a stack at t0 (holding another, or standing on one) receives nothing:
    that would build a three-high tower, which no LIBERO task does.
    """
    holders, standing = _stacks(scene)
    out: list[tuple[str, Rule]] = []
    for name, cat in scene.objects.items():
        if cat in RECEIVES and name not in holders | standing:
            out.append((name, RECEIVES[cat]))
    for region in scene.regions:
        kind = receiver_kind(region.entity, scene) or ""
        rule = _table_spot_rule(region, scene) if kind.startswith("table.") else RECEIVES.get(kind)
        if rule is not None:
            out.append((region.entity, rule))
    return out


def movable(scene: BddlProblem) -> list[str]:
    """Objects that can be picked and placed, in BDDL order.

    An object that holds another at t0 stays put: moving it carries or drops what is on it.
    """
    holders, _ = _stacks(scene)
    takes = frozenset().union(*(rule.takes for rule in RECEIVES.values()), _TABLE_SPOT_TAKES)
    return [name for name, cat in scene.objects.items() if cat in takes and name not in holders]


def placements(scene: BddlProblem) -> list[Predicate]:
    """Every pick-and-place goal the scene affords that is not already true at t0 by construction."""
    facts = _init_facts(scene)
    out = []
    for obj in movable(scene):
        for target, rule in receivers(scene):
            if obj == target or scene.objects[obj] not in rule.takes:
                continue
            if ("on", obj, target) in facts or ("in", obj, target) in facts:
                continue  # its own :init placement
            out.append(Predicate.of(rule.predicate, (obj, target)))
    return out


def placements_onto(target: str, scene: BddlProblem) -> list[Predicate]:
    """Every object receiver `target` takes, as a placement onto it that is not true at t0, in BDDL order.

    Unlike `placements`, an object holding another at t0 counts: a sentence that allows "anything" onto
    `target` allows lifting what stands on it off first (no generated single goal asks for that)."""
    rule = dict(receivers(scene)).get(target)
    if rule is None:
        return []
    facts = _init_facts(scene)
    return [
        Predicate.of(rule.predicate, (obj, target))
        for obj, cat in scene.objects.items()
        if obj != target and cat in rule.takes and (rule.predicate.lower(), obj, target) not in facts
    ]


def articulations(scene: BddlProblem) -> list[Predicate]:
    """For each articulated part, the one action that changes its :init state (open a closed drawer, ...)."""
    facts = _init_facts(scene)
    parts: list[tuple[str, tuple[str, str]]] = []
    for region in scene.regions:
        if receiver_kind(region.entity, scene) in {f"cabinet.{d}" for d in _DRAWERS}:
            parts.append((region.entity, _DRAWER_ACTIONS))
    for name, cat in scene.fixtures.items():
        if cat in _ARTICULATED:
            parts.append((name, _ARTICULATED[cat]))
    out = []
    for entity, (on, off) in parts:
        is_on = (on.lower(), entity) in facts
        out.append(Predicate.of(off if is_on else on, (entity,)))
    return out


def is_push(predicate: Predicate, scene: BddlProblem) -> bool:
    """Whether the placement is done by pushing: the plate lies flat and is pushed, not lifted, to a
    spot on the table."""
    obj, target = predicate.args
    return scene.objects.get(obj) == "plate" and (receiver_kind(target, scene) or "").startswith("table.")


def is_articulation(predicate: Predicate) -> bool:
    """Open, Close, Turnon, Turnoff: an action on a fixture rather than a pick-and-place."""
    return predicate.name not in ("On", "In")
