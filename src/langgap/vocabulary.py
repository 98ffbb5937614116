"""LangGap's words, defined once: what each decision LangGap shows is called, and the rates behind them.

The ground floor: it imports nothing from LangGap, so every layer takes its words from here, and a word
read in a table, a report or a JSON file is the same word everywhere. Each enumeration is a `str` enum
whose values are the words shown. Files keep storing what they stored before (a verdict file keeps
`feasible` and `proof`); the words are derived from that where they are shown.
"""

from __future__ import annotations

from enum import StrEnum


class Verdict(StrEnum):
    """The feasibility gate's verdict on a task, one word each wherever it is shown."""

    # A demonstration did it: the oracle's own episodes at `FEASIBLE_RATE`, or those with stored, replayed
    # searched demonstrations on the init states the oracle failed. The gate admits only these.
    DOABLE = "doable"
    # Rejected without a proof: nobody has shown it doable or impossible (the oracle failing shows nothing
    # about other policies).
    UNPROVEN = "unproven"
    # Rejected with a proof that holds for every policy (`langgap.validity.proofs`).
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
