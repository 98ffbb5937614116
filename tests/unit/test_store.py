"""The run store on real SQLite: the schema follows the record, older stores stay readable."""

from __future__ import annotations

import json
import sqlite3
from dataclasses import fields

import pytest

from langgap.records import EpisodeKey, EpisodeRecord, Privilege, Status, _columns, privilege
from langgap.report.load import load_runs
from langgap.report.summary import results
from langgap.store import SCHEMA_VERSION, RunStore, StoreError
from langgap.vocabulary import Outcome

# The schema-1 layout (LangGap before the `privileged` column), as such stores exist on disk.
_SCHEMA_1 = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE episodes (
    task_id TEXT NOT NULL, init_index INTEGER NOT NULL, seed INTEGER NOT NULL, condition TEXT NOT NULL,
    status TEXT NOT NULL, success INTEGER NOT NULL, outcome TEXT NOT NULL, failure_kind TEXT, error TEXT,
    steps INTEGER NOT NULL, policy_calls INTEGER NOT NULL,
    instruction TEXT NOT NULL, instruction_sha256 TEXT NOT NULL, t0_hash TEXT NOT NULL,
    reached TEXT NOT NULL, goals_at_start TEXT NOT NULL, goals_at_end TEXT NOT NULL,
    catalog TEXT NOT NULL, suite TEXT NOT NULL, kind TEXT NOT NULL, dimension TEXT NOT NULL, split TEXT NOT NULL,
    source TEXT NOT NULL, scene TEXT NOT NULL, max_steps INTEGER NOT NULL,
    policy TEXT NOT NULL, policy_config_hash TEXT NOT NULL, physics TEXT NOT NULL, code_version TEXT NOT NULL,
    attempts INTEGER NOT NULL, wall_time_s REAL NOT NULL, worker INTEGER NOT NULL, finished_at TEXT NOT NULL,
    video TEXT, PRIMARY KEY (task_id, init_index, seed, condition)
);
"""


def record(task_id="spatial/s0/a", init_index=0, **changes) -> EpisodeRecord:
    base = dict(
        task_id=task_id,
        init_index=init_index,
        seed=init_index,
        condition="given",
        status=Status.DONE,
        success=False,
        outcome=Outcome.DID_SOURCE_TASK,
        failure_kind="policy",
        error=None,
        steps=10,
        policy_calls=10,
        instruction="put it there",
        instruction_sha256="0" * 64,
        t0_hash="1" * 64,
        reached={"spatial/s0/b": 7},
        kind="extended",
        sees_state=True,
        physics={"mujoco": "3.2.3"},
    )
    return EpisodeRecord(**{**base, **changes})


def test_a_record_round_trips_through_the_store(tmp_path):
    with RunStore.create(tmp_path / "run", {"spec": {"policy": "noop"}}) as store:
        store.write(record())
        store.write(record(init_index=1, status=Status.GAP, outcome=Outcome.GAP))
    with RunStore.open(tmp_path / "run") as store:
        assert store.records() == [record(), record(init_index=1, status=Status.GAP, outcome=Outcome.GAP)]
        assert store.done_keys() == {EpisodeKey("spatial/s0/a", 0, 0)}
        assert store.meta("spec") == {"policy": "noop"} and store.meta("missing") is None
    db = sqlite3.connect(tmp_path / "run" / "episodes.sqlite")
    columns = [row[1] for row in db.execute("PRAGMA table_info(episodes)")]
    assert columns == [f.name for f in fields(EpisodeRecord)]  # the table is the dataclass
    assert db.execute("SELECT value FROM meta WHERE key='schema_version'").fetchone() == (str(SCHEMA_VERSION),)


def _schema_1_store(directory, version="1"):
    directory.mkdir()
    db = sqlite3.connect(directory / "episodes.sqlite")
    db.executescript(_SCHEMA_1)
    db.execute("INSERT INTO meta VALUES ('schema_version', ?)", (version,))
    db.execute("INSERT INTO meta VALUES ('config', ?)", (json.dumps({"policy": "oracle"}),))
    old = record(sees_state=False)
    schema_1 = {row[1] for row in db.execute("PRAGMA table_info(episodes)")}
    row = {f.name: getattr(old, f.name) for f in fields(EpisodeRecord) if f.name in schema_1}
    for name in ("reached", "goals_at_start", "goals_at_end", "physics"):
        row[name] = json.dumps(row[name])
    db.execute(f"INSERT INTO episodes ({', '.join(row)}) VALUES ({', '.join('?' * len(row))})", list(row.values()))
    db.commit()
    db.close()


def test_done_keys_tell_conditions_apart(tmp_path):
    """Two judged episodes that differ only in their condition are two done keys (a resume skips both)."""
    with RunStore.create(tmp_path / "run", {}) as store:
        store.write(record(condition="given"))
        store.write(record(condition="empty"))
        store.write(record(init_index=1, condition="empty", status=Status.GAP))
        assert store.done_keys() == {
            EpisodeKey("spatial/s0/a", 0, 0, "given"),
            EpisodeKey("spatial/s0/a", 0, 0, "empty"),
        }


def test_done_keys_tell_seeds_apart(tmp_path):
    """Two judged episodes that differ only in their seed (`--repeats`) are two done keys, each with its seed."""
    with RunStore.create(tmp_path / "run", {}) as store:
        store.write(record(seed=0))
        store.write(record(seed=1000))
        assert store.done_keys() == {
            EpisodeKey("spatial/s0/a", 0, 0, "given"),
            EpisodeKey("spatial/s0/a", 0, 1000, "given"),
        }


def test_a_schema_1_store_opens_for_reading_and_refuses_writing_in_one_line(tmp_path):
    _schema_1_store(tmp_path / "old")
    with RunStore.open(tmp_path / "old") as store:
        (old,) = store.records()
        assert old == record(sees_state=False)  # the missing columns take the record's defaults
        assert store.meta("config") == {"policy": "oracle"}
    with pytest.raises(StoreError) as info:
        RunStore.open(tmp_path / "old", write=True)
    message = str(info.value)
    assert "schema 1" in message and "\n" not in message


def test_an_unknown_schema_is_a_one_line_error(tmp_path):
    _schema_1_store(tmp_path / "future", version="99")
    with pytest.raises(StoreError, match="unsupported run store schema 99"):
        RunStore.open(tmp_path / "future")


# The schema-2 layout: schema 1's, with the one `privileged` column (split into `sees_state` and `sees_goal`).
_SCHEMA_2 = _SCHEMA_1.replace("video TEXT,", "privileged INTEGER NOT NULL, video TEXT,")


@pytest.mark.parametrize("privileged", [True, False])
def test_a_schema_2_store_reads_its_privileged_flag_as_both_privileges(tmp_path, privileged):
    directory = tmp_path / "old"
    directory.mkdir()
    db = sqlite3.connect(directory / "episodes.sqlite")
    db.executescript(_SCHEMA_2)
    db.execute("INSERT INTO meta VALUES ('schema_version', '2')")
    db.execute("INSERT INTO meta VALUES ('spec', ?)", (json.dumps({"policy": "oracle", "seed": 0}),))
    old = record()
    schema_2 = {row[1] for row in db.execute("PRAGMA table_info(episodes)")}
    row = {f.name: getattr(old, f.name) for f in fields(EpisodeRecord) if f.name in schema_2}
    row.update({name: json.dumps(row[name]) for name in ("reached", "goals_at_start", "goals_at_end", "physics")})
    row["privileged"] = int(privileged)
    db.execute(f"INSERT INTO episodes ({', '.join(row)}) VALUES ({', '.join('?' * len(row))})", list(row.values()))
    db.commit()
    db.close()
    with RunStore.open(directory) as store:
        (read,) = store.records()
    # Such a policy was told the goal and shown the simulator state: it reads as a scripted reference.
    assert read == record(sees_state=privileged, sees_goal=privileged)
    assert privilege([read]) == (Privilege.GOAL if privileged else Privilege.NONE)
    (shown,) = load_runs([directory])  # and it still reports
    assert results(shown).label == ("old (oracle) †" if privileged else "old (oracle)")


def test_a_schema_3_store_reads_each_episode_s_one_instruction_as_its_timeline(tmp_path):
    with RunStore.create(tmp_path / "old", {}) as store:
        store.write(record())
    db = sqlite3.connect(tmp_path / "old" / "episodes.sqlite")
    db.execute("ALTER TABLE episodes DROP COLUMN instructions")  # the schema-3 layout: no timeline
    db.execute("UPDATE meta SET value = '3' WHERE key = 'schema_version'")
    db.commit()
    db.close()
    with RunStore.open(tmp_path / "old") as store:
        (old,) = store.records()
    assert old.instructions == [] and old.timeline == [(0, "put it there")]
    with pytest.raises(StoreError, match="schema 3"):
        RunStore.open(tmp_path / "old", write=True)


def test_a_switch_s_timeline_round_trips(tmp_path):
    switched = record(condition="switch:20", instructions=[[0, "put it there"], [20, "put it here"]])
    with RunStore.create(tmp_path / "run", {}) as store:
        store.write(switched)
    with RunStore.open(tmp_path / "run") as store:
        (stored,) = store.records()
    assert stored == switched and stored.timeline == [(0, "put it there"), (20, "put it here")]


def test_a_clip_is_attached_to_its_own_episode_only(tmp_path):
    assert not RunStore.exists(tmp_path / "run")
    with RunStore.create(tmp_path / "run", {}) as store:
        store.write(record())
        store.write(record(init_index=1))
        store.attach_video(EpisodeKey("spatial/s0/a", 1, 1), "videos/a-1.mp4")
        assert [r.video for r in store.records()] == [None, "videos/a-1.mp4"]
    assert RunStore.exists(tmp_path / "run")


def test_the_table_columns_are_derived_from_the_records_fields():
    """`_columns` runs once, at import, into `COLUMNS`; it is called here so its derivation is what is checked."""
    columns = {c.name: (c.kind, c.nullable) for c in _columns()}
    assert list(columns) == [f.name for f in fields(EpisodeRecord)]
    assert columns["task_id"] == (str, False) and columns["init_index"] == (int, False)
    assert columns["success"] == (bool, False) and columns["wall_time_s"] == (float, False)
    assert columns["failure_kind"] == (str, True) and columns["video"] == (str, True)
    assert columns["reached"] == (dict, False) and columns["instructions"] == (list, False)
    assert columns["cameras"] == (list, False) and columns["physics"] == (dict, False)


def test_a_store_that_cannot_be_opened_says_why_in_one_line(tmp_path):
    missing = tmp_path / "none"
    with pytest.raises(StoreError) as info:
        RunStore.open(missing)
    assert str(info.value) == f"no run store at {missing} (expected {missing / 'episodes.sqlite'})"
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "episodes.sqlite").write_text("not a database, just text" * 100)
    with pytest.raises(StoreError) as info:
        RunStore.open(tmp_path / "bad")
    assert (
        str(info.value) == f"{tmp_path / 'bad' / 'episodes.sqlite'} is not a LangGap run store (file is not a database)"
    )
    _schema_1_store(tmp_path / "old")
    with pytest.raises(StoreError) as info:
        RunStore.open(tmp_path / "old", write=True)
    assert str(info.value) == (
        f"{tmp_path / 'old' / 'episodes.sqlite'} has run store schema 1, written by an older LangGap: reports read "
        f"it, but it cannot be resumed (this LangGap writes schema {SCHEMA_VERSION}); start a new run"
    )


@pytest.mark.parametrize(("version", "shown"), [("abc", "abc"), (None, "none")])
def test_a_schema_version_that_is_no_number_or_missing_is_unsupported(tmp_path, version, shown):
    _schema_1_store(tmp_path / "odd", version=version or "1")
    db = sqlite3.connect(tmp_path / "odd" / "episodes.sqlite")
    with db:
        if version is None:
            db.execute("DELETE FROM meta WHERE key = 'schema_version'")
    db.close()
    with pytest.raises(StoreError) as info:
        RunStore.open(tmp_path / "odd")
    assert str(info.value) == f"{tmp_path / 'odd' / 'episodes.sqlite'}: unsupported run store schema {shown}"


def test_a_store_opens_with_its_directory_and_schema_and_is_created_in_an_empty_directory(tmp_path):
    (tmp_path / "run").mkdir()
    with RunStore.create(tmp_path / "run", {}) as store:  # an existing empty directory is fine
        assert (store.directory, store.schema) == (tmp_path / "run", SCHEMA_VERSION)
    with RunStore.open(tmp_path / "run") as store:
        assert (store.directory, store.schema) == (tmp_path / "run", SCHEMA_VERSION)
    _schema_1_store(tmp_path / "old")
    with RunStore.open(tmp_path / "old") as store:
        assert (store.directory, store.schema) == (tmp_path / "old", 1)
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError) as info:
        RunStore.create(tmp_path / "file", {})
    assert str(info.value) == f"run {tmp_path / 'file'} is a file, not a directory"


def test_creating_a_store_makes_its_parents_holds_the_writer_lock_and_refuses_an_existing_run(tmp_path):
    run = tmp_path / "runs" / "deep" / "run"
    with RunStore.create(run, {}), pytest.raises(StoreError, match="is being written by another process"):
        RunStore.open(run, write=True)
    with pytest.raises(StoreError) as info:
        RunStore.create(run, {})
    assert str(info.value).startswith(f"run {run} already exists")
    with RunStore.open(run, write=True) as store:  # the refused create let its lock go
        store.write(record())


def test_a_sqlite_file_of_something_else_is_not_a_run_store(tmp_path):
    (tmp_path / "other").mkdir()
    db = sqlite3.connect(tmp_path / "other" / "episodes.sqlite")
    db.execute("CREATE TABLE notes (text TEXT)")
    db.close()
    with pytest.raises(StoreError) as info:
        RunStore.open(tmp_path / "other")
    path = tmp_path / "other" / "episodes.sqlite"
    assert str(info.value) == f"{path} is not a LangGap run store (no such table: meta)"
