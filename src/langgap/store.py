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
from dataclasses import astuple
from pathlib import Path

from langgap.errors import LangGapError, ParameterError
from langgap.records import (
    COLUMNS,
    KEY_COLUMNS,
    LEGACY_COLUMNS,
    EpisodeKey,
    EpisodeRecord,
    Status,
    record_dict,
    upgraded,
)

# 2: the run's spec is stored whole (meta `spec`, `execution`), episodes say whether the policy was privileged.
# 3: that one `privileged` column is two, `sees_state` and `sees_goal` (`records.upgraded` reads schema 2's).
# 4: the `instructions` timeline (every instruction sent and the step it took effect; older rows: the first only).
SCHEMA_VERSION = 4
READABLE_SCHEMAS = (1, 2, 3, 4)
DB_NAME = "episodes.sqlite"
LOCK_NAME = ".writer.lock"
# Meta key of where the run stands: `{"planned": N, "stopped": None or why its last call ended early}`,
# written by each `evaluate` call (a report says how many planned episodes are stored, and why the rest are not).
PROGRESS = "progress"


def _schema() -> str:
    """The store's DDL, derived from `EpisodeRecord` (one column per field, the episode key as primary key)."""
    columns = ",\n    ".join(c.ddl() for c in COLUMNS)
    return (
        "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);\n"
        f"CREATE TABLE IF NOT EXISTS episodes (\n    {columns},\n    PRIMARY KEY ({', '.join(KEY_COLUMNS)})\n);\n"
    )


class StoreError(LangGapError):
    """The run store is missing, corrupt, or belongs to another run configuration."""


class StoreParameterError(StoreError, ParameterError):
    """The run directory asked for cannot be written as asked; named as `evaluate`'s caller passed it (`run`,
    `resume`)."""


def _to_row(record: EpisodeRecord) -> tuple:
    data = record_dict(record)
    return tuple(json.dumps(data[c.name], sort_keys=True) if c.json else data[c.name] for c in COLUMNS)


def _from_row(row: sqlite3.Row, present: set[str]) -> EpisodeRecord:
    """A record from a row; columns an older schema lacks keep the record's defaults."""
    data = {}
    for column in COLUMNS:
        if column.name not in present:
            continue
        value = row[column.name]
        if column.json:
            value = json.loads(value)
        elif column.kind is bool:
            value = bool(value)
        data[column.name] = value
    data.update(upgraded({name: row[name] for name in LEGACY_COLUMNS if name in present}))
    return EpisodeRecord(**data)


def _remove_database(path: Path) -> None:
    """Delete an SQLite database and the journal files beside it."""
    for file in (path, path.with_name(f"{path.name}-wal"), path.with_name(f"{path.name}-shm")):
        file.unlink(missing_ok=True)


def _lock_for_writing(directory: Path) -> int:
    """Take the run's writer lock (non-blocking); returns its file descriptor, closed to release it."""
    fd = os.open(directory / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise StoreParameterError(
            "run {directory} is being written by another process (pid {holder}); wait for it, or choose another {run}",
            directory=directory,
            holder=holder,
        ) from None
    os.ftruncate(fd, 0)
    os.pwrite(fd, str(os.getpid()).encode(), 0)
    return fd


class RunStore:
    """A run directory holding `episodes.sqlite` (and videos). Use `create` or `open`."""

    def __init__(
        self, directory: Path, connection: sqlite3.Connection, lock: int | None = None, schema: int = SCHEMA_VERSION
    ):
        self.directory = directory
        self.schema = schema
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
    def create(cls, directory: str | Path, meta: dict[str, dict]) -> RunStore:
        """Create a new run store; refuses to touch an existing one."""
        directory = Path(directory)
        path = cls.path_of(directory)
        if directory.exists() and not directory.is_dir():
            raise StoreParameterError("{run} {directory} is a file, not a directory", directory=directory)
        directory.mkdir(parents=True, exist_ok=True)
        with contextlib.ExitStack() as undo:
            lock = _lock_for_writing(directory)
            undo.callback(os.close, lock)
            # Checked under the lock: another process may be creating the same run.
            if path.exists():
                raise StoreParameterError(
                    "run {directory} already exists; pass {resume} to continue it, or choose a new {run}",
                    directory=directory,
                )
            # A create that fails part-way leaves no store behind (a retry would find one without its meta).
            undo.callback(_remove_database, path)
            db = cls._connect(path)
            undo.callback(db.close)
            with db:
                db.executescript(_schema())
                db.executemany(
                    "INSERT INTO meta (key, value) VALUES (?, ?)",
                    [("schema_version", str(SCHEMA_VERSION))]
                    + [(k, json.dumps(v, sort_keys=True)) for k, v in meta.items()],
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
            schema = int(version[0]) if version is not None and str(version[0]).isdigit() else None
            if schema not in READABLE_SCHEMAS:
                raise StoreError(f"{path}: unsupported run store schema {version[0] if version else 'none'}")
            if write and schema != SCHEMA_VERSION:
                raise StoreParameterError(
                    "{path} has run store schema {schema}, written by an older LangGap: reports read it, but it "
                    "cannot be resumed (this LangGap writes schema {current}); start a new {run}",
                    path=path,
                    schema=schema,
                    current=SCHEMA_VERSION,
                )
            undo.pop_all()
        return cls(directory, db, lock, schema)

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

    # -- what the run is -------------------------------------------------------------------------

    def meta(self, key: str) -> dict | None:
        """A JSON value stored with the run (`spec`, `execution`; `config` in schema-1 stores), or None."""
        row = self._db.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return None if row is None else json.loads(row[0])

    def set_meta(self, key: str, value: dict) -> None:
        with self._db:
            self._db.execute(
                "INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", (key, json.dumps(value, sort_keys=True))
            )

    # -- episodes --------------------------------------------------------------------------------

    def write(self, record: EpisodeRecord) -> None:
        """Insert or replace one episode's row, committed immediately."""
        names = ", ".join(c.name for c in COLUMNS)
        placeholders = ", ".join("?" for _ in COLUMNS)
        with self._db:
            self._db.execute(f"INSERT OR REPLACE INTO episodes ({names}) VALUES ({placeholders})", _to_row(record))

    def attach_video(self, key: EpisodeKey, video: str) -> None:
        """Record the clip of a stored episode (a path relative to the run directory); nothing else changes."""
        where = " AND ".join(f"{c} = ?" for c in KEY_COLUMNS)
        with self._db:
            self._db.execute(f"UPDATE episodes SET video = ? WHERE {where}", (video, *astuple(key)))

    def done_keys(self) -> set[EpisodeKey]:
        """The keys of the judged episodes (a resume re-runs everything else)."""
        rows = self._db.execute(f"SELECT {', '.join(KEY_COLUMNS)} FROM episodes WHERE status = ?", (str(Status.DONE),))
        return {EpisodeKey(*row) for row in rows}

    def records(self) -> list[EpisodeRecord]:
        """Every stored episode, in key order."""
        present = {row[1] for row in self._db.execute("PRAGMA table_info(episodes)")}
        rows = self._db.execute("SELECT * FROM episodes ORDER BY task_id, condition, init_index, seed")
        return [_from_row(r, present) for r in rows]
