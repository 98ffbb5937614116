"""`langgap check-policy`: each broken policy fails its check with a fix (exit 1), good ones pass (exit 0), an
openpi server's inputs are shown as sent, and `langgap eval` names the check when its policy fails.

The policies without cameras or privileges share one environment (`check_policy(env=...)`); the CLI runs are
the few that show what only the command line does.
"""

from __future__ import annotations

import numpy as np
import pytest

import tests.support.policies as policies
from langgap.cli.main import main
from langgap.diagnostics.policy_check import EPISODE_CHECKS, UPRIGHT, check_policy
from langgap.engine.rollout import env_options_for
from langgap.policies.simple import NoopPolicy
from langgap.sim.env import TaskEnv
from tests.support.harness import TINY_TASK, run_cli
from tests.support.servers import free_port, helper_server, running, subprocess_env

SUPPORT = "tests.support.policies"
CHECKS = ["interface", "spec", "privileges", *EPISODE_CHECKS]


@pytest.fixture(scope="module")
def env(catalog):
    """One environment for every policy that needs no camera and no privilege: the check's first task."""
    with TaskEnv(catalog.select(None)[0], env_options_for(NoopPolicy())) as shared:
        yield shared


@pytest.mark.parametrize(
    ("policy", "args", "timeout_s", "check", "message", "fix"),
    [
        pytest.param(
            f"{SUPPORT}:WrongShapePolicy", None, 900, "actions",
            "call 1: policy returned shape (6,); expected (7,) or (k, 7) (eval records a policy_error)",
            "return one action of 7 numbers", id="wrong shape",
        ),
        pytest.param(
            f"{SUPPORT}:NanPolicy", None, 900, "actions", "policy returned a non-finite action (NaN or inf)",
            "find where the model makes NaN or inf", id="NaN",
        ),
        pytest.param(
            f"{SUPPORT}:LongChunkPolicy", None, 900, "actions",
            "policy returned a chunk of 3 actions; its spec declares chunk=2", "declare PolicySpec(chunk=3)",
            id="longer chunk than declared",
        ),
        pytest.param(
            f"{SUPPORT}:RaisingPolicy", None, 900, "actions", "act raised RuntimeError: model exploded (",
            "fix the exception: eval attempts such an episode 3 times, then stores a gap", id="exception in act",
        ),
        pytest.param(
            f"{SUPPORT}:OutOfRangePolicy", None, 900, "actions", "4 of 28 values outside [-1, 1]: robosuite clips",
            "return actions in [-1, 1]", id="out of bounds",
        ),
        pytest.param(
            f"{SUPPORT}:UnseededRandomPolicy", None, 900, "determinism",
            "the same episode twice (init state 0, seed 0) gave other actions from call 1 on",
            "or declare PolicySpec(stochastic=True)", id="nondeterministic, declared deterministic",
        ),
        pytest.param(
            "delay", {"delay_ms": "150"}, 60, "latency", "more than half of eval's --timeout 60 s per episode",
            "or give eval --timeout", id="slow act",
        ),
        pytest.param(
            f"{SUPPORT}:ClosesOncePolicy", None, 900, "lifecycle", "close again raised RuntimeError: already closed",
            "make close() safe to call twice", id="close twice",
        ),
        pytest.param(
            f"{SUPPORT}:LateNanPolicy", None, 900, "whole episode",
            "the whole episode, call 10 (step 10): policy returned a non-finite action (NaN or inf) (eval records",
            "find where the model makes NaN or inf", id="NaN late in the episode",
        ),
        pytest.param(
            f"{SUPPORT}:NonePolicy", None, 900, "actions", "call 1: policy returned None, not an action",
            "return the action from act", id="returns None",
        ),
    ],
)  # fmt: skip
def test_a_broken_policy_fails_its_check_with_a_fix_and_exit_1(env, policy, args, timeout_s, check, message, fix):
    report = check_policy(policy, args, timeout_s=timeout_s, budget_s=5, env=env)
    assert report.exit_code == 1
    (failed,) = report.failed
    assert failed.name == check and message in failed.detail and fix in failed.remedy, report.page()
    assert [c.name for c in report.checks] == CHECKS
    # What needs a played-out episode is not run after an output that ended it; every other check ran.
    ended = check == "actions" and "values outside" not in message
    skipped = CHECKS[CHECKS.index("lifecycle") :] if ended else []
    assert [c.name for c in report.checks if c.ok is None] == skipped
    page = report.page()
    assert f"[FAIL] {check}" in page and f"fix: {failed.remedy}" in page
    assert page.splitlines()[-1].startswith(f"check-policy: 1 of {len(CHECKS) - len(skipped)} checks failed")
    if "raised" in message:  # and the line of the policy's code that raised
        raising = getattr(policies, policy.partition(":")[2])
        method = raising.act if check == "actions" else raising.close
        assert f"policies.py:{method.__code__.co_firstlineno + 1 + (check == 'lifecycle')}, in {method.__name__})" in (
            failed.detail
        )


@pytest.mark.parametrize(
    ("policy", "failed", "message", "fix"),
    [
        ("SpeclessPolicy", "interface", "no spec", "give the class spec = PolicySpec(...)"),
        (
            "UnbuildablePolicy",
            "build",
            "the constructor raised FileNotFoundError: no checkpoint at /nowhere (",
            "fix the exception in the constructor",
        ),
        ("UnknownCameraPolicy", "spec", "unknown camera(s) ['frontview']", "declare cameras LIBERO has"),
        ("HugeImagePolicy", "spec", "image size must be in 16..1024, got 2048", "an image_size in 16..1024"),
    ],
)
def test_a_policy_that_cannot_run_an_episode_fails_before_one(policy, failed, message, fix):
    """Nothing is simulated: the check says what stops every episode, and shows the rest as not run."""
    report = check_policy(f"{SUPPORT}:{policy}")
    assert report.exit_code == 1
    (found,) = report.failed
    assert found.name == failed and message in found.detail and fix in found.remedy, report.page()
    assert all(c.ok is None for c in report.checks if c.name in EPISODE_CHECKS)
    assert len(report.heading) == 1  # no episode ran


def test_a_slow_policy_s_latency_gives_the_timeout_that_would_fit(env):
    """The latency verdict and the estimate come from the measured calls: 150 ms per call make a 520-step
    libero_10 episode (520 calls) take over 78 s, more than half of a 60 s timeout; the timeout it names (whole
    minutes) fits, with room for the noise of another measurement."""
    slow = check_policy("delay", {"delay_ms": "150"}, timeout_s=60, budget_s=5, env=env)
    (latency,) = [c for c in slow.checks if c.name == "latency"]
    assert "libero_10, 520 steps, 520 calls" in latency.detail
    needed = int(latency.remedy.split("--timeout ")[1].split()[0])
    assert needed % 60 == 0 and 2 * 520 * 0.15 <= needed <= 2 * 520 * 0.3 + 60
    assert check_policy("delay", {"delay_ms": "150"}, timeout_s=1.5 * needed, budget_s=5, env=env).exit_code == 0


@pytest.mark.parametrize(
    ("policy", "args", "said"),
    [
        ("noop", None, ["no camera; chunk 1, replan 1: one action per call", "gave the same actions (4 calls)"]),
        (
            "random",
            {"chunk": "5"},
            ["cut to 20 of its 220 steps", "chunk 5, replan 5", "libero_spatial 220 steps (44 calls)"],
        ),
        (f"{SUPPORT}:DeclaredStochasticPolicy", None, ["declared stochastic: the same episode twice", "from call 1"]),
    ],
)
def test_a_good_policy_passes_every_check_with_exit_0(env, policy, args, said):
    report = check_policy(policy, args, env=env)
    assert report.exit_code == 0 and all(c.ok for c in report.checks), report.page()
    assert [c.name for c in report.checks] == CHECKS
    page = report.page()
    assert all(text in page for text in said), page
    assert "1,980 episodes (99 tasks × 20 init states of langgap99)" in page  # eval's default plan, counted
    assert "instruction-blind (reads_instruction=False)" in page and "a policy under test" in page
    assert page.splitlines()[-1].startswith(f"check-policy: all {len(CHECKS)} checks passed")


def test_the_oracle_passes_from_the_command_line_with_every_flag(short_catalog):
    """As a user runs it: exit 0, one page; the flags reach the check (catalog, tasks, episodes, timeout, style)."""
    task = "spatial/s0/black-bowl-2-on-plate"
    result = run_cli(
        *("check-policy", "oracle", "--catalog", short_catalog, "--tasks", task),
        *("--episodes", "3", "--timeout", "20", "--style", "paper"),
    )
    assert result.returncode == 0, result.stdout + result.stderr
    page = result.stdout
    assert f"{task} (short), init state 0, seed 0, cut to 4 of its 15 steps" in page
    assert "3 episodes (1 task × 3 init states of short)" in page and "libero_spatial 15 steps" in page
    assert "within half of eval's --timeout 20 s per episode" in page
    assert "instruction 'pick up the black bowl on the right of the ramekin and place it on the plate'" in page
    assert "sees_goal: told the task id and the goal at reset, so a scripted reference (marked †)" in page
    assert "the simulator state (" in page


def test_a_failing_check_exits_1_from_the_command_line(short_catalog):
    result = run_cli("check-policy", f"{SUPPORT}:NanPolicy", "--catalog", short_catalog)
    assert result.returncode == 1 and result.stderr == ""
    assert "[FAIL] actions" in result.stdout and "fix: find where the model makes NaN" in result.stdout


def test_an_openpi_server_s_inputs_are_shown_as_sent(tmp_path):
    """A plain openpi server (openpi's own server package, recording what it receives): the page names the
    observation the client gets and the request it sends, which is what the server received."""
    port = free_port()
    with running(helper_server("openpi-record", port), port, env=subprocess_env(RECORD_DIR=str(tmp_path))):
        report = check_policy("openpi", {"port": str(port)})
    assert report.exit_code == 0, report.page()
    (inputs,) = [c.detail for c in report.checks if c.name == "inputs"]
    received = dict(np.load(tmp_path / "0000.npz"))
    assert (
        "receives state float32 (8,), agentview uint8 (256, 256, 3), robot0_eye_in_hand uint8 (256, 256, 3)" in inputs
    )
    assert UPRIGHT in inputs
    (sends,) = [line for line in inputs.splitlines() if line.startswith("sends ")]
    shown = [f"{k} {repr(str(v)) if k == 'prompt' else f'{v.dtype} {v.shape}'}" for k, v in received.items()]
    assert all(item in sends for item in shown)  # every key the server received, as it received it
    assert len(sends) == len("sends ") + len(", ".join(shown))  # and nothing else
    assert "observation/image uint8 (224, 224, 3), observation/wrist_image uint8 (224, 224, 3)" in sends
    page = report.page()
    assert "chunk 5, replan 5" in page and "close, close again" in page


def test_eval_names_check_policy_when_its_policy_fails(short_catalog, tmp_path, capsys):
    run = ("eval", "--catalog", short_catalog, "--tasks", TINY_TASK, "--episodes", "1", "--workers", "0")
    quiet = ("--no-progress", "--quiet")
    command = f"langgap check-policy {SUPPORT}:%s --catalog {short_catalog} --tasks {TINY_TASK}"
    # A malformed action: the run goes on (a policy_error), and says how to find why.
    assert main([*run, "--policy", f"{SUPPORT}:NanPolicy", "--run", str(tmp_path / "nan"), *quiet]) == 0
    assert f"policy errors: 1, gaps: 0; check the policy in a minute with {command % 'NanPolicy'}" in (
        capsys.readouterr().out
    )
    # An exception in act: the run stops, and its one error line says the same.
    stop = ("--max-attempts", "1", "--max-failure-streak", "1")
    assert main([*run, "--policy", f"{SUPPORT}:RaisingPolicy", "--run", str(tmp_path / "raise"), *stop, *quiet]) == 4
    (error,) = capsys.readouterr().err.splitlines()
    assert error.startswith("error: stopped after 1 episodes in a row failed with: RuntimeError: model exploded")
    assert error.endswith(f"; check the policy in a minute with {command % 'RaisingPolicy'}")


def test_the_episode_is_played_whole_and_the_page_says_how_much(env):
    """The check plays eval's first episode to its step limit when the budget allows, else as far as it does, and
    says which; a check that runs a while says so on stderr (`say`)."""
    noop = check_policy("noop", env=env)
    (whole,) = [c for c in noop.checks if c.name == "whole episode"]
    assert whole.ok and not whole.warning
    assert whole.detail.startswith("played to its step limit, no goal reached: 220 of its 220 steps, 220 calls")
    said: list[str] = []
    slow = check_policy("delay", {"delay_ms": "100"}, budget_s=2, env=env, say=said.append)
    (whole,) = [c for c in slow.checks if c.name == "whole episode"]
    played = int(whole.detail.split()[1])
    assert whole.ok and 5 <= played < 220 and f"played {played} of its 220 steps" in whole.detail
    assert f"the steps after {played} are not checked" in whole.warning and "larger --budget" in whole.warning
    assert "[warn] whole episode" in slow.page() and slow.page().splitlines()[-1].endswith(
        "checks passed, 1 with a warning (" + slow.page().splitlines()[-1].split("(")[-1]
    )
    assert any(line.startswith("note: check-policy: playing the episode whole:") for line in said)


def test_a_silent_wait_is_broken_by_notes(env, monkeypatch):
    import langgap.diagnostics.policy_check as policy_check

    monkeypatch.setattr(policy_check, "NOTE_EVERY_S", 0.0)
    said: list[str] = []
    check_policy("delay", {"delay_ms": "20"}, budget_s=1, env=env, say=said.append)
    assert "note: check-policy: the episode: 1 calls so far, the last " in said[0]
    assert any("the whole episode: " in line for line in said)


def test_integer_actions_pass_and_are_said_to_be_taken_as_floats(env):
    report = check_policy(f"{SUPPORT}:IntegerPolicy", budget_s=2, env=env)
    (actions,) = [c for c in report.checks if c.name == "actions"]
    assert report.exit_code == 0 and "(7,) int64" in actions.detail and "integers are taken" in actions.detail


def test_cameras_are_checked_as_the_policy_reads_them():
    """Declared and never read: a warning that each call renders them. Read and not declared: a failure that names
    the spec, in check-policy and in the policy's own exception."""
    unread = check_policy(f"{SUPPORT}:UnreadCamerasPolicy", budget_s=2, timeout_s=1e6)  # renders are slow here
    (inputs,) = [c for c in unread.checks if c.name == "inputs"]
    assert unread.exit_code == 0 and "act never read agentview, robot0_eye_in_hand in" in inputs.warning
    assert "declare every camera act reads in PolicySpec(cameras=...)" in inputs.warning
    undeclared = check_policy(f"{SUPPORT}:UndeclaredCameraPolicy", budget_s=2, timeout_s=1e6)
    (failed,) = undeclared.failed
    assert failed.name == "actions" and failed.remedy.startswith("declare every camera act reads")
    assert (
        "act raised CameraNotDeclared: camera 'robot0_eye_in_hand' is not rendered: the policy's spec declares "
        "agentview" in failed.detail
    )
