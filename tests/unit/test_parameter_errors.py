"""Bad arguments name the parameter as the caller passed it: a Python caller reads `episodes`, `workers`,
`max_attempts`; the CLI reads the flag that sets it (`--episodes`, `--workers`, `collect`'s
`--max-task-attempts`), spelled from the parser's own actions (`langgap.cli.parameter_flags`)."""

from __future__ import annotations

import copy
import pickle

import pytest

from langgap.cli.execution_flags import execution_options
from langgap.cli.main import build_parser, main
from langgap.cli.parameter_flags import error_message
from langgap.engine.spec import ExecutionOptions, RunSpec, SpecError
from langgap.errors import ParameterError

BOWL_1 = "spatial/s0/black-bowl-1-on-plate"


def test_a_python_caller_reads_the_parameter_it_passed():
    with pytest.raises(ParameterError) as spec:
        RunSpec.create("noop", tasks=BOWL_1, episodes=0)
    assert str(spec.value) == "episodes must be at least 1, got 0"
    assert spec.value.parameters == ("episodes",)
    assert isinstance(spec.value, SpecError)  # still the spec's error, as before
    with pytest.raises(ParameterError) as options:
        ExecutionOptions(workers=-1)
    assert str(options.value) == "workers must be at least 0, got -1"
    with pytest.raises(ParameterError) as attempts:
        ExecutionOptions(max_attempts=0)
    assert (str(attempts.value), attempts.value.parameters) == (
        "max_attempts must be at least 1, got 0",
        ("max_attempts",),
    )
    with pytest.raises(ParameterError) as both:
        ExecutionOptions(backend="ray", shared_policy=True, max_wait_ms=-1.0)
    assert both.value.parameters == ("max_wait_ms", "policy_gpus")


def test_another_spelling_renames_only_the_parameters():
    error = ParameterError("{video} takes first:N, got {got!r}", got="{video}")
    assert str(error) == "video takes first:N, got '{video}'"  # a value is never read as a field
    assert error.naming({"video": "--video"}) == "--video takes first:N, got '{video}'"
    assert error.naming({}) == str(error)


@pytest.mark.parametrize("clone", [copy.copy, lambda e: pickle.loads(pickle.dumps(e))], ids=["copy", "pickle"])
def test_an_error_copied_or_pickled_keeps_its_parameters(clone):
    with pytest.raises(ParameterError) as info:
        ExecutionOptions(video="{x}")
    again = clone(info.value)
    assert type(again) is type(info.value) and str(again) == "video takes first:N, per-outcome:N or N, got '{x}'"
    assert again.naming({"video": "--video"}) == info.value.naming({"video": "--video"})


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["eval", "--policy", "noop", "--tasks", BOWL_1, "--episodes", "0"], "--episodes must be at least 1, got 0"),
        (["eval", "--policy", "noop", "--tasks", BOWL_1, "--workers", "-1"], "--workers must be at least 0, got -1"),
        (
            ["eval", "--policy", "noop", "--tasks", BOWL_1, "--workers", "0", "--timeout", "5"],
            "--timeout needs worker processes: an episode in this process cannot be stopped",
        ),
        (
            ["eval", "--policy", "noop", "--tasks", BOWL_1, "--max-attempts", "0"],
            "--max-attempts must be at least 1, got 0",
        ),
        # `validate --inits` reaches `RunSpec.create` as `episodes`: the command's own flag is named.
        (["validate", BOWL_1, "--inits", "0", "--policy", "noop"], "--inits must be at least 1, got 0"),
    ],
    ids=["episodes", "workers", "timeout", "max-attempts", "validate-inits"],
)
def test_the_cli_reads_the_flag(argv, line, tmp_path, capsys):
    run = ["--run", str(tmp_path / "run")] if argv[0] == "eval" else []
    assert main([*argv, *run]) == 2
    assert capsys.readouterr().err == f"error: {line}\n"
    assert not any(tmp_path.iterdir())  # refused before anything was written


def test_a_flag_of_another_dest_is_found_in_the_parser():
    """`collect` spells the retries `--max-task-attempts` (its own `--max-attempts` counts demonstration
    attempts per task): the flag is read from the parser's action for `max_attempts`, not made from the
    parameter's name. (`collect` itself imports the simulator, so its parsed arguments go through the function
    its command calls.)"""
    parser = build_parser()
    args = parser.parse_args(
        ["collect", "--tasks", BOWL_1, "--demos", "1", "--out", "demos", "--max-task-attempts", "0"]
    )
    with pytest.raises(ParameterError) as info:
        execution_options(args)
    assert error_message(info.value, parser, args) == "--max-task-attempts must be at least 1, got 0"
