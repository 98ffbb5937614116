"""The answer a report opens with: one sentence per run that a reader can quote.

It says how well the policy reads its instruction — success on the original tasks against the
extended ones (with the extended rate's interval and the paired test), the oracle's ceiling on the
extended tasks, and how often the policy did the scene's original task instead (the default-task
rate, with its interval). The verdict word compares the extended rate with the original one:
`READS` of it or more reads the instruction, `WEAKLY` or more reads it weakly, less hardly reads it.
A run whose extended tasks ran only under a switch (`switch:K`) says, per K, how often the policy did
the task switched to and how often it went on with the first instruction's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from langgap.report.data import Spec
from langgap.report.stats import PairedTest, Rate
from langgap.vocabulary import Condition, TaskKind

READS = 0.8  # extended success at this share of original success or more: the policy reads its instruction
WEAKLY = 0.2  # at this share or more (below READS): it reads its instruction weakly; below: hardly
SIGNIFICANT = 0.05


def percent(x: float) -> str:
    return f"{100 * x:.0f} %"


def interval(r: Rate) -> str:
    low, high = r.ci
    return f"[{100 * low:.0f}, {100 * high:.0f}]"


def p_text(test: PairedTest) -> str:
    return "p < 0.001" if test.p_value < 0.001 else f"p = {test.p_value:.2g}"


@dataclass(frozen=True)
class Switched:
    """A run's extended episodes under one `switch:K`: the share that did the task switched to, and the share
    that went on with the task the first instruction asked for (`persisted`)."""

    k: int
    success: Rate
    persisted: Rate

    @property
    def text(self) -> str:
        success, persisted = self.success, self.persisted
        return (
            f"at K={self.k} it did the task switched to in {percent(success.rate)} {interval(success)} of "
            f"{success.episodes} {TaskKind.EXTENDED} episodes and went on with the first instruction's task in "
            f"{percent(persisted.rate)} {interval(persisted)}"
        )


@dataclass(frozen=True)
class Answer:
    """What one run's opening sentence says (every number from the summary)."""

    label: str
    original: Rate  # original tasks
    extended: Rate  # extended tasks
    default_task: Rate  # extended episodes that did the scene's original task instead
    against_originals: PairedTest | None  # extended episodes against their sources'
    against_blind: PairedTest | None  # extended episodes against a compared blind run's
    gaps: int
    same_goal_only: bool = False  # every extended task asks for its source's goal in other words
    reworded_left_out: int = 0  # extended tasks left out of `extended`: rewordings of their source's goal
    switched: tuple[Switched, ...] = ()  # extended episodes under each `switch:K` of the run, in K order

    @property
    def verdict(self) -> str | None:
        """How well the policy reads its instruction (None: no extended tasks, no original success to compare
        with, or only extended tasks that a policy ignoring its instruction does as well as their sources)."""
        if self.same_goal_only:
            return None
        if not self.extended.episodes or not self.original.episodes or not self.original.rate:
            return None
        share = self.extended.rate / self.original.rate
        if share >= READS:
            return "reads its instruction"
        return "reads its instruction weakly" if share >= WEAKLY else "hardly reads its instruction"

    def _tests(self) -> str:
        parts = []
        if (test := self.against_originals) is not None:
            parts.append(f"paired with their {TaskKind.ORIGINAL}s: {p_text(test)}")
        if (test := self.against_blind) is not None:
            blind = percent(test.rate_a)
            parts.append(f"against blind, {blind} on the same {test.pairs} episodes: {p_text(test)}")
        return f" ({'; '.join(parts)})" if parts else ""

    def _instead(self) -> str:
        failures = self.extended.episodes - self.extended.successes
        if not failures:
            return f"it failed no {TaskKind.EXTENDED} episode"
        default = self.default_task
        return (
            f"{percent(default.successes / failures)} of its {TaskKind.EXTENDED}-task failures did the scene's "
            f"{TaskKind.ORIGINAL} task instead ({percent(default.rate)} {interval(default)} of its "
            f"{TaskKind.EXTENDED} episodes)"
        )

    @property
    def text(self) -> str:
        """The sentence."""
        original, extended = self.original, self.extended
        on_originals = (
            f"{percent(original.rate)} on {TaskKind.ORIGINAL} tasks"
            if original.episodes
            else f"no {TaskKind.ORIGINAL} tasks"
        )
        if not extended.episodes and self.switched:
            return self._switched_only(on_originals)
        if not extended.episodes:
            return (
                f"{self.label}: {on_originals} {interval(original)}; the run has no {TaskKind.EXTENDED} tasks, so it "
                "does not show whether the policy reads its instruction."
            )
        if self.same_goal_only:
            return (
                f"{self.label}: {on_originals} vs {percent(extended.rate)} {interval(extended)} on "
                f"{TaskKind.EXTENDED} tasks{self._tests()}; every {TaskKind.EXTENDED} task asks for its "
                f"{TaskKind.ORIGINAL}'s goal in other words, which a policy that ignores its instruction does as well, "
                "so these tasks cannot show whether it reads it."
            )
        if (verdict := self.verdict) is None:
            verdict = f"does no {TaskKind.ORIGINAL} task, so the gap cannot be measured" if original.episodes else ""
        head = f"{self.label} {verdict}" if verdict else self.label
        oracle = (
            "no oracle verdict covers them"
            if extended.oracle_rate is None
            else f"the oracle reaches {percent(extended.oracle_rate)} on them"
        )
        were = "episode was a gap" if self.gaps == 1 else "episodes were gaps"
        gaps = f"; {self.gaps} {were}, left out" if self.gaps else ""
        return (
            f"{head}: {on_originals} vs {percent(extended.rate)} {interval(extended)} on {self._which()}"
            f"{self._tests()}; {oracle}; {self._instead()}{gaps}{self._left_out()}."
        )

    def _switched_only(self, on_originals: str) -> str:
        """The sentence of a run whose extended tasks ran only under a switch: what it did after each K."""
        original = self.original
        head = (
            f"{on_originals} {interval(original)}"
            if original.episodes
            else f"no episode under the {Condition.GIVEN} instruction"
        )
        return (
            f"{self.label}: {head}; its {TaskKind.EXTENDED} tasks ran only under a switch (another task's "
            f"instruction first, their own from policy step K): {'; '.join(s.text for s in self.switched)} (a "
            "policy that reads its instruction does the task switched to; one that ignores it goes on with the first)."
        )

    def _which(self) -> str:
        return (
            f"{TaskKind.EXTENDED} tasks that ask for another goal"
            if self.reworded_left_out
            else f"{TaskKind.EXTENDED} tasks"
        )

    def _left_out(self) -> str:
        if not self.reworded_left_out:
            return ""
        these = "task that rewords" if self.reworded_left_out == 1 else "tasks that reword"
        return (
            f"; {self.reworded_left_out} {these} the {TaskKind.ORIGINAL}'s goal left out (a policy that ignores its "
            "instruction does them as well)"
        )

    # The JSON report's answer (`langgap.report.data.to_data`): the sentence, its verdict and what they rest on.
    DATA: ClassVar[Spec] = (
        "text",
        "verdict",
        ("default_task_rate", lambda a: a.default_task.rate if a.default_task.episodes else None),
        "against_originals",
        "against_blind",
    )
