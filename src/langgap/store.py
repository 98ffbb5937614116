"""The run store: one SQLite database (WAL) per run, one row per planned episode.

A row is written once per episode, in its own transaction, as soon as the episode ends, so killing a
run at any moment loses at most the episodes in flight. A row is either `done` (the policy was
evaluated: success or a policy failure) or a `gap` (infrastructure failed after bounded retries; no
verdict on the policy). `--resume` skips `done` rows and re-runs everything else.

One process writes a run at a time: a writer holds an exclusive lock on `DIR/.writer.lock` (released
by the kernel when the process dies, so a killed run never leaves a stale lock). Readers (reports)
take no lock.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import sqlite3
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

from langgap.engine.plan import EpisodeKey
from langgap.errors import LangGapError

SCHEMA_VERSION = 1
DB_NAME = "episodes.sqlite"
LOCK_NAME = ".writer.lock"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS episodes (
    task_id TEXT NOT NULL, init_index INTEGER NOT NULL, seed INTEGER NOT NULL, condition TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('done', 'gap')),
    success INTEGER NOT NULL, outcome TEXT NOT NULL, failure_kind TEXT, error TEXT,
    steps INTEGER NOT NULL, policy_calls INTEGER NOT NULL,
    instruction TEXT NOT NULL, instruction_sha256 TEXT NOT NULL, t0_hash TEXT NOT NULL,
    reached TEXT NOT NULL, goals_at_start TEXT NOT NULL, goals_at_end TEXT NOT NULL,
    catalog TEXT NOT NULL, suite TEXT NOT NULL, kind TEXT NOT NULL, dimension TEXT NOT NULL, split TEXT NOT NULL,
    source TEXT NOT NULL, scene TEXT NOT NULL, max_steps INTEGER NOT NULL,
    policy TEXT NOT NULL, policy_config_hash TEXT NOT NULL, physics TEXT NOT NULL, code_version TEXT NOT NULL,
    attempts INTEGER NOT NULL, wall_time_s REAL NOT NULL, worker INTEGER NOT NULL, finished_at TEXT NOT NULL,
    video TEXT,
    PRIMARY KEY (task_id, init_index, seed, condition)
);
"""


class StoreError(LangGapError):
    """The run store is missing, corrupt, or belongs to another run configuration."""


@dataclass
class EpisodeRecord:
    """Everything needed to trust one episode's result."""

    task_id: str
    init_index: int
    seed: int
    condition: str
    status: str  # done | gap
    success: bool
    outcome: str  # success | did_source_task | did_other_task | no_goal_reached | policy_error | gap
    failure_kind: str | None  # None | policy | infra
    error: str | None
    steps: int
    policy_calls: int
    instruction: str
    instruction_sha256: str
    t0_hash: str
    reached: dict[str, int] = field(default_factory=dict)  # scene task id -> first step its goal held
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
    policy: str = ""
    policy_config_hash: str = ""
    physics: dict = field(default_factory=dict)
    code_version: str = ""
    attempts: int = 1
    wall_time_s: float = 0.0
    worker: int = 0
    finished_at: str = ""
    video: str | None = None

    @property
    def key(self) -> EpisodeKey:
        return EpisodeKey(self.task_id, self.init_index, self.seed, self.condition)


_JSON_FIELDS = {"reached", "goals_at_start", "goals_at_end", "physics"}
_COLUMNS = [f.name for f in fields(EpisodeRecord)]


def _to_row(record: EpisodeRecord) -> tuple:
    data = asdict(record)
    return tuple(json.dumps(data[c], sort_keys=True) if c in _JSON_FIELDS else data[c] for c in _COLUMNS)


def _from_row(row: sqlite3.Row) -> EpisodeRecord:
    data = {c: (json.loads(row[c]) if c in _JSON_FIELDS else row[c]) for c in _COLUMNS}
    data["success"] = bool(data["success"])
    return EpisodeRecord(**data)


def _lock_for_writing(directory: Path) -> int:
    """Take the run's writer lock (non-blocking); returns its file descriptor, closed to release it."""
    fd = os.open(directory / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise StoreError(
            f"run {directory} is being written by another process (pid {holder}); wait for it, or choose another --run"
        ) from None
    os.ftruncate(fd, 0)
    os.pwrite(fd, str(os.getpid()).encode(), 0)
    return fd


class RunStore:
    """A run directory holding `episodes.sqlite` (and videos). Use `create` or `open`."""

    def __init__(self, directory: Path, connection: sqlite3.Connection, lock: int | None = None):
        self.directory = directory
        self._db = connection
        self._lock = lock  # the writer lock's file descriptor (None: opened for reading)

    # -- opening -------------------------------------------------------------------------------

    @staticmethod
    def path_of(directory: str | Path) -> Path:
        return Path(directory) / DB_NAME

    @classmethod
    def exists(cls, directory: str | Path) -> bool:
        return cls.path_of(directory).is_file()

    @classmethod
    def create(cls, directory: str | Path, config: dict) -> RunStore:
        """Create a new run store; refuses to touch an existing one."""
        directory = Path(directory)
        path = cls.path_of(directory)
        if directory.exists() and not directory.is_dir():
            raise StoreError(f"--run {directory} is a file, not a directory")
        directory.mkdir(parents=True, exist_ok=True)
        with contextlib.ExitStack() as undo:
            lock = _lock_for_writing(directory)
            undo.callback(os.close, lock)
            # Checked under the lock: another process may be creating the same run.
            if path.exists():
                raise StoreError(f"run {directory} already exists; pass --resume to continue it, or choose a new --run")
            db = cls._connect(path)
            undo.callback(db.close)
            with db:
                db.executescript(_SCHEMA)
                db.executemany(
                    "INSERT INTO meta (key, value) VALUES (?, ?)",
                    [("schema_version", str(SCHEMA_VERSION)), ("config", json.dumps(config, sort_keys=True))],
                )
            undo.pop_all()
        return cls(directory, db, lock)

    @classmethod
    def open(cls, directory: str | Path, *, write: bool = False) -> RunStore:
        """Open an existing run store; `write` (to append episodes) takes the run's writer lock."""
        directory = Path(directory)
        path = cls.path_of(directory)
        if not path.is_file():
            raise StoreError(f"no run store at {directory} (expected {path})")
        lock = None
        with contextlib.ExitStack() as undo:
            if write:
                lock = _lock_for_writing(directory)
                undo.callback(os.close, lock)
            db = cls._connect(path)
            undo.callback(db.close)
            try:
                version = db.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
                db.execute("SELECT count(*) FROM episodes").fetchone()
            except sqlite3.DatabaseError as exc:
                raise StoreError(f"{path} is not a LangGap run store ({exc})") from None
            if version is None or int(version[0]) != SCHEMA_VERSION:
                raise StoreError(f"{path}: unsupported store schema {version[0] if version else 'none'}")
            undo.pop_all()
        return cls(directory, db, lock)

    @staticmethod
    def _connect(path: Path) -> sqlite3.Connection:
        try:
            db = sqlite3.connect(path, timeout=30)
            db.row_factory = sqlite3.Row
            db.execute("PRAGMA journal_mode=WAL")
            db.execute("PRAGMA synchronous=NORMAL")
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{path} is not a LangGap run store ({exc})") from None
        return db

    def close(self) -> None:
        self._db.close()
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    def __enter__(self) -> RunStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- configuration ---------------------------------------------------------------------------

    @property
    def config(self) -> dict:
        return json.loads(self._db.execute("SELECT value FROM meta WHERE key = 'config'").fetchone()[0])

    def check_config(self, config: dict, identity_keys: Iterable[str]) -> None:
        """Refuse to resume with a configuration that would make the stored episodes incomparable."""
        stored = self.config
        differing = [k for k in identity_keys if stored.get(k) != config.get(k)]
        if differing:
            details = "; ".join(f"{k}: stored {stored.get(k)!r}, given {config.get(k)!r}" for k in differing)
            raise StoreError(f"run {self.directory} was made with another configuration ({details})")

    # -- episodes --------------------------------------------------------------------------------

    def write(self, record: EpisodeRecord) -> None:
        """Insert or replace one episode's row, committed immediately."""
        placeholders = ", ".join("?" for _ in _COLUMNS)
        with self._db:
            self._db.execute(
                f"INSERT OR REPLACE INTO episodes ({', '.join(_COLUMNS)}) VALUES ({placeholders})", _to_row(record)
            )

    def done_keys(self) -> set[EpisodeKey]:
        rows = self._db.execute("SELECT task_id, init_index, seed, condition FROM episodes WHERE status = 'done'")
        return {EpisodeKey(*row) for row in rows}

    def records(self) -> list[EpisodeRecord]:
        rows = self._db.execute("SELECT * FROM episodes ORDER BY task_id, condition, init_index, seed")
        return [_from_row(r) for r in rows]
