"""What the source and the docs cite by name exists: a module as `langgap.catalog.task` (and a name after it, as
`langgap.catalog.task.Task`, in that module) or as a path of the package, `catalog/task` or `catalog/task.py`.
A module that moves leaves no citation of its old place behind."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support.harness import REPO

SRC = REPO / "src" / "langgap"
PACKAGES = sorted(p.name for p in SRC.iterdir() if (p / "__init__.py").is_file())


def _module_file(parts: list[str]) -> Path | None:
    place = SRC.joinpath(*parts)
    for candidate in (place.with_suffix(".py"), place / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _dotted_resolves(parts: list[str]) -> bool:
    """`parts` (after `langgap`) name a module, or a module and a name its text holds."""
    for k in range(len(parts), 0, -1):
        found = _module_file(parts[:k])
        if found is not None:
            return k == len(parts) or re.search(rf"\b{parts[k]}\b", found.read_text(encoding="utf-8")) is not None
    return False


def _broken(text: str) -> list[str]:
    broken = [m for m in re.findall(r"`(langgap(?:\.\w+)+)", text) if not _dotted_resolves(m.split(".")[1:])]
    paths = re.findall(rf"`((?:{'|'.join(PACKAGES)})(?:/\w+)+)(?:\.py)?`", text)
    return broken + [p for p in paths if _module_file(p.split("/")) is None and not (SRC / p).is_dir()]


def test_every_module_the_source_and_docs_cite_exists():
    texts = [*sorted(SRC.rglob("*.py")), *sorted((REPO / "docs").glob("*.md")), REPO / "README.md"]
    found = [
        f"{path.relative_to(REPO)}: {name}" for path in texts for name in _broken(path.read_text(encoding="utf-8"))
    ]
    assert not found, found


def test_a_citation_of_a_moved_module_is_found():
    assert _broken("the file checks (`catalog/audit`), `langgap.validity`, `langgap.catalog.task.Nothing`") == [
        "langgap.validity",
        "langgap.catalog.task.Nothing",
        "catalog/audit",
    ]
    assert _broken("`audit/findings`, `catalog/task.py`, `langgap.catalog.task.Task`, `engine/pools/`") == []
