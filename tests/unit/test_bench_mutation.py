"""bench_mutation's bookkeeping (no mutation run): what a mutant's exit code counts as, how a survivor is matched
to its review, and that every review in bench/mutation_survivors.toml still names code the module holds."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.bench_mutation import MODULES, ROOT, changed_lines, function_of, review_of, reviewed, status

DIFF = """--- src/langgap/report/stats.py
+++ src/langgap/report/stats.py
@@ -1,7 +1,7 @@
 def mcnemar_exact(only_a: int, only_b: int) -> float:
     n = only_a + only_b
-    if n == 0:
+    if n == 1:
         return 1.0"""
MUTANT = "langgap.report.stats.x_mcnemar_exact__mutmut_4"


@pytest.mark.parametrize(
    ("code", "word"),
    [(1, "killed"), (3, "killed"), (0, "survived"), (33, "no tests"), (5, "no tests"), (36, "timeout"),
     (-24, "timeout"), (None, "not run"), (-11, "exit -11")],
)  # fmt: skip
def test_an_exit_code_is_one_word(code, word):
    assert status(code) == word


def test_a_survivor_is_matched_by_module_function_and_the_lines_it_changes():
    assert changed_lines(DIFF) == ("if n == 0:", "if n == 1:")
    assert function_of(MUTANT) == "x_mcnemar_exact"
    assert function_of("langgap.store.xǁRunStoreǁmeta__mutmut_7") == "xǁRunStoreǁmeta"
    review = {"module": "stats", "function": "x_mcnemar_exact", "removed": "if n == 0:", "added": "if n == 1:"}
    assert review_of("stats", MUTANT, DIFF, [review]) is review
    assert review_of("goals", MUTANT, DIFF, [review]) is None  # another module
    assert review_of("stats", MUTANT, DIFF.replace("n == 1", "n == 2"), [review]) is None  # another change
    other = dict(review, function="x_wilson")
    assert review_of("stats", MUTANT, DIFF, [other]) is None  # the same change in another function


def test_every_review_names_a_module_lines_its_source_still_holds_and_a_reason_of_one_kind():
    reviews = reviewed()
    assert reviews
    for review in reviews:
        assert review["module"] in MODULES, review
        source = {line.strip() for line in (ROOT / MODULES[review["module"]].path).read_text().splitlines()}
        missing = [line for line in review["removed"].splitlines() if line not in source]
        assert not missing, f"{review['module']} {review['function']}: no longer holds {missing}"
        assert review["reason"].startswith(("Equivalent", "Not worth a test: ")), review


def test_every_module_is_a_file_of_the_mutation_config():
    import tomllib

    only = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mutmut"]["only_mutate"])
    assert {m.path for m in MODULES.values()} == only
    assert all(Path(ROOT / m.path).is_file() for m in MODULES.values())
