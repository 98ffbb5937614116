"""Instructions in the `libero` style: the phrasing of LIBERO's published training data.

Public checkpoints were trained on LIBERO's file-name sentences ("pick up the black bowl between
the plate and the ramekin and place it on the plate"). An extended task must be phrased exactly
as the originals phrase the same object, target and relation, so that it differs from its source
sentence only in the words that change the task. The tables below are those phrasings, read
off the 30 originals of libero_spatial / libero_goal / libero_object (a test re-derives all 30).
"""

from __future__ import annotations

from langgap.bddl import BddlProblem, Predicate
from langgap.errors import CatalogError

# How each suite names things (category or region entity -> noun phrase without article).
_NOUNS = {
    "libero_spatial": {
        "akita_black_bowl": "black bowl",
        "glazed_rim_porcelain_ramekin": "ramekin",
        "cookies": "cookie box",
        "plate": "plate",
        "flat_stove_1_cook_region": "stove",
        "wooden_cabinet_1_top_side": "wooden cabinet",
    },
    "libero_goal": {
        "akita_black_bowl": "bowl",
        "cream_cheese": "cream cheese",
        "wine_bottle": "wine bottle",
        "plate": "plate",
    },
}
# Where something is placed: target -> the words after the verb phrase, per suite.
_GOAL_TARGETS = {
    "flat_stove_1_cook_region": "on the stove",
    "wooden_cabinet_1_top_side": "on top of the cabinet",
    "wine_rack_1_top_region": "on the rack",
    "main_table_stove_front_region": "to the front of the stove",
    "akita_black_bowl_1": "in the bowl",
    "plate_1": "on the plate",
}
# libero_spatial: how the originals say where the bowl starts (its :init placement).
_SPATIAL_TABLE_REGIONS = {
    "main_table_between_plate_ramekin_region": "between the plate and the ramekin",
    "main_table_next_to_ramekin_region": "next to the ramekin",
    "main_table_table_center": "from table center",
    "main_table_next_to_box_region": "next to the cookie box",
    "main_table_next_to_plate_region": "next to the plate",
}
_DRAWER_LEVEL = {"top_region": "top", "middle_region": "middle", "bottom_region": "bottom"}


def _noun(suite: str, entity: str, scene: BddlProblem) -> str:
    table = _NOUNS.get(suite, {})
    if entity in table:
        return table[entity]
    category = scene.objects.get(entity) or scene.fixtures.get(entity)
    if category is not None:
        return table.get(category, category.replace("_", " "))
    raise CatalogError(f"no {suite} phrasing for {entity!r}")


def _drawer_level(entity: str, scene: BddlProblem) -> str:
    for region in scene.regions:
        if region.entity == entity and region.name in _DRAWER_LEVEL:
            return _DRAWER_LEVEL[region.name]
    raise CatalogError(f"{entity!r} is not a drawer of this scene")


def _spatial_where(obj: str, scene: BddlProblem) -> str:
    """How libero_spatial says where `obj` starts, from its :init placement."""
    for fact in scene.init:
        if len(fact) == 3 and fact[1] == obj:
            relation, place = fact[0].lower(), fact[2]
            if place in _SPATIAL_TABLE_REGIONS:
                return _SPATIAL_TABLE_REGIONS[place]
            if relation == "in" and place.endswith("_region"):
                return f"in the {_drawer_level(place, scene)} drawer of the wooden cabinet"
            return f"on the {_noun('libero_spatial', place, scene)}"
    raise CatalogError(f"{obj!r} has no initial placement to describe")


def _needs_description(obj: str, scene: BddlProblem) -> bool:
    category = scene.objects.get(obj)
    return sum(1 for c in scene.objects.values() if c == category) > 1


def _spatial(goal: tuple[Predicate, ...], scene: BddlProblem) -> str:
    (p,) = goal
    if p.name in ("Open", "Close"):
        return f"{p.name.lower()} the {_drawer_level(p.args[0], scene)} drawer of the cabinet"
    if p.name == "On":
        obj, target = p.args
        subject = f"the {_noun('libero_spatial', obj, scene)}"
        if _needs_description(obj, scene):
            subject += f" {_spatial_where(obj, scene)}"
        return f"pick up {subject} and place it on the {_noun('libero_spatial', target, scene)}"
    raise CatalogError(f"no libero_spatial phrasing for {p}")


def _goal(goal: tuple[Predicate, ...], scene: BddlProblem) -> str:
    (p,) = goal
    if p.name in ("Open", "Close"):
        return f"{p.name.lower()} the {_drawer_level(p.args[0], scene)} drawer of the cabinet"
    if p.name == "Turnon":
        return "turn on the stove"
    obj = _noun("libero_goal", p.args[0], scene)
    if p.name == "In" and p.args[1].endswith("_region"):
        return f"open the {_drawer_level(p.args[1], scene)} drawer and put the {obj} inside"
    if p.name == "On" and p.args[1] in _GOAL_TARGETS:
        # The plate lies flat and is pushed, never lifted, in this suite.
        verb = "push" if scene.objects.get(p.args[0]) == "plate" else "put"
        return f"{verb} the {obj} {_GOAL_TARGETS[p.args[1]]}"
    raise CatalogError(f"no libero_goal phrasing for {p}")


def _object(goal: tuple[Predicate, ...], scene: BddlProblem) -> str:
    (p,) = goal
    if p.name == "In" and p.args[1] == "basket_1_contain_region":
        return f"pick up the {_noun('libero_object', p.args[0], scene)} and place it in the basket"
    raise CatalogError(f"no libero_object phrasing for {p}")


_BY_SUITE = {"libero_spatial": _spatial, "libero_goal": _goal, "libero_object": _object}


def libero_instruction(suite: str, goal: tuple[Predicate, ...] | list[Predicate], scene: BddlProblem) -> str:
    """The `libero`-style sentence for a single-predicate goal on `scene` of `suite`."""
    goal = tuple(goal)
    if suite not in _BY_SUITE:
        raise CatalogError(f"no libero-style phrasing rules for {suite}")
    if len(goal) != 1:
        raise CatalogError(f"libero-style phrasing covers one-predicate goals, got {len(goal)}")
    return _BY_SUITE[suite](goal, scene)
