"""How suites, dimensions and splits are named and ordered in reports (the paper's table layout)."""

from __future__ import annotations

from langgap.catalog.task import DIMENSIONS, SPLITS

# The paper's Table VI order (not LIBERO's suite order).
SUITE_ORDER = ("libero_spatial", "libero_goal", "libero_object", "libero_10")
SUITE_LABEL = {"libero_spatial": "Spatial", "libero_goal": "Goal", "libero_object": "Object", "libero_10": "Libero-10"}

EXTENDED_DIMENSIONS = tuple(d for d in DIMENSIONS if d != "original")
DIMENSION_LABEL = {
    "original": "Original",
    "change_object": "Change Object",
    "change_target": "Change Target",
    "spatial_description": "Spatial Description",
    "drawer_action": "Drawer Action",
}

SPLIT_ORDER = SPLITS
SPLIT_LABEL = {"original": "Original tasks", "train": "Extended, training split", "heldout": "Extended, held-out"}


def label(names: dict[str, str], key: str) -> str:
    """The display name of `key`, or the key itself for a name a newer catalog added."""
    return names.get(key, key)
