"""Episode records and their enumerations: the bottom of LangGap's data flow.

Everything above (the engine that produces records, the store that keeps them, the reports that
read them) takes the record's shape and its key from here, and the names of its outcomes from
`langgap.vocabulary`, the only part of LangGap this module imports.
"""

from __future__ import annotations

import typing
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field, fields
from enum import StrEnum

from langgap.vocabulary import Condition, Outcome, TaskKind


class Status(StrEnum):
    """Whether the policy was judged: `done` (success or a policy failure) or `gap` (infrastructure failed)."""

    DONE = "done"
    GAP = "gap"


# The outcomes of judged episodes, in the order reports show them.
JUDGED_OUTCOMES = tuple(o for o in Outcome if o is not Outcome.GAP)


class Privilege(StrEnum):
    """What a policy was given beyond a policy under test, the most telling first (see `privilege`)."""

    GOAL = "goal"  # told the task id and goal (and shown the simulator state): a scripted reference
    STATE = "state"  # shown the simulator state only: a learned policy that reads it, still under test
    NONE = "none"


class FailureKind(StrEnum):
    """Who failed an unsuccessful episode."""

    POLICY = "policy"
    INFRA = "infra"


@dataclass(frozen=True, order=True)
class EpisodeKey:
    """The identity of one planned episode; the store's primary key."""

    task_id: str
    init_index: int
    seed: int
    condition: str = Condition.GIVEN.value

    def label(self) -> str:
        return f"{self.task_id}#{self.init_index}/seed{self.seed}/{self.condition}"


@dataclass
class EpisodeRecord:
    """Everything needed to trust one episode's result (one row of a run store).

    Attributes:
        task_id: The task's id.
        init_index: The init state the episode started from.
        seed: Its environment seed.
        condition: Its language condition (`given`, `empty`, `shuffled`, `source`, `nonsense`, `switch:K`).
        status: A `Status`: `done` (the policy was judged) or `gap` (infrastructure failed).
        success: The task's goal held.
        outcome: What the episode achieved: an `Outcome`.
        failure_kind: Who failed an unsuccessful episode: a `FailureKind`; None on success.
        error: Why a policy error or a gap ended it (None otherwise).
        steps: The policy steps taken (settling not counted).
        policy_calls: The calls to the policy's `act`.
        instruction: The first instruction sent.
        instruction_sha256: Its SHA-256.
        t0_hash: A hash of the simulator state at reset: the same in every sibling task of a scene for one init
            state and seed (empty for a gap).
        reached: Scene task id -> the first step its goal held.
        goals_at_start: The scene tasks whose goals already held after settling.
        goals_at_end: Those whose goals held when the episode ended.
        catalog: The task's catalog.
        suite: Its LIBERO suite.
        kind: Its kind (`original`, `extended`).
        dimension: Its dimension.
        split: Its split.
        source: Its source task's id.
        scene: A hash of the scene it is set in (`langgap.catalog.files.scene_key`).
        max_steps: Its step limit.
        settle_steps: Idle steps after reset, before the policy acts.
        policy: The policy's name.
        policy_config_hash: A short hash of the policy's configuration (`policy_config`; empty for a gap).
        sees_state: The policy's observations carried the simulator state.
        sees_goal: The policy was told the task id and goal (a scripted reference).
        cameras: The cameras the policy saw.
        image_size: Their size in pixels (0: no images).
        physics: The physics stack and conventions the episode ran on (`langgap.stack.physics_stack`).
        code_version: The LangGap code that ran it (`langgap.version.code_version`).
        attempts: The attempts it took.
        wall_time_s: Seconds it took.
        worker: The worker that ran it (-1: none, for a gap).
        finished_at: When it ended (UTC, ISO 8601).
        video: Its clip's path, relative to the run directory (None: not filmed).
        instructions: [policy step, instruction] for every instruction sent, from step 0 (schema 4; see
            `timeline`).
    """

    task_id: str
    init_index: int
    seed: int
    condition: str
    status: str
    success: bool
    outcome: str
    failure_kind: str | None
    error: str | None
    steps: int
    policy_calls: int
    instruction: str
    instruction_sha256: str
    t0_hash: str
    reached: dict[str, int] = field(default_factory=dict)
    goals_at_start: list[str] = field(default_factory=list)
    goals_at_end: list[str] = field(default_factory=list)
    catalog: str = ""
    suite: str = ""
    kind: str = ""
    dimension: str = ""
    split: str = ""
    source: str = ""
    scene: str = ""
    max_steps: int = 0
    settle_steps: int = 0
    policy: str = ""
    policy_config_hash: str = ""
    sees_state: bool = False
    sees_goal: bool = False
    cameras: list[str] = field(default_factory=list)
    image_size: int = 0
    physics: dict = field(default_factory=dict)
    code_version: str = ""
    attempts: int = 1
    wall_time_s: float = 0.0
    worker: int = 0
    finished_at: str = ""
    video: str | None = None
    instructions: list = field(default_factory=list)

    @property
    def key(self) -> EpisodeKey:
        return EpisodeKey(self.task_id, self.init_index, self.seed, self.condition)

    @property
    def timeline(self) -> list[tuple[int, str]]:
        """Every instruction the policy was sent, with the policy step it took effect (a store older than
        schema 4 kept only the first)."""
        return [(int(step), text) for step, text in self.instructions] or [(0, self.instruction)]

    @property
    def judged(self) -> bool:
        """True when the policy was evaluated (not a gap)."""
        return self.status == Status.DONE


def privilege(records: Iterable[EpisodeRecord]) -> Privilege:
    """The most telling privilege any of `records`' policies had (a run's, for its reports)."""
    records = list(records)
    if any(r.sees_goal for r in records):
        return Privilege.GOAL
    return Privilege.STATE if any(r.sees_state for r in records) else Privilege.NONE


def classify(
    task_id: str,
    kind: str,
    source: str,
    success: bool,
    reached: Mapping[str, int],
    *,
    wrong_order: bool = False,
    switched: tuple[str, int] | None = None,
) -> Outcome:
    """What an episode of task `task_id` achieved, from the scene goals that became true during it.

    `wrong_order`: the task's goal is ordered and its parts all held at some step, out of order. That
    is named before the source task, which an ordered task built on the source's goal also reaches.
    `switched`: (the task the first instruction asked for, the step the instruction became the task's own);
    reaching that first task's goal at or after the switch is `persisted`, named first of the failures.
    """
    if success:
        return Outcome.SUCCESS
    if switched is not None and reached.get(switched[0], -1) >= switched[1]:
        return Outcome.PERSISTED
    if wrong_order:
        return Outcome.WRONG_ORDER
    if kind == TaskKind.EXTENDED and source in reached:
        return Outcome.DID_SOURCE_TASK
    if any(name != task_id for name in reached):
        return Outcome.DID_OTHER_TASK
    return Outcome.NO_GOAL_REACHED


def achieved(record: EpisodeRecord) -> str:
    """The task an episode accomplished: its own, else the scene task whose goal became true first, else `none`.

    Goals reached at the same step go to a task beside the episode's own (the same id up to its last `/`), then
    by name: LIBERO-goal's scenes share one layout, so a goal reached there is every one of those scenes' task.
    """
    if record.success:
        return record.task_id
    if record.reached:
        home = record.task_id.rpartition("/")[0]
        return min(record.reached.items(), key=lambda kv: (kv[1], kv[0].rpartition("/")[0] != home, kv[0]))[0]
    return "none"


# -- the record as a table row ---------------------------------------------------------------------

KEY_COLUMNS = tuple(f.name for f in fields(EpisodeKey))
_SQL_TYPES = {str: "TEXT", int: "INTEGER", bool: "INTEGER", float: "REAL", dict: "TEXT", list: "TEXT"}


@dataclass(frozen=True)
class Column:
    """One field of `EpisodeRecord` as a table column."""

    name: str
    kind: type  # str, int, bool, float, dict or list (dict and list are stored as JSON text)
    nullable: bool

    @property
    def json(self) -> bool:
        return self.kind in (dict, list)

    def ddl(self) -> str:
        check = ""
        if self.name == "status":
            check = f" CHECK (status IN ({', '.join(repr(s.value) for s in Status)}))"
        return f"{self.name} {_SQL_TYPES[self.kind]}{'' if self.nullable else ' NOT NULL'}{check}"


def _columns() -> tuple[Column, ...]:
    hints = typing.get_type_hints(EpisodeRecord)
    columns = []
    for f in fields(EpisodeRecord):
        hint = hints[f.name]
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        nullable = type(None) in typing.get_args(hint)
        base = typing.get_origin(args[0] if nullable else hint) or (args[0] if nullable else hint)
        columns.append(Column(f.name, base, nullable))
    return tuple(columns)


COLUMNS = _columns()
# Columns of older stores that the record no longer has (see `upgraded`).
LEGACY_COLUMNS = ("privileged",)


def upgraded(legacy: Mapping[str, object]) -> dict:
    """Today's fields for the legacy columns of a stored row (`LEGACY_COLUMNS`, those the row has).

    `privileged` (schema 2) was one flag for two things: such a policy was both told the goal and
    shown the simulator state, so it maps to both (a small-bc run of then was handed the goal too).
    """
    if "privileged" not in legacy:
        return {}
    flag = bool(legacy["privileged"])
    return {"sees_state": flag, "sees_goal": flag}


def record_dict(record: EpisodeRecord) -> dict:
    """The record as plain data (enumerations as their string values)."""
    data = asdict(record)
    return {k: (str(v) if isinstance(v, StrEnum) else v) for k, v in data.items()}
