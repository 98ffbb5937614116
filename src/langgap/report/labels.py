"""How suites, dimensions and splits are named and ordered in reports (the paper's table layout)."""

from __future__ import annotations

from langgap.vocabulary import BEYOND_DIMENSIONS, PAPER_DIMENSIONS, Dimension, Split

# The paper's Table VI order (not LIBERO's suite order).
SUITE_ORDER = ("libero_spatial", "libero_goal", "libero_object", "libero_10")
SUITE_LABEL = {"libero_spatial": "Spatial", "libero_goal": "Goal", "libero_object": "Object", "libero_10": "Libero-10"}

# The paper's dimensions (Table VII, always shown); the `langgap-beyond` ones appear where a run has them.
EXTENDED_DIMENSIONS = PAPER_DIMENSIONS
ALL_EXTENDED_DIMENSIONS = (*PAPER_DIMENSIONS, *BEYOND_DIMENSIONS)
DIMENSION_LABEL = {
    Dimension.ORIGINAL: "Original",
    Dimension.CHANGE_OBJECT: "Change Object",
    Dimension.CHANGE_TARGET: "Change Target",
    Dimension.SPATIAL_DESCRIPTION: "Spatial Description",
    Dimension.DRAWER_ACTION: "Drawer Action",
    Dimension.ORDERING: "Ordering",
    Dimension.NEGATION: "Negation",
    Dimension.PARAPHRASE: "Paraphrase",
    Dimension.ATTRIBUTE_REFERENCE: "Attribute Reference",
    Dimension.TASK: "Task (LIBERO-PRO)",
    Dimension.LANGUAGE: "Language",
}
# Every extended dimension reports name, in table order: LangGap's, then other catalogs' (libero-pro's).
KNOWN_DIMENSIONS = tuple(d for d in DIMENSION_LABEL if d is not Dimension.ORIGINAL)

SPLIT_ORDER = tuple(Split)
SPLIT_LABEL = {
    Split.ORIGINAL: "Original tasks",
    Split.TRAIN: "Extended, training split",
    Split.HELDOUT: "Extended, held-out",
}

# A stored split's groups (`langgap report --split NAME[:K]`), in table order: its training part, its held-out part,
# every other task of the run.
SPLIT_PARTS = ("trained ({})", "held out ({})", "outside {}")


def split_order(groups: set[str]) -> list[str]:
    """`groups` in table order: the catalog's splits, a stored split's parts (`SPLIT_PARTS`), the rest sorted."""
    ranks = {g: i for i, g in enumerate(SPLIT_ORDER)}
    for group in groups:
        for i, part in enumerate(SPLIT_PARTS):
            head, tail = part.split("{}")
            if group.startswith(head) and group.endswith(tail):
                ranks.setdefault(group, len(SPLIT_ORDER) + i)
    return sorted(groups, key=lambda g: (ranks.get(g, len(SPLIT_ORDER) + len(SPLIT_PARTS)), g))


def label(names: dict[str, str], key: str) -> str:
    """The display name of `key`, or the key itself for a name a newer catalog added."""
    return names.get(key, key)
