"""LangGap's exceptions are named apart: no two share a name once its ending (Error, Exception, Failure, Failed)
is taken off, so two different failures never read alike (one attempt's `WorkFailure` and the scheduler's
`AttemptsExhausted` once were `WorkFailure` and `WorkFailed`)."""

from __future__ import annotations

import ast
import re
from collections import defaultdict

from tests.support.harness import REPO

ENDING = re.compile(r"(Error|Exception|Failure|Failed)$")


def _exceptions() -> dict[str, list[str]]:
    """Each exception class's name without its ending -> where the classes of that name are defined."""
    by_stem = defaultdict(list)
    for path in sorted((REPO / "src" / "langgap").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and ENDING.search(node.name):
                by_stem[ENDING.sub("", node.name)].append(f"{node.name} ({path.relative_to(REPO)})")
    return by_stem


def test_no_two_exceptions_read_alike():
    found = _exceptions()
    assert {stem: where for stem, where in found.items() if len(where) > 1} == {}
