"""LangGap's words, defined once: the kinds of task, their dimensions (in groups) and splits, the instruction
styles, the language conditions, the outcomes of an episode, the steppings and seed schemes of its physics, the
gate's verdicts, and the rates behind them.

The ground floor: it imports nothing from LangGap, so every layer takes its words from here, and a word
read in a table, a report or a JSON file is the same word everywhere. Each enumeration is a `str` enum
whose values are the words shown. Files keep storing what they stored before (a verdict file keeps
`feasible` and `proof`); the words are derived from that where they are shown.

A member equals its word, hashes as it, and f-strings, `csv` and `json` write its word, so code compares, keys
and formats with the members. Its `repr` is not its word's (`<TaskKind.ORIGINAL: 'original'>`) and YAML refuses
it, so the fields that held plain strings keep holding them: where a word becomes a task's kind, dimension or
split, an episode's condition, a default that runs into specs and options, or a run spec's conditions, it is its
`.value` (or `words`), and so are argparse's choices (its `invalid choice` error quotes their reprs).
"""

from __future__ import annotations

from collections.abc import Iterable
from enum import StrEnum


class TaskKind(StrEnum):
    """What a task is. An original's dimension and split are its kind's word too (`langgap.catalog.task`).

    Attributes:
        ORIGINAL: A LIBERO task, run from LIBERO's own BDDL file.
        EXTENDED: A LangGap task set on an original's scene and init states (its `source`).
    """

    ORIGINAL = "original"
    EXTENDED = "extended"


class Dimension(StrEnum):
    """What a task changes of its source (`langgap.catalog.task`), in three groups: the paper's
    (`PAPER_DIMENSIONS`), those of LangGap's `langgap-beyond` catalog (`BEYOND_DIMENSIONS`) and the perturbations
    of the field's benchmarks read from their packages (`EXTERNAL_DIMENSIONS`). An original's is its kind's word.

    Attributes:
        ORIGINAL: An original task's (it changes nothing).
        CHANGE_OBJECT: Another object to move (the paper's).
        CHANGE_TARGET: Another place to put it (the paper's).
        SPATIAL_DESCRIPTION: An object told apart by where it stands (the paper's).
        DRAWER_ACTION: Another drawer action (the paper's).
        ORDERING: Two sub-goals in a stated order (beyond).
        NEGATION: An object told apart by what it is not next to or between (beyond).
        PARAPHRASE: The source's own goal in other words (beyond).
        ATTRIBUTE_REFERENCE: An object told apart by an attribute (beyond).
        TASK: Another goal on the same scene (LIBERO-PRO's *task*).
        LANGUAGE: A reworded instruction (LIBERO-PRO's *lan*, LIBERO-Plus's language).
    """

    ORIGINAL = "original"
    CHANGE_OBJECT = "change_object"
    CHANGE_TARGET = "change_target"
    SPATIAL_DESCRIPTION = "spatial_description"
    DRAWER_ACTION = "drawer_action"
    ORDERING = "ordering"
    NEGATION = "negation"
    PARAPHRASE = "paraphrase"
    ATTRIBUTE_REFERENCE = "attribute_reference"
    TASK = "task"
    LANGUAGE = "language"


# The paper's four dimensions, then the four of the `langgap-beyond` catalog (`generation/beyond.py`).
PAPER_DIMENSIONS = (
    Dimension.CHANGE_OBJECT,
    Dimension.CHANGE_TARGET,
    Dimension.SPATIAL_DESCRIPTION,
    Dimension.DRAWER_ACTION,
)
BEYOND_DIMENSIONS = (Dimension.ORDERING, Dimension.NEGATION, Dimension.PARAPHRASE, Dimension.ATTRIBUTE_REFERENCE)
# The perturbations of the field's benchmarks read from their packages (`generation/external.py`).
EXTERNAL_DIMENSIONS = (Dimension.TASK, Dimension.LANGUAGE)
# Dimensions whose tasks ask for their source's own goal in other words: a policy that ignores its instruction
# does them as well as their sources, so they alone cannot show whether it reads.
SAME_GOAL_DIMENSIONS = (Dimension.PARAPHRASE, Dimension.LANGUAGE)


class Split(StrEnum):
    """Which part of a catalog's tasks a task belongs to (a task's own `split` field; `langgap.catalog.splits`
    holds split *files*, selections made over these).

    Attributes:
        ORIGINAL: An original task's (its kind's word).
        TRAIN: An extended task a policy may be trained on.
        HELDOUT: An extended task held out of training.
    """

    ORIGINAL = "original"
    TRAIN = "train"
    HELDOUT = "heldout"


class InstructionStyle(StrEnum):
    """The sentence of a task a policy is sent (`langgap.catalog.task.Task.instruction`).

    Attributes:
        LIBERO: LIBERO's phrasing (the default).
        PAPER: The paper's phrasing.
        PACKAGE: What the runner of the package a task was read from sends (`langgap.catalog.runner_sentences`):
            only tasks read from a package, and their catalogs' originals, have it.
    """

    LIBERO = "libero"
    PAPER = "paper"
    PACKAGE = "package"


class Condition(StrEnum):
    """A language condition: which instruction an episode's policy receives (`langgap.engine.plan`). Beside
    these fixed ones, `switch:K` (`SWITCH`) changes the instruction at policy step K.

    Attributes:
        GIVEN: The task's own.
        EMPTY: An empty string.
        SHUFFLED: Another task's on the same scene.
        SOURCE: The task's source (original) task's.
        NONSENSE: As many words as the task's, drawn from the catalog's instructions.
    """

    GIVEN = "given"
    EMPTY = "empty"
    SHUFFLED = "shuffled"
    SOURCE = "source"
    NONSENSE = "nonsense"


# `switch:K`: another task's instruction until policy step K, then the task's own (`switch_step`).
SWITCH = "switch:"


def switch_step(condition: str) -> int | None:
    """K of a valid `switch:K` condition (a positive number of policy steps); None for any other condition."""
    k = condition.removeprefix(SWITCH)
    return int(k) if condition.startswith(SWITCH) and k.isdigit() and int(k) >= 1 else None


class Outcome(StrEnum):
    """What an episode achieved (see `langgap.records.classify`).

    Attributes:
        SUCCESS: The task's goal held.
        PERSISTED: After its instruction changed, the policy achieved the first instruction's goal.
        WRONG_ORDER: An ordered task's sub-goals all held, but not in the order asked.
        DID_SOURCE_TASK: An extended task's policy did the scene's original task instead.
        DID_OTHER_TASK: The policy achieved the goal of another task of the scene.
        NO_GOAL_REACHED: No goal of the scene's tasks held.
        POLICY_ERROR: The policy returned a malformed action.
        GAP: Infrastructure failed to run the episode: no verdict on the policy.
    """

    SUCCESS = "success"
    PERSISTED = "persisted"
    WRONG_ORDER = "wrong_order"
    DID_SOURCE_TASK = "did_source_task"
    DID_OTHER_TASK = "did_other_task"
    NO_GOAL_REACHED = "no_goal_reached"
    POLICY_ERROR = "policy_error"
    GAP = "gap"


class Stepping(StrEnum):
    """How physics substeps are computed (`langgap.sim.stepping`): `fast` differs from the others in the last bits
    (and then drifts), so a result's physics names it.

    Attributes:
        EXACT: The bits of robosuite's own stepping, faster.
        FAST: The last bits differ, faster still.
        ROBOSUITE: robosuite's own code, slower (for benchmarks and tests).
    """

    EXACT = "exact"
    FAST = "fast"
    ROBOSUITE = "robosuite"


class SeedScheme(StrEnum):
    """How an episode's seed selects its fixture placement (`langgap.sim.env.TaskEnv.reset`).

    Attributes:
        PER_EPISODE: NumPy seeded with the episode's own seed (run seed + k for init state k).
        OPENPI: As openpi's LIBERO example: one stream per task seeded once (with the run seed), episode k drawing
            after k resets' draws.
    """

    PER_EPISODE = "per-episode"
    OPENPI = "openpi"


def words(members: Iterable[str]) -> tuple[str, ...]:
    """`members` as plain strings, for data a user holds and for what shows their `repr` (argparse's `invalid
    choice` error quotes its choices' reprs)."""
    return tuple(str(member) for member in members)


class Verdict(StrEnum):
    """The feasibility gate's verdict on a task, one word each wherever it is shown."""

    # A demonstration did it: the oracle's own episodes at `FEASIBLE_RATE`, or those with stored, replayed
    # searched demonstrations on the init states the oracle failed. The gate admits only these.
    DOABLE = "doable"
    # Rejected without a proof: nobody has shown it doable or impossible (the oracle failing shows nothing
    # about other policies).
    UNPROVEN = "unproven"
    # Rejected with a proof that holds for every policy (`langgap.gate.proofs`).
    INFEASIBLE = "infeasible"
    # Rejected because its starts do not come to rest: the scene still moves after the settle steps, so the
    # task has no fixed start to be judged from, whatever the oracle did on it. A word of its own, since it
    # says nothing of whether the task can be done (neither unproven nor infeasible).
    UNSETTLED = "unsettled"


# The gate admits a task when the oracle's episodes and searched demonstrations do this share of its init states.
FEASIBLE_RATE = 0.90
# An oracle below this share of a run's init states marks the task ⚠ beside the run's results: an admitted task
# can carry ⚠ (between `FEASIBLE_RATE` and this), the ceiling a policy's rate is read against being lower.
CEILING_TARGET = 0.95
# The switch gate admits a task at one K (`switch:K`) when the oracle follows the switch on this share of the
# init states, with no gap.
SWITCH_RATE = 0.95
