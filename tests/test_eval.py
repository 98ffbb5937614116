"""The evaluation harness: plan, store, workers, retries, gaps, resume after kill -9, bad input."""

from __future__ import annotations

import json
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from langgap.engine.evaluate import evaluate
from langgap.engine.plan import build_plan, condition_instruction, episode_seed
from langgap.engine.spec import ExecutionOptions, RunSpec, SpecError
from langgap.store import RunStore, StoreError
from langgap.video import FRAME_EVERY
from tests.support.harness import REPO, SHORT_STEPS, run_cli, store_rows


def _spec(short_catalog, policy="noop", episodes=2, **kw) -> RunSpec:
    return RunSpec.create(policy, catalog=short_catalog, episodes=episodes, **kw)


def _eval(short_catalog, run, policy="noop", episodes=2, workers=0, options=None, **kw):
    options = options or ExecutionOptions(workers=workers, progress=False)
    return evaluate(_spec(short_catalog, policy, episodes, **kw), run, options)


def test_episode_rows_carry_full_provenance(short_catalog, tmp_path):
    summary = _eval(short_catalog, tmp_path / "run", policy="tests.support.policies:ChunkPolicy")
    assert (summary.planned, summary.ran, summary.gaps) == (6, 6, 0)
    rows = store_rows(tmp_path / "run")
    assert len(rows) == 6
    row = rows[0]
    assert row["status"] == "done" and row["failure_kind"] == "policy" and row["outcome"] == "no_goal_reached"
    assert row["steps"] == SHORT_STEPS and row["policy_calls"] == SHORT_STEPS // 2 + SHORT_STEPS % 2
    assert row["instruction"] == "pick up the black bowl between the plate and the ramekin and place it on the plate"
    assert len(row["instruction_sha256"]) == 64 and len(row["t0_hash"]) == 64
    assert json.loads(row["physics"])["mujoco"] == "3.2.3"
    assert row["seed"] == episode_seed(0, row["init_index"])
    assert row["policy"] == "tests.support.policies:ChunkPolicy" and len(row["policy_config_hash"]) == 16
    assert row["code_version"].startswith("0.1.0")
    # Siblings start from the identical scene: same init index -> same t0 hash in every task.
    by_init = {}
    for r in rows:
        assert by_init.setdefault(r["init_index"], r["t0_hash"]) == r["t0_hash"]
    with RunStore.open(tmp_path / "run") as store:
        assert store.meta("spec") == _spec(short_catalog, "tests.support.policies:ChunkPolicy").to_dict()


def test_resume_skips_done_and_extend_grows_the_run(short_catalog, tmp_path):
    run = tmp_path / "run"
    _eval(short_catalog, run, episodes=1)
    options = ExecutionOptions(workers=0, progress=False)
    assert evaluate(_spec(short_catalog, episodes=1), run, options, resume=True).ran == 0
    with pytest.raises(SpecError, match="inits: stored") as info:
        evaluate(_spec(short_catalog, episodes=2), run, options, resume=True)
    # A Python caller reads the parameter's name; the CLI spells the flag (test_parameter_errors.py).
    assert "(extend grows a run's tasks, episodes or conditions)" in str(info.value) and "--" not in str(info.value)
    summary = evaluate(_spec(short_catalog, episodes=2), run, options, resume=True, extend=True)
    assert (summary.skipped, summary.ran) == (3, 3)
    assert len(store_rows(run)) == 6
    with RunStore.open(run) as store:
        assert store.meta("spec")["inits"] == [0, 1]
    # Growing never changes what the episodes are: another policy is refused even with --extend.
    with pytest.raises(SpecError, match="policy: stored 'noop', given 'random'"):
        evaluate(_spec(short_catalog, "random", episodes=2), run, options, resume=True, extend=True)


def test_a_resume_keeps_every_condition_s_stored_episodes(short_catalog, tmp_path):
    """A resume tells episodes apart by their condition too: grown from `given` to `given` + `empty` it runs
    only the `empty` episodes, and resumed again it neither re-runs nor overwrites any (the store's done keys
    and the plan's filter hold the condition)."""
    run = tmp_path / "run"
    one = dict(episodes=1, tasks="spatial/s0/black-bowl-1-on-plate")
    options = ExecutionOptions(workers=0, progress=False)
    _eval(short_catalog, run, **one)
    both = _spec(short_catalog, conditions=("given", "empty"), **one)
    grown = evaluate(both, run, options, resume=True, extend=True)
    assert (grown.planned, grown.skipped, grown.ran) == (2, 1, 1)
    stored = store_rows(run)
    assert sorted(r["condition"] for r in stored) == ["empty", "given"]
    again = evaluate(both, run, options, resume=True)
    assert (again.planned, again.skipped, again.ran) == (2, 2, 0)
    assert store_rows(run) == stored  # not one row rewritten (their wall times and finish times included)


def test_policy_output_errors_are_policy_failures(short_catalog, tmp_path):
    for name, message in (
        ("NanPolicy", "non-finite"),
        ("WrongShapePolicy", "shape"),
        # Refused, never cut: the policy, the declared and the received lengths.
        ("LongChunkPolicy", "LongChunkPolicy: policy returned a chunk of 3 actions; its spec declares chunk=2"),
    ):
        run = tmp_path / name
        _eval(short_catalog, run, policy=f"tests.support.policies:{name}", episodes=1)
        rows = store_rows(run)
        assert all(r["status"] == "done" and r["outcome"] == "policy_error" for r in rows)
        assert all(r["failure_kind"] == "policy" and message in r["error"] for r in rows)


def test_exceptions_are_retried_then_recorded_as_gaps(short_catalog, tmp_path):
    run = tmp_path / "raise"
    options = ExecutionOptions(workers=0, max_attempts=2, max_failure_streak=10, progress=False)
    summary = _eval(short_catalog, run, policy="tests.support.policies:RaisingPolicy", episodes=1, options=options)
    rows = store_rows(run)
    assert summary.gaps == 3
    assert all(r["status"] == "gap" and r["failure_kind"] == "infra" and r["attempts"] == 2 for r in rows)
    assert all("model exploded" in r["error"] for r in rows)


def test_a_flaky_policy_succeeds_on_retry_in_worker_processes(short_catalog, tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    spec = _spec(
        short_catalog, "tests.support.policies:FlakyPolicy", episodes=1, policy_args={"marker_dir": str(markers)}
    )
    # Every episode fails once with the same cause: without a higher streak limit that stops the run.
    options = ExecutionOptions(workers=2, max_failure_streak=10, progress=False)
    summary = evaluate(spec, tmp_path / "run", options)
    rows = store_rows(tmp_path / "run")
    assert summary.gaps == 0 and len(rows) == 3
    assert all(r["status"] == "done" and r["attempts"] == 2 for r in rows)


def test_hanging_and_crashing_workers_become_gaps_and_the_run_completes(short_catalog, tmp_path):
    hang = evaluate(
        _spec(short_catalog, "tests.support.policies:HangingPolicy", episodes=1, tasks="spatial/s0/open*"),
        tmp_path / "hang",
        ExecutionOptions(workers=1, timeout_s=8, max_attempts=2, progress=False),
    )
    rows = store_rows(tmp_path / "hang")
    assert hang.gaps == 1 and rows[0]["status"] == "gap" and "timed out" in rows[0]["error"]
    crash = evaluate(
        _spec(short_catalog, "tests.support.policies:CrashingPolicy", episodes=1),
        tmp_path / "crash",
        ExecutionOptions(workers=2, max_attempts=2, max_failure_streak=10, progress=False),
    )
    rows = store_rows(tmp_path / "crash")
    assert crash.gaps == 3 and all("worker process died (exit code 17)" in r["error"] for r in rows)


def test_kill_minus_nine_and_resume_loses_and_duplicates_nothing(short_catalog, tmp_path):
    args = [
        "eval",
        "--policy",
        "random",
        "--catalog",
        short_catalog,
        "--episodes",
        "4",
        "--workers",
        "2",
        "--no-progress",
        "--quiet",
    ]
    reference = tmp_path / "reference"
    assert run_cli(*args, "--run", str(reference)).returncode == 0
    run = tmp_path / "killed"
    rng = random.Random(1)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for _ in range(3):
        process = subprocess.Popen(
            [sys.executable, "-m", "langgap.cli.main", *args, "--run", str(run), "--resume"],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        time.sleep(rng.uniform(6, 14))
        process.send_signal(signal.SIGKILL)
        process.wait()
    assert run_cli(*args, "--run", str(run), "--resume").returncode == 0
    keep = ("task_id", "init_index", "seed", "success", "steps", "t0_hash", "reached", "goals_at_end")
    killed = [{k: r[k] for k in keep} for r in store_rows(run)]
    assert len(killed) == 12 and killed == [{k: r[k] for k in keep} for r in store_rows(reference)]
    time.sleep(1.5)
    orphans = subprocess.run(["pgrep", "-f", f"langgap-worker|{run}"], capture_output=True, text=True).stdout.split()
    assert not [p for p in orphans if int(p) != os.getpid()]


def test_conditions_send_the_planned_strings(catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    assert condition_instruction(task, catalog, "empty", "libero", 0) == ""
    assert condition_instruction(task, catalog, "source", "libero", 0) == catalog.get(task.source).instruction()
    mates = {t.instruction() for t in catalog.scene_mates(task)} - {task.instruction()}
    shuffled = {condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(20)}
    assert shuffled <= mates and len(shuffled) > 1
    assert shuffled == {condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(20)}
    plan = build_plan([task], catalog, episodes=2, conditions=("given", "empty"))
    assert [(p.key.condition, p.instruction) for p in plan][-1] == ("empty", "")


def _clip(run, row) -> tuple[int, int]:
    """A stored clip's frame count and width/height ratio, as a video decoder reads them."""
    import cv2

    path = run / row["video"]
    assert path.suffix == ".webm" and path.is_file()
    video = cv2.VideoCapture(str(path))
    frames = 0
    while video.read()[0]:
        frames += 1
    return frames, video.get(cv2.CAP_PROP_FRAME_WIDTH) / video.get(cv2.CAP_PROP_FRAME_HEIGHT)


def test_videos_of_the_first_episodes_are_written(short_catalog, tmp_path):
    options = ExecutionOptions(workers=0, video="first:1", progress=False)
    summary = _eval(short_catalog, tmp_path / "run", tasks="spatial/s0/black-bowl-1-on-plate", options=options)
    first, second = store_rows(tmp_path / "run")
    assert summary.filmed == 1 and second["video"] is None
    assert first["video"] == "videos/spatial__s0__black-bowl-1-on-plate__init0__seed0__given.webm"
    # One frame every FRAME_EVERY steps, both cameras side by side.
    assert _clip(tmp_path / "run", first) == (SHORT_STEPS // FRAME_EVERY, 2.0)


def test_per_outcome_videos_replay_the_chosen_episodes(short_catalog, tmp_path, capsys):
    # Init states 2 and 3 end in a policy error, 0 and 1 in no goal: one clip per outcome is of 0 and 2.
    policy, task = "tests.support.policies:ErrsOnInitsPolicy", "spatial/s0/black-bowl-1-on-plate"
    spec = _spec(short_catalog, policy, 4, tasks=task, policy_args={"inits": "2,3"})
    evaluate(spec, tmp_path / "run", ExecutionOptions(workers=0, progress=False))
    before = store_rows(tmp_path / "run")
    assert [r["outcome"] for r in before] == ["no_goal_reached"] * 2 + ["policy_error"] * 2
    # Filming a finished run: nothing runs again but the two replays, and only their clips are added; the
    # replays have a progress bar of their own.
    options = ExecutionOptions(workers=1, video="per-outcome:1", progress=True)
    summary = evaluate(spec, tmp_path / "run", options, resume=True)
    assert (summary.ran, summary.filmed, summary.film_mismatches) == (0, 2, 0)
    assert re.search(r"filming: 100%.*2/2 \[.*clip", capsys.readouterr().err)
    after = store_rows(tmp_path / "run")
    assert [r["video"] is not None for r in after] == [True, False, True, False]
    assert [{**r, "video": None} for r in after] == before
    assert _clip(tmp_path / "run", after[0])[0] == SHORT_STEPS // FRAME_EVERY
    assert _clip(tmp_path / "run", after[2])[0] == 4 // FRAME_EVERY  # the policy erred at its 5th action
    assert sorted(p.name for p in (tmp_path / "run" / "videos").iterdir()) == sorted(
        Path(r["video"]).name for r in after if r["video"]
    )


def test_a_replay_that_ends_otherwise_gets_no_clip(short_catalog, tmp_path):
    # The policy errs on init state 1 only the first time it runs it: its replay ends otherwise.
    policy_args = {"inits": "1", "once_dir": str(tmp_path)}
    spec = _spec(short_catalog, "tests.support.policies:ErrsOnInitsPolicy", 2, tasks="spatial/s0/black-bowl-1-on-plate",
                 policy_args=policy_args)  # fmt: skip
    options = ExecutionOptions(workers=0, video="per-outcome:1", progress=False)
    summary = evaluate(spec, tmp_path / "run", options)
    assert (summary.filmed, summary.film_mismatches) == (1, 1)
    rows = store_rows(tmp_path / "run")
    assert [r["outcome"] for r in rows] == ["no_goal_reached", "policy_error"]
    assert rows[1]["video"] is None and [p.name for p in (tmp_path / "run" / "videos").iterdir()] == [
        Path(rows[0]["video"]).name
    ]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--policy", "gpt-robot"], "unknown policy"),
        (["--policy", "random", "--policy-arg", "temperature=3"], "no argument 'temperature'"),
        (["--policy", "noop", "--tasks", "spatial/s0/levitate"], "unknown task"),
        (["--policy", "noop", "--episodes", "51"], "out of range"),
        (["--policy", "noop", "--policy-arg", "oops"], "key=value"),
        (["--policy", "noop", "--max-batch", "2"], "--max-batch only apply to a shared policy (--shared-policy)"),
        (["--policy", "noop", "--shared-policy", "--workers", "0"], "--shared-policy needs worker processes"),
        (["--policy", "noop", "--shared-policy", "--policy-gpus", "1"], "--policy-gpus needs --backend ray"),
        (
            ["--policy", "tests.support.policies:UnbuildablePolicy", "--shared-policy", "--workers", "2"],
            "the shared policy process could not start: FileNotFoundError: no checkpoint at /nowhere",
        ),
    ],
)
def test_bad_input_is_one_line_and_creates_nothing(tmp_path, extra, message):
    run = tmp_path / "run"
    result = run_cli("eval", "--run", str(run), *extra)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1 and message in result.stderr
    assert not run.exists()


def test_existing_foreign_or_corrupt_stores_are_never_overwritten(short_catalog, tmp_path):
    run = tmp_path / "run"
    _eval(short_catalog, run, episodes=1)
    db = run / "episodes.sqlite"
    before = db.read_bytes()
    base = ["eval", "--catalog", short_catalog, "--episodes", "1", "--run", str(run), "--no-progress"]
    for extra, message in (
        (["--policy", "noop"], "already exists"),
        (["--policy", "random", "--resume"], "another spec: policy: stored 'noop', given 'random'"),
        (["--policy", "noop", "--seed", "5", "--resume"], "another spec: seed: stored 0, given 5"),
        (["--policy", "noop", "--stepping", "fast", "--resume"], "another spec: physics: stored"),
    ):
        result = run_cli(*base, *extra)
        assert result.returncode == 2 and message in result.stderr and result.stderr.count("\n") == 1
    assert db.read_bytes() == before
    corrupt = tmp_path / "corrupt"
    corrupt.mkdir()
    (corrupt / "episodes.sqlite").write_bytes(b"this is not a database" * 100)
    result = run_cli("eval", "--policy", "noop", "--run", str(corrupt), "--resume", "--catalog", short_catalog)
    assert result.returncode == 2 and "not a LangGap run store" in result.stderr
    assert (corrupt / "episodes.sqlite").read_bytes() == b"this is not a database" * 100
    with pytest.raises(StoreError):
        RunStore.open(corrupt)


def test_one_writer_per_run(short_catalog, tmp_path):
    run = tmp_path / "run"
    _eval(short_catalog, run, episodes=1)
    before = (run / "episodes.sqlite").read_bytes()
    with RunStore.open(run, write=True):  # another process is appending to this run
        result = run_cli(
            "eval", "--policy", "noop", "--catalog", short_catalog, "--episodes", "2", "--run", str(run), "--resume"
        )
        assert result.returncode == 2 and result.stderr.count("\n") == 1
        assert f"being written by another process (pid {os.getpid()})" in result.stderr
        with pytest.raises(StoreError, match="being written"):
            RunStore.open(run, write=True)
        with RunStore.open(run) as reader:  # reports read while a run is written
            assert len(reader.done_keys()) == 3
    assert (run / "episodes.sqlite").read_bytes() == before
    # The lock goes with its holder: the run resumes afterwards.
    options = ExecutionOptions(workers=0, progress=False)
    assert evaluate(_spec(short_catalog, episodes=2), run, options, resume=True, extend=True).ran == 3


def test_report_formats(short_catalog, tmp_path):
    run = tmp_path / "run"
    _eval(short_catalog, run, episodes=2, conditions=("given", "empty"))
    other = tmp_path / "other"
    _eval(short_catalog, other, policy="random", episodes=2)
    result = run_cli("report", str(run), "--compare", str(other), "--format", "json")
    report = json.loads(result.stdout)
    for section in ("per_task", "per_dimension", "per_suite", "per_split"):
        for row in report[section]:
            assert {"id", "episodes", "successes", "rate", "ci_low", "ci_high", "gaps"} <= set(row)
    assert report["conditions"][0]["name"] == "given vs empty" and report["comparisons"][0]["pairs"] == 6
    markdown = run_cli("report", str(run), "--plots", str(tmp_path / "plots"), "--episodes", str(tmp_path / "ep.csv"))
    assert markdown.returncode == 0
    assert "(the paper's Table VII)" in markdown.stdout and "(the paper's Table VI)" in markdown.stdout
    assert (tmp_path / "plots" / "success_by_dimension.png").stat().st_size > 1000
    import csv

    rows = list(csv.DictReader((tmp_path / "ep.csv").open()))
    assert len(rows) == 12 and {r["condition"] for r in rows} == {"given", "empty"}
    assert r"\toprule" in run_cli("report", str(run), "--format", "latex").stdout
    assert run_cli("report", str(run), "--format", "csv").stdout.startswith("run,privilege,table,group")


def _cli_eval(short_catalog, run, policy, *extra):
    return run_cli(
        "eval",
        "--policy",
        policy,
        "--catalog",
        short_catalog,
        "--run",
        str(run),
        "--workers",
        "0",
        "--no-progress",
        "--quiet",
        *extra,
    )


def test_a_dead_policy_server_stops_the_run_and_resume_continues(short_catalog, tmp_path):
    run, switch = tmp_path / "run", tmp_path / "server-down"
    outage = ["tests.support.outage_policy:OutagePolicy", "--policy-arg", f"switch={switch}"]
    assert _cli_eval(short_catalog, run, *outage, "--episodes", "1").returncode == 0
    before = store_rows(run)
    switch.touch()
    stopped = _cli_eval(short_catalog, run, *outage, "--episodes", "3", "--resume", "--extend")
    assert stopped.returncode == 4, stopped.stderr
    assert (
        stopped.stderr.strip()
        .splitlines()[-1]
        .startswith("error: stopped after 3 episodes in a row failed with: ConnectionError: policy server unreachable")
    )
    assert store_rows(run) == before  # nothing stored was touched, no gap charged to the policy
    # The run records its plan and why it stopped, and its report says both.
    incomplete = "the run is incomplete: 3 of 9 planned episodes stored; it stopped early: stopped after 3 episodes"
    assert incomplete in run_cli("report", str(run), "--summary").stdout.split("\n\n")[1]
    switch.unlink()
    resumed = _cli_eval(short_catalog, run, *outage, "--episodes", "3", "--resume", "--extend")
    assert resumed.returncode == 0 and "3 already stored, 6 run" in resumed.stdout
    assert len(store_rows(run)) == 9 and all(r["status"] == "done" for r in store_rows(run))
    assert "planned episodes" not in run_cli("report", str(run)).stdout


def test_no_openpi_server_stops_the_run_with_its_address(short_catalog, tmp_path):
    start = time.monotonic()
    result = _cli_eval(
        short_catalog,
        tmp_path / "run",
        "openpi",
        "--policy-arg",
        "port=1",
        "--policy-arg",
        "connect_timeout=1",
        "--episodes",
        "2",
    )
    assert result.returncode == 4
    assert "no policy server at 127.0.0.1:1" in result.stderr.strip().splitlines()[-1]
    assert time.monotonic() - start < 60
    assert store_rows(tmp_path / "run") == []
    report = run_cli("report", str(tmp_path / "run"))
    assert report.returncode == 2 and report.stdout == ""
    assert re.match(
        r"error: nothing to report for .*: the run is empty: 0 of 6 planned episodes stored; it stopped early: "
        r"stopped after 3 episodes in a row failed with: .*no policy server at 127\.0\.0\.1:1",
        report.stderr,
    )


def test_a_run_that_ends_with_gaps_exits_3(short_catalog, tmp_path):
    result = _cli_eval(
        short_catalog,
        tmp_path / "run",
        "tests.support.policies:RaisingPolicy",
        "--episodes",
        "1",
        "--max-attempts",
        "1",
        "--max-failure-streak",
        "10",
    )
    assert result.returncode == 3 and "(0 successes, 3 gaps)" in result.stdout
    assert [r["attempts"] for r in store_rows(tmp_path / "run")] == [1, 1, 1]  # --max-attempts 1 reached the loop


def test_every_flag_of_a_run_reaches_its_effect(short_catalog, tmp_path):
    run = tmp_path / "run"
    result = run_cli(
        "eval",
        "--policy",
        "noop",
        "--catalog",
        short_catalog,
        "--run",
        str(run),
        "--episodes",
        "2",
        "--tasks",
        "spatial/s0/black-bowl-*",
        "--style",
        "paper",
        "--seed",
        "5",
        "--condition",
        "given",
        "--condition",
        "empty",
        "--workers",
        "2",
        "--max-attempts",
        "2",
        "--timeout",
        "300",
    )
    assert result.returncode == 0, result.stderr
    rows = store_rows(run)
    assert {r["task_id"] for r in rows} == {"spatial/s0/black-bowl-1-on-plate", "spatial/s0/black-bowl-2-on-plate"}
    assert sorted({(r["init_index"], r["seed"]) for r in rows}) == [(0, episode_seed(5, 0)), (1, episode_seed(5, 1))]
    assert {r["condition"] for r in rows} == {"given", "empty"}
    given = [r["instruction"] for r in rows if r["condition"] == "given"]
    from langgap.catalog.catalog import load_catalog_file

    task = load_catalog_file(short_catalog).get("spatial/s0/black-bowl-1-on-plate")
    assert task.instruction("paper") in given and task.instruction("libero") not in given
    assert {r["worker"] for r in rows} == {0, 1}
    assert "Success on extended tasks by dimension" in result.stdout  # the diagnosis, since --quiet was not given
    assert "%|" in result.stderr  # the progress bar, since --no-progress was not given
    with RunStore.open(run) as store:
        execution = store.meta("execution")
    assert (execution["max_attempts"], execution["timeout_s"], execution["workers"]) == (2, 300, 2)
    quiet = _cli_eval(short_catalog, tmp_path / "quiet", "noop", "--episodes", "1")
    assert quiet.returncode == 0 and quiet.stdout.count("\n") == 1 and "%|" not in quiet.stderr


def test_repeats_run_every_episode_with_more_seeds_and_reports_the_spread(short_catalog, tmp_path):
    run = tmp_path / "run"
    result = _cli_eval(short_catalog, run, "random", "--episodes", "2", "--repeats", "2", "--tasks", "spatial/s0/open*")
    assert result.returncode == 0, result.stderr
    assert sorted((r["init_index"], r["seed"]) for r in store_rows(run)) == [(0, 0), (0, 1000), (1, 1), (1, 1001)]
    again = _cli_eval(short_catalog, run, "random", "--episodes", "2", "--repeats", "2", "--tasks", "spatial/s0/open*",
                      "--resume")  # fmt: skip
    assert again.returncode == 0 and "4 planned, 4 already stored, 0 run" in again.stdout, again.stdout
    report = run_cli("report", str(run), "--no-published")
    assert "Between-seed spread" in report.stdout and "run seed 0 + init index, 2 repeats" in report.stdout
