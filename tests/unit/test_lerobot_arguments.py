"""A `lerobot` policy's checkpoint path is checked before a run starts, without LeRobot: a path that holds no
checkpoint is bad input (one error line, exit code 2, no run directory), not a run whose every episode fails.
The `lerobot` policy itself imports only in .venv-lerobot (tests/test_lerobot.py runs it there); here a policy
class with the same check stands for it."""

from __future__ import annotations

import pytest

from langgap.cli.main import main
from langgap.policies import policy_kwargs
from langgap.policies.lerobot_checkpoint import CheckpointError, check_arguments


class CheckpointPolicy:
    """A policy that takes a LeRobot checkpoint as `lerobot` does (its arguments and their check)."""

    check_arguments = staticmethod(check_arguments)

    def __init__(self, path: str, device: str = "cpu", adapter: str = ""):
        raise AssertionError("never built: its arguments are refused first")


POLICY = f"{__name__}:CheckpointPolicy"


@pytest.fixture
def checkpoint(tmp_path):
    """A directory as LeRobot saves a checkpoint: its pretrained_model/ holds config.json (and the weights)."""
    model = tmp_path / "ckpt" / "pretrained_model"
    model.mkdir(parents=True)
    (model / "config.json").write_text("{}")
    (model / "model.safetensors").write_bytes(b"")
    return tmp_path / "ckpt"


def test_a_checkpoint_directory_or_its_pretrained_model_is_accepted(checkpoint, tmp_path):
    check_arguments(path=str(checkpoint))
    check_arguments(path=str(checkpoint / "pretrained_model"), adapter=str(tmp_path), device="cuda")
    assert policy_kwargs(POLICY, {"path": str(checkpoint), "device": "cuda"}) == {
        "path": str(checkpoint),
        "device": "cuda",
    }


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"path": "/nonexistent"}, "no LeRobot checkpoint at /nonexistent (expected config.json there or in "),
        ({}, "lerobot needs path=DIR"),
        ({"adapter": "/no-adapter"}, "no PEFT adapter directory at /no-adapter"),
    ],
)
def test_a_path_that_holds_no_checkpoint_is_refused(arguments, message, checkpoint):
    if "path" not in arguments and "adapter" in arguments:
        arguments = {"path": str(checkpoint), **arguments}
    with pytest.raises(CheckpointError) as error:
        check_arguments(**arguments)
    assert str(error.value).startswith(message) and error.value.exit_code == 2
    with pytest.raises(CheckpointError):
        policy_kwargs(POLICY, arguments)


def test_eval_refuses_it_before_the_run_directory_exists(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()  # a directory, but no checkpoint in it
    run = tmp_path / "run"
    code = main(["eval", "--policy", POLICY, "--policy-arg", f"path={empty}", "--run", str(run), "--workers", "0"])
    out, err = capsys.readouterr()
    assert code == 2 and err == f"error: no LeRobot checkpoint at {empty} (expected config.json there or in " + (
        "pretrained_model/)\n"
    )
    assert not run.exists()
