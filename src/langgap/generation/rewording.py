"""Sentences of the `langgap-beyond` tasks: templates over the phrasing of `phrasing`, no model at run time.

Every sentence is built from the pieces `phrasing` gives a goal in one instruction style (the placed
object's noun phrase, its destination, an articulated part's noun, the whole sentence), so both styles
of a new task differ from their source's sentence only where the dimension says. Templates are data.
"""

from __future__ import annotations

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import affordances
from langgap.generation import phrasing

ORDERED = "first {first}, then {then}"
NEGATED_WHERE = "anywhere but {where}"
NEGATED_WHAT = "anything but {what}"

# Paraphrase templates: name -> {goal kind: template}. The kind is `place` (one pick-and-place goal:
# {what}, {where}), an articulation predicate ({noun}), or `any` (every goal, LIBERO's conjunctions
# too: {sentence}, the original sentence in the same style). A name without a template for a goal's
# kind gives that goal no paraphrase.
PARAPHRASES: dict[str, dict[str, str]] = {
    "synonyms": {
        "place": "grab {what} and set it down {where}",
        "Open": "pull open the {noun}",
        "Close": "push the {noun} shut",
        "Turnon": "switch on the {noun}",
        "Turnoff": "switch off the {noun}",
    },
    "passive": {
        "place": "{what} should be picked up and placed {where}",
        "Open": "the {noun} should be opened",
        "Close": "the {noun} should be closed",
        "Turnon": "the {noun} should be turned on",
        "Turnoff": "the {noun} should be turned off",
    },
    "clause-order": {"place": "place it {where} after you pick up {what}"},
    "conversational": {"any": "could you please {sentence}?"},
}

# Attribute references: category -> (the phrase, the attribute it names). The phrase refers to one
# object only where no other object of the scene has the same attribute. Colours are the ones the
# category names state (LIBERO's `akita_black_bowl`, `red_coffee_mug`, ...); contents name a container
# by what it holds.
ATTRIBUTES: dict[str, tuple[str, str]] = {
    "akita_black_bowl": ("the black one", "colour:black"),
    "black_book": ("the black one", "colour:black"),
    "red_coffee_mug": ("the red one", "colour:red"),
    "white_yellow_mug": ("the yellow one", "colour:yellow"),
    "alphabet_soup": ("the container of alphabet soup", "holds:alphabet soup"),
    "bbq_sauce": ("the container of barbecue sauce", "holds:barbecue sauce"),
    "butter": ("the container of butter", "holds:butter"),
    "chocolate_pudding": ("the container of chocolate pudding", "holds:chocolate pudding"),
    "cookies": ("the container of cookies", "holds:cookies"),
    "cream_cheese": ("the container of cream cheese", "holds:cream cheese"),
    "ketchup": ("the container of ketchup", "holds:ketchup"),
    "milk": ("the container of milk", "holds:milk"),
    "orange_juice": ("the container of orange juice", "holds:orange juice"),
    "salad_dressing": ("the container of salad dressing", "holds:salad dressing"),
    "tomato_sauce": ("the container of tomato sauce", "holds:tomato sauce"),
    "wine_bottle": ("the container of wine", "holds:wine"),
}


def replace_once(sentence: str, phrase: str, replacement: str) -> str | None:
    """`sentence` with its one occurrence of `phrase` replaced (None when it has none or several)."""
    return sentence.replace(phrase, replacement) if sentence.count(phrase) == 1 else None


def single_goal_sentence(style: str, suite: str, predicate: Predicate, scene: BddlProblem) -> str:
    """The `style` sentence of a one-atom goal (LIBERO's phrasing rules)."""
    return phrasing.instruction(style, suite, (predicate,), scene)


def ordered(first: str, then: str) -> str:
    """ "first A, then B" from the sentences of A and B."""
    return ORDERED.format(first=first, then=then)


def negated(style: str, suite: str, predicate: Predicate, scene: BddlProblem, part: str) -> str | None:
    """The sentence of a pick-and-place goal with its destination (`part="where"`) or its object
    (`part="what"`) negated; None where the sentence does not name that part exactly once."""
    what, where = phrasing.placement_parts(style, suite, predicate, scene)
    sentence = single_goal_sentence(style, suite, predicate, scene)
    if part == "where":
        return replace_once(sentence, where, NEGATED_WHERE.format(where=where))
    return replace_once(sentence, what, NEGATED_WHAT.format(what=what))


def attribute_reference(obj: str, scene: BddlProblem) -> str | None:
    """A phrase naming `obj` by an attribute that no other object of `scene` shares (None: there is none)."""
    entry = ATTRIBUTES.get(scene.objects[obj])
    if entry is None:
        return None
    phrase, attribute = entry
    sharing = [o for o, category in scene.objects.items() if ATTRIBUTES.get(category, ("", ""))[1] == attribute]
    return phrase if sharing == [obj] else None


def by_attribute(style: str, suite: str, predicate: Predicate, scene: BddlProblem) -> str | None:
    """The sentence of a pick-and-place goal with its object named by an attribute (None where that is ambiguous)."""
    phrase = attribute_reference(predicate.args[0], scene)
    if phrase is None:
        return None
    what, _ = phrasing.placement_parts(style, suite, predicate, scene)
    return replace_once(single_goal_sentence(style, suite, predicate, scene), what, phrase)


def paraphrase(
    name: str, style: str, suite: str, goal: tuple[Predicate, ...], scene: BddlProblem, sentence: str
) -> str | None:
    """Paraphrase `name` of a goal whose `style` sentence is `sentence` (None: no template for that goal)."""
    templates = PARAPHRASES[name]
    if "any" in templates:
        return templates["any"].format(sentence=sentence[:1].lower() + sentence[1:])
    if len(goal) != 1:
        return None
    (predicate,) = goal
    if affordances.is_articulation(predicate):
        template = templates.get(predicate.name)
        return None if template is None else template.format(noun=phrasing.articulated_noun(predicate.args[0], scene))
    what, where = phrasing.placement_parts(style, suite, predicate, scene)
    return templates["place"].format(what=what, where=where)
