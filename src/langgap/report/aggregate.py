"""Pure aggregation over stored episode records: rates with Wilson intervals, diagnoses, paired tests.

Gaps (infrastructure failures) never count as policy failures: every rate is over `done` episodes,
and every row carries the number of gaps it left out.
"""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

from langgap.records import EpisodeRecord

DIMENSION_ORDER = ("change_object", "change_target", "spatial_description", "drawer_action")
DIMENSION_LABEL = {
    "original": "Original",
    "change_object": "Change Object",
    "change_target": "Change Target",
    "spatial_description": "Spatial Description",
    "drawer_action": "Drawer Action",
}
SUITE_ORDER = ("libero_spatial", "libero_goal", "libero_object", "libero_10")
SUITE_LABEL = {"libero_spatial": "Spatial", "libero_goal": "Goal", "libero_object": "Object", "libero_10": "Libero-10"}


def wilson(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score 95 % interval for a binomial proportion (0, 0 for n = 0)."""
    if n == 0:
        return 0.0, 0.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """Two-sided exact McNemar p-value from the two discordant counts (binomial test at 1/2)."""
    n = only_a + only_b
    if n == 0:
        return 1.0
    k = min(only_a, only_b)
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2**n
    return min(1.0, 2 * tail)


@dataclass
class Rate:
    """One row of a table: a group of episodes and its success rate."""

    group: str
    episodes: int
    successes: int
    rate: float
    ci_low: float
    ci_high: float
    gaps: int
    tasks: int = 0

    def as_dict(self) -> dict:
        return asdict(self)


def rate(group: str, records: Iterable[EpisodeRecord]) -> Rate:
    records = list(records)
    done = [r for r in records if r.status == "done"]
    successes = sum(r.success for r in done)
    low, high = wilson(successes, len(done))
    return Rate(
        group=group,
        episodes=len(done),
        successes=successes,
        rate=successes / len(done) if done else 0.0,
        ci_low=low,
        ci_high=high,
        gaps=len(records) - len(done),
        tasks=len({r.task_id for r in records}),
    )


def rates_by(records: Iterable[EpisodeRecord], key: Callable[[EpisodeRecord], str | None], order=()) -> list[Rate]:
    """One `Rate` per value of `key` (records with key None are left out), in `order` first, then sorted."""
    groups: dict[str, list[EpisodeRecord]] = defaultdict(list)
    for record in records:
        name = key(record)
        if name is not None:
            groups[name].append(record)
    names = [n for n in order if n in groups] + sorted(n for n in groups if n not in order)
    return [rate(n, groups[n]) for n in names]


def given(records: Iterable[EpisodeRecord]) -> list[EpisodeRecord]:
    """The episodes run with the task's own instruction (the benchmark's numbers)."""
    return [r for r in records if r.condition == "given"]


def by_source(records: list[EpisodeRecord]) -> list[Rate]:
    """Table II, top: original vs extended vs total."""
    records = given(records)
    return [
        rate("Original (LIBERO)", (r for r in records if r.kind == "original")),
        rate("Extended (LangGap)", (r for r in records if r.kind == "extended")),
        rate("Total", records),
    ]


def by_dimension(records: list[EpisodeRecord]) -> list[Rate]:
    """Table II bottom / Table VII: extended tasks per perturbation dimension."""
    return rates_by(given(records), lambda r: r.dimension if r.kind == "extended" else None, DIMENSION_ORDER)


def by_suite_and_kind(records: list[EpisodeRecord]) -> list[Rate]:
    """Table VI: each suite's original and extended tasks."""
    return rates_by(
        given(records),
        lambda r: f"{r.suite}/{r.kind}",
        [f"{s}/{k}" for s in SUITE_ORDER for k in ("original", "extended")],
    )


def by_split(records: list[EpisodeRecord]) -> list[Rate]:
    """Training vs held-out extended tasks (and the originals)."""
    return rates_by(given(records), lambda r: r.split, ("original", "train", "heldout"))


def by_task(records: list[EpisodeRecord]) -> list[Rate]:
    return rates_by(given(records), lambda r: r.task_id)


@dataclass
class OutcomeRow:
    """What the policy did instead, for one group of extended-task episodes."""

    group: str
    episodes: int
    success: float
    did_source_task: float
    did_other_task: float
    no_goal_reached: float
    policy_error: float
    gaps: int

    def as_dict(self) -> dict:
        return asdict(self)


def outcomes_by_dimension(records: list[EpisodeRecord]) -> list[OutcomeRow]:
    """Per dimension: the share of episodes by outcome. `did_source_task` is the default-task rate."""
    rows = []
    extended = [r for r in given(records) if r.kind == "extended"]
    groups = [(DIMENSION_LABEL[d], [r for r in extended if r.dimension == d]) for d in DIMENSION_ORDER]
    groups.append(("All extended", extended))
    originals = [r for r in given(records) if r.kind == "original"]
    if originals:
        groups.append(("Original", originals))
    for name, group in groups:
        done = [r for r in group if r.status == "done"]
        if not group:
            continue
        counts = Counter(r.outcome for r in done)
        share = {
            k: counts[k] / len(done) if done else 0.0
            for k in ("success", "did_source_task", "did_other_task", "no_goal_reached", "policy_error")
        }
        rows.append(OutcomeRow(group=name, episodes=len(done), gaps=len(group) - len(done), **share))
    return rows


def achieved(record: EpisodeRecord) -> str:
    """The task an episode accomplished: its own, else the scene task whose goal became true first, else none."""
    if record.success:
        return record.task_id
    if record.reached:
        return min(record.reached.items(), key=lambda kv: (kv[1], kv[0]))[0]
    return "none"


def confusion(records: list[EpisodeRecord]) -> dict[str, dict[str, dict[str, int]]]:
    """Per scene: intended task -> achieved task -> episode count (done episodes, given instruction)."""
    matrices: dict[str, dict[str, Counter]] = defaultdict(lambda: defaultdict(Counter))
    for record in given(records):
        if record.status == "done":
            matrices[record.scene][record.task_id][achieved(record)] += 1
    return {scene: {task: dict(row) for task, row in rows.items()} for scene, rows in matrices.items()}


@dataclass
class PairedTest:
    """Two sets of episodes matched one to one (same task, init state, seed), compared with McNemar."""

    name: str
    pairs: int
    rate_a: float
    rate_b: float
    only_a: int
    only_b: int
    p_value: float
    changed_behaviour: float  # share of pairs whose achieved task differs

    def as_dict(self) -> dict:
        return asdict(self)


def paired(name: str, a: dict[tuple, EpisodeRecord], b: dict[tuple, EpisodeRecord]) -> PairedTest | None:
    keys = [k for k in a if k in b and a[k].status == "done" and b[k].status == "done"]
    if not keys:
        return None
    only_a = sum(a[k].success and not b[k].success for k in keys)
    only_b = sum(b[k].success and not a[k].success for k in keys)
    changed = sum(achieved(a[k]) != achieved(b[k]) for k in keys)
    return PairedTest(
        name=name,
        pairs=len(keys),
        rate_a=sum(a[k].success for k in keys) / len(keys),
        rate_b=sum(b[k].success for k in keys) / len(keys),
        only_a=only_a,
        only_b=only_b,
        p_value=mcnemar_exact(only_a, only_b),
        changed_behaviour=changed / len(keys),
    )


def condition_tests(records: list[EpisodeRecord]) -> list[PairedTest]:
    """Each language condition against `given`, episode by episode: a policy that reads language changes."""
    by_condition: dict[str, dict[tuple, EpisodeRecord]] = defaultdict(dict)
    for r in records:
        by_condition[r.condition][(r.task_id, r.init_index, r.seed)] = r
    tests = []
    for condition in sorted(c for c in by_condition if c != "given"):
        test = paired(f"given vs {condition}", by_condition["given"], by_condition[condition])
        if test is not None:
            tests.append(test)
    return tests


def run_comparison(name_a: str, a: list[EpisodeRecord], name_b: str, b: list[EpisodeRecord]) -> PairedTest | None:
    """Two runs on matched episodes (same task, init state, seed, condition)."""

    def keyed(records):
        return {(r.task_id, r.init_index, r.seed, r.condition): r for r in records}

    return paired(f"{name_a} vs {name_b}", keyed(a), keyed(b))
