"""How suites, dimensions and splits are named and ordered in reports (the paper's table layout)."""

from __future__ import annotations

from langgap.catalog.task import BEYOND_DIMENSIONS, PAPER_DIMENSIONS, SPLITS
from langgap.vocabulary import TaskKind

# The paper's Table VI order (not LIBERO's suite order).
SUITE_ORDER = ("libero_spatial", "libero_goal", "libero_object", "libero_10")
SUITE_LABEL = {"libero_spatial": "Spatial", "libero_goal": "Goal", "libero_object": "Object", "libero_10": "Libero-10"}

# The paper's dimensions (Table VII, always shown); the `langgap-beyond` ones appear where a run has them.
EXTENDED_DIMENSIONS = PAPER_DIMENSIONS
ALL_EXTENDED_DIMENSIONS = (*PAPER_DIMENSIONS, *BEYOND_DIMENSIONS)
DIMENSION_LABEL = {
    TaskKind.ORIGINAL: "Original",
    "change_object": "Change Object",
    "change_target": "Change Target",
    "spatial_description": "Spatial Description",
    "drawer_action": "Drawer Action",
    "ordering": "Ordering",
    "negation": "Negation",
    "paraphrase": "Paraphrase",
    "attribute_reference": "Attribute Reference",
    "task": "Task (LIBERO-PRO)",
    "language": "Language",
}
# Every extended dimension reports name, in table order: LangGap's, then other catalogs' (libero-pro's).
KNOWN_DIMENSIONS = tuple(d for d in DIMENSION_LABEL if d != TaskKind.ORIGINAL)

SPLIT_ORDER = SPLITS
SPLIT_LABEL = {
    TaskKind.ORIGINAL: "Original tasks",
    "train": "Extended, training split",
    "heldout": "Extended, held-out",
}


def label(names: dict[str, str], key: str) -> str:
    """The display name of `key`, or the key itself for a name a newer catalog added."""
    return names.get(key, key)
