"""Which episodes a run films, and attaching clips made by replaying judged episodes.

`--video first:N` films the first N planned episodes while they run. `--video per-outcome:N` films up
to N episodes of every task, condition and outcome, so every `did_source_task` case can be watched:
outcomes are only known once episodes are judged, so the chosen episodes are run again with the
cameras on (same task, init state, seed and instruction), and a clip is attached only when the replay
ends exactly as the stored episode did.
"""

from __future__ import annotations

import re
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass

from langgap.errors import ParameterError
from langgap.records import EpisodeKey, EpisodeRecord

# Clips live in this folder of the run directory; records hold paths relative to the run directory.
VIDEO_DIR = "videos"
MODES = ("first", "per-outcome")
DEFAULT_VIDEO = "first:10"
VIDEO_HELP = (
    "film episodes (agentview | wrist, WebM): first:N films the first N planned episodes as they run; "
    "per-outcome:N films up to N episodes per task, condition and outcome by replaying them once judged; "
    f"a bare N means first:N (default: {DEFAULT_VIDEO})"
)


def clip_name(key: EpisodeKey) -> str:
    """The file name (without suffix) of an episode's clip: safe in paths and URLs."""
    return f"{key.task_id.replace('/', '__')}__init{key.init_index}__seed{key.seed}__{key.condition}"


@dataclass(frozen=True)
class VideoSelection:
    """Which episodes to film: `mode` in `MODES` and a count (0: film nothing)."""

    mode: str = "first"
    count: int = 0

    @classmethod
    def parse(cls, text: str) -> VideoSelection:
        """`first:N`, `per-outcome:N` or `N` (first N); '' films nothing."""
        if not text:
            return cls()
        match = re.fullmatch(r"(?:(?P<mode>[a-z-]+):)?(?P<count>-?\d+)", text.strip())
        if match is None or (match["mode"] or "first") not in MODES:
            raise ParameterError("{video} takes first:N, per-outcome:N or N, got {got!r}", got=text)
        selection = cls(match["mode"] or "first", int(match["count"]))
        if selection.count < 0:
            raise ParameterError("{video} must film at least 0 episodes, got {got!r}", got=text)
        return selection

    def __bool__(self) -> bool:
        return self.count > 0

    def __str__(self) -> str:
        return f"{self.mode}:{self.count}" if self else ""

    def filmed_while_running(self, plan: list[EpisodeKey]) -> set[EpisodeKey]:
        """The planned episodes to film as they run (`first:N`)."""
        return set(plan[: self.count]) if self.mode == "first" else set()

    def choose(self, plan: list[EpisodeKey], records: Iterable[EpisodeRecord]) -> list[EpisodeKey]:
        """The episodes that should have a clip, in plan order, among the judged `records`."""
        judged = {r.key: r for r in records if r.judged}
        if self.mode == "first":
            return [k for k in plan[: self.count] if k in judged]
        chosen, per_group = [], defaultdict(int)
        for key in plan:
            if (record := judged.get(key)) is None:
                continue
            group = (key.task_id, key.condition, str(record.outcome))
            if per_group[group] < self.count:
                per_group[group] += 1
                chosen.append(key)
        return chosen


def replay_matches(stored: EpisodeRecord, replay: EpisodeRecord) -> bool:
    """True when a filmed replay is the stored episode again (same verdict, outcome and length)."""
    return (
        replay.judged
        and replay.instruction == stored.instruction
        and replay.t0_hash == stored.t0_hash
        and (replay.success, str(replay.outcome), replay.reached, replay.steps)
        == (stored.success, str(stored.outcome), stored.reached, stored.steps)
    )
