"""Bad arguments name the parameter as the caller passed it: a Python caller reads `episodes`, `workers`,
`max_attempts`; the CLI reads the flag that sets it (`--episodes`, `--workers`, `collect`'s
`--max-task-attempts`), spelled from the parser's own actions (`langgap.cli.parameter_flags`)."""

from __future__ import annotations

import ast
import copy
import pickle
import re
from collections.abc import Iterator

import pytest

from langgap.cli.execution_flags import execution_options
from langgap.cli.main import build_parser, main
from langgap.cli.parameter_flags import error_message
from langgap.engine.evaluate import evaluate
from langgap.engine.spec import ExecutionOptions, RunSpec, SpecError
from langgap.errors import ParameterError
from langgap.policies.lerobot_checkpoint import check_arguments
from langgap.report.pooled import pool
from langgap.store import RunStore
from tests.support.harness import REPO, cli_parsers
from tests.support.reports import reader, write_run

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


# Below the CLI, an error names a Python parameter: a flag of LangGap's CLI in what a library module raises is one
# the CLI should have spelled. A whole command quoted for the user to run (`langgap export-hdf5 DIR --images`) reads
# the same from Python; other tools' flags (pip's, lerobot-eval's) are theirs.
_FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")
_COMMAND = re.compile(r"`langgap [^`]*`")
_RAISES = re.compile(r"(Error|Exhausted|Stopped)$")


def _callee(node: ast.AST) -> str:
    func = node.func if isinstance(node, ast.Call) else None
    return func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""


def _raised_strings(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """The strings of each exception a scope raises or builds, with those of the names it builds them from."""
    for scope in ast.walk(tree):
        if not isinstance(scope, ast.Module | ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        made = [n.exc for n in ast.walk(scope) if isinstance(n, ast.Raise) and n.exc is not None]
        made += [n for n in ast.walk(scope) if _RAISES.search(_callee(n))]
        names = {n.id for m in made for n in ast.walk(m) if isinstance(n, ast.Name)}
        made += [
            n.value
            for n in ast.walk(scope)
            if isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id in names for t in n.targets)
        ]
        for node in made:
            pieces = list(ast.walk(node))
            inside = {id(v) for f in pieces if isinstance(f, ast.JoinedStr) for v in f.values}
            for piece in pieces:
                if isinstance(piece, ast.JoinedStr):  # an f-string read whole, its fields as {}
                    yield piece.lineno, "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in piece.values)
                elif isinstance(piece, ast.Constant) and isinstance(piece.value, str) and id(piece) not in inside:
                    yield piece.lineno, piece.value


def _flags_raised(source: str, flags: set[str]) -> set[str]:
    return {
        f"{line}: {flag}"
        for line, text in _raised_strings(ast.parse(source))
        for flag in _FLAG.findall(_COMMAND.sub("", text))
        if flag in flags
    }


def test_no_library_module_raises_an_error_that_spells_a_flag():
    flags = {o for _, p in cli_parsers(build_parser()) for a in p._actions for o in a.option_strings}
    src = REPO / "src" / "langgap"
    library = [p for p in sorted(src.rglob("*.py")) if p.relative_to(src).parts[0] != "cli"]
    found = [f"{p.relative_to(src)}:{hit}" for p in library for hit in sorted(_flags_raised(p.read_text(), flags))]
    assert not found, found
    # what the scan finds: a flag raised, or built into a message beforehand; not a command quoted, nor pip's flag
    caught = _flags_raised(
        "def f(x):\n"
        "    hint = ' (--extend grows it)'\n"
        "    if x:\n"
        "        raise SpecError('run ' + hint)\n"
        "    raise LangGapError('--run exists; run `langgap eval --resume` or pip download --no-deps')\n"
        "def g(x):\n"
        "    raise LangGapError(f'--device {x}: run `langgap export-hdf5 {x} --images` first')\n",
        flags,
    )
    assert caught == {"2: --extend", "5: --run", "7: --device"}


def test_a_resume_with_another_spec_names_extend_as_the_caller_passes_it(tmp_path, capsys):
    run = tmp_path / "run"
    RunStore.create(run, {"spec": RunSpec.create("noop", tasks=BOWL_1, episodes=1).to_dict()}).close()
    grown = RunSpec.create("noop", tasks=BOWL_1, episodes=2)
    with pytest.raises(SpecError) as info:
        evaluate(grown, run, ExecutionOptions(workers=0), resume=True)
    assert str(info.value).endswith(" (extend grows a run's tasks, episodes or conditions)")
    argv = ["eval", "--policy", "noop", "--tasks", BOWL_1, "--episodes", "2", "--run", str(run), "--resume"]
    assert main([*argv, "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: run {run} was made with another spec: ")
    assert err.endswith(" (--extend grows a run's tasks, episodes or conditions)\n")


def test_pooling_runs_of_two_protocols_names_allow_mismatch_as_the_caller_passes_it(tmp_path, capsys):
    first = write_run(tmp_path / "a", "my-vla", reader())
    other = write_run(tmp_path / "b", "my-vla", reader(), physics={"mujoco": "3.3.0"})
    with pytest.raises(ParameterError) as info:
        pool({"x": [first, other]})
    assert str(info.value).endswith("must come from one protocol (allow_mismatch pools them anyway)")
    assert main(["report", "--pool", f"x={first},{other}"]) == 2
    assert capsys.readouterr().err == (
        f"error: {other} differs from {first} in physics: pooled episodes must come from one protocol "
        "(--allow-mismatch pools them anyway)\n"
    )


def test_a_policy_argument_reads_as_the_constructor_takes_it_and_as_policy_arg_on_the_command_line(capsys):
    with pytest.raises(ParameterError) as info:
        check_arguments()
    assert str(info.value) == "lerobot needs path=DIR, a checkpoint's pretrained_model/ directory"
    parser = build_parser()
    args = parser.parse_args(["eval", "--policy", "lerobot", "--run", "r"])
    assert error_message(info.value, parser, args).startswith("lerobot needs --policy-arg path=DIR, ")
