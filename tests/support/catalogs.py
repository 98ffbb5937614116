"""Cut-down copies of a shipped registry, so that harness tests run a few tasks with short step limits."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import yaml

from tests.support.harness import REPO

REGISTRY = REPO / "src/langgap/catalog/registry"


def cut_down_catalog(
    path: Path,
    ids: Iterable[str],
    *,
    steps: int | None = None,
    registry: str = "langgap99",
    changes: dict[str, dict] | None = None,
    copies: Iterable[tuple[str, dict]] = (),
) -> Path:
    """Write at `path` (named after its stem) `registry` holding only the tasks `ids`, each task's fields replaced by
    `changes[id]`, plus `copies`: (the id of a kept task, the fields its copy replaces, its new id among them);
    every suite's step limit `steps` (None: the registry's own)."""
    data = yaml.safe_load((REGISTRY / f"{registry}.yaml").read_text(encoding="utf-8"))
    data["catalog"] = path.stem
    if steps is not None:
        data["max_steps"] = {suite: steps for suite in data["max_steps"]}
    changes = changes or {}
    ids = set(ids)
    kept = {t["id"]: t | changes.get(t["id"], {}) for t in data["tasks"] if t["id"] in ids}
    data["tasks"] = [*kept.values(), *(kept[of] | fields for of, fields in copies)]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path
