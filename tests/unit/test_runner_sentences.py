"""The sentence the field's runners send, computed as their packages compute it, on hand-written files."""

from __future__ import annotations

from langgap.catalog.runner_sentences import PLUS_FALLBACK, file_name_sentence, plus_sentence

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
