"""Stable, readable task ids derived from a task's suite, scene and goal.

An id reads `<suite>/s<k>/<goal-slug>`: the suite, the LIBERO task index whose scene and init
states the task uses, and its goal, e.g. `spatial/s0/black-bowl-2-on-plate` or
`goal/s0/open-cabinet-middle-drawer`. Ids of published catalogs never change; the registry
stores them, and this module is how new ids (the generated `full` catalog) are spelled.
"""

from __future__ import annotations

from collections import Counter

from langgap.bddl import BddlProblem, Predicate

SUITE_SHORT = {"libero_spatial": "spatial", "libero_object": "object", "libero_goal": "goal", "libero_10": "libero10"}

# Category -> slug, where the LIBERO category name is not what a person would call it.
_CATEGORY_SLUG = {
    "akita_black_bowl": "black-bowl",
    "glazed_rim_porcelain_ramekin": "ramekin",
    "cookies": "cookie-box",
    "porcelain_mug": "white-mug",
    "white_yellow_mug": "yellow-white-mug",
    "black_book": "book",
    "flat_stove": "stove",
    "wooden_cabinet": "cabinet",
    "white_cabinet": "cabinet",
    "wine_rack": "rack",
    "desk_caddy": "caddy",
    "chefmate_8_frypan": "frying-pan",
    "red_coffee_mug": "red-mug",
}
# Region name -> slug suffix ("" means the region stands for its fixture, e.g. the stove's cook region).
_REGION_SLUG = {
    "cook_region": "",
    "contain_region": "",
    "heating_region": "",
    "top_side": "top",
    "top_region": "",  # the top of a rack or shelf; a cabinet's top_region is its top drawer (below)
    "back_contain_region": "back",
    "front_contain_region": "front",
    "left_contain_region": "left",
    "right_contain_region": "right",
    "porcelain_mug_front_region": "white-mug-front",
    "desk_caddy_right_region": "caddy-right",
}
_DRAWER_SLUG = {"top_region": "top-drawer", "middle_region": "middle-drawer", "bottom_region": "bottom-drawer"}
_VERB_SLUG = {
    "On": "{0}-on-{1}",
    "In": "{0}-in-{1}",
    "Open": "open-{0}",
    "Close": "close-{0}",
    "Turnon": "turn-on-{0}",
    "Turnoff": "turn-off-{0}",
}


def _category_slug(category: str) -> str:
    return _CATEGORY_SLUG.get(category, category.replace("_", "-"))


def entity_slug(name: str, scene: BddlProblem) -> str:
    """A short name for an object, fixture or region of `scene` (`akita_black_bowl_2` -> `black-bowl-2`)."""
    kinds = {**scene.fixtures, **scene.objects}
    if name in kinds:
        category = kinds[name]
        slug = _category_slug(category)
        if Counter(kinds.values())[category] > 1:
            slug += "-" + name.rsplit("_", 1)[-1]
        return slug
    for region in scene.regions:
        if region.entity == name:
            target_kind = kinds.get(region.target, "")
            if "cabinet" in target_kind and region.name in _DRAWER_SLUG:
                suffix = _DRAWER_SLUG[region.name]
            else:
                suffix = _REGION_SLUG.get(region.name, region.name.removesuffix("_region").replace("_", "-"))
            if region.target not in kinds or target_kind.endswith("table"):
                return suffix  # a region of the table itself, e.g. `stove-front`
            base = entity_slug(region.target, scene)
            return f"{base}-{suffix}" if suffix else base
    return name.replace("_", "-")


def goal_slug(goal: tuple[Predicate, ...] | list[Predicate], scene: BddlProblem) -> str:
    """`black-bowl-1-on-plate`; conjunctions are joined with `+` in goal order."""
    return "+".join(_VERB_SLUG[p.name].format(*(entity_slug(a, scene) for a in p.args)) for p in goal)


def task_id(suite: str, scene_index: int, goal: tuple[Predicate, ...] | list[Predicate], scene: BddlProblem) -> str:
    """The id of the task with `goal` on the scene of LIBERO task `scene_index` of `suite`."""
    return f"{SUITE_SHORT[suite]}/s{scene_index}/{goal_slug(goal, scene)}"
