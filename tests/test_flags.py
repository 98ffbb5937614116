"""Every flag of every verb reaches its effect: the checks of `tests/support/flag_table.py`, run for real
(the fast layer's `tests/unit/test_flag_table.py` makes sure every option has one)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from langgap.cli.main import main
from tests.support.flag_table import FLAG_CHECKS, SHORT_TASK, Differs, Refused
from tests.support.harness import store_rows
from tests.support.servers import free_port, langgap_serve, running

# Columns of a stored episode that differ between two identical runs.
_TIMING = ("wall_time_s", "finished_at")


def _params() -> list:
    """One test per `Differs` and `Refused` of the table; a known-broken one is a strict xfail."""
    params = []
    for option, checks in FLAG_CHECKS.items():
        for i, check in enumerate(checks):
            if isinstance(check, Differs | Refused):
                marks = [pytest.mark.xfail(strict=True, reason=check.broken)] if check.broken else []
                params.append(pytest.param(check, id=f"{option} #{i + 1}", marks=marks))
    return params


@pytest.fixture(scope="module")
def stored_runs(short_catalog, tmp_path_factory) -> dict[str, str]:
    """`{stored}`, `{same}` (its spec again) and `{reseeded}` (another seed): one-episode `noop` runs."""
    from langgap.engine.evaluate import evaluate
    from langgap.engine.spec import ExecutionOptions, RunSpec

    root = tmp_path_factory.mktemp("stored")
    runs = {"stored": 0, "same": 0, "reseeded": 1}
    for name, seed in runs.items():
        spec = RunSpec.create("noop", catalog=short_catalog, tasks=SHORT_TASK, episodes=1, seed=seed)
        evaluate(spec, root / name, ExecutionOptions(workers=0, progress=False))
    return {name: str(root / name) for name in runs}


class _Invoker:
    """Runs `langgap ARGV` in this process, each invocation in a fresh directory `{dir}`, and says what it did."""

    def __init__(self, request, tmp_path: Path, capsys, monkeypatch):
        self.request, self.tmp_path, self.capsys, self.monkeypatch = request, tmp_path, capsys, monkeypatch
        self.fills = {"catalog": request.getfixturevalue("short_catalog"), "collection": str(tmp_path / "none")}
        self.count = 0

    def __call__(self, argv: tuple[str, ...], path: str | None = None) -> tuple[int, str, str, Path]:
        self.count += 1
        directory = self.tmp_path / f"call{self.count}"
        directory.mkdir()
        if any("{stored}" in a or "{same}" in a or "{reseeded}" in a for a in argv):
            self.fills.update(self.request.getfixturevalue("stored_runs"))
        args = [a.format(dir=directory, **self.fills) for a in argv]
        with self.monkeypatch.context() as patch:
            if path is not None:
                patch.setenv("PATH", path)
            try:
                code = main(args)
            except SystemExit as exc:  # argparse's own refusals
                code = exc.code
        out, err = self.capsys.readouterr()
        return code, out.replace(str(directory), "{dir}"), err, directory

    def observe(self, argv: tuple[str, ...], path: str | None = None) -> dict:
        """Everything a flag may change: exit status, stdout, the `error:` line, whether a progress bar showed,
        the episodes stored in `{dir}/run`, the files written under `{dir}` and what its JSON files hold."""
        code, out, err, directory = self(argv, path)
        rows = store_rows(directory / "run") if (directory / "run" / "episodes.sqlite").exists() else []
        return {
            "exit": code,
            "stdout": out,
            "error": [line for line in err.splitlines() if line.startswith("error:")],
            "progress bar": "%|" in err,
            "episodes": [{k: v for k, v in r.items() if k not in _TIMING} for r in rows],
            "files": sorted(str(p.relative_to(directory)) for p in directory.rglob("*") if p.is_file()),
            "json written": [p.read_text().replace(str(directory), "{dir}") for p in sorted(directory.rglob("*.json"))],
        }


@pytest.mark.parametrize("check", _params())
def test_the_flag_reaches_its_effect(check, request, tmp_path, capsys, monkeypatch):
    invoke = _Invoker(request, tmp_path, capsys, monkeypatch)
    if isinstance(check, Differs):
        without = invoke.observe(check.base, check.path)
        with_flag = invoke.observe((*check.base, *check.added), check.path)
        assert with_flag != without, f"{' '.join(check.added)} changed nothing: {without}"
    else:
        code, out, err, directory = invoke(check.argv)
        assert code == 2, (out, err)
        lines = err.splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ") and check.message in lines[0], err
        assert not any(directory.iterdir())  # a refusal writes nothing


def test_serve_binds_the_host_and_port_it_is_given():
    """`--host` and `--port` decide where the policy listens (127.0.0.2 is loopback too, but not the default)."""
    port = free_port()
    command = [*langgap_serve(port, "noop"), "--host", "127.0.0.2"]
    with running(command, port, host="127.0.0.2") as server:
        listening = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    mine = [line.split()[3] for line in listening.splitlines() if f"pid={server.pid}," in line]
    assert mine == [f"127.0.0.2:{port}"]


@pytest.mark.parametrize("kind", ["small-bc", "small-vla"])
def test_small_bc_training_options_reach_the_config(tmp_path, kind):
    """`--lr`, `--seed`, `--loss` and `--device` land in the training config, over a `--config` file's values; so does
    the file's `model` mapping, as the kind's own model config."""
    from langgap.cli.main import build_parser
    from langgap.cli.train_cmd import _training_config
    from langgap.policies.small_bc.model import ModelConfig
    from langgap.policies.small_vla.model import VisionConfig

    model_config = {"small-bc": ModelConfig, "small-vla": VisionConfig}[kind]
    config_file = tmp_path / "bc.yaml"
    config_file.write_text("lr: 0.5\nseed: 3\nloss: l1\ndevice: cuda\nmodel:\n  chunk: 4\n")
    base = ["train", kind, "--config", str(config_file), "--data", "d", "--out", "o.safetensors"]
    from_file, _ = _training_config(build_parser().parse_args(base), model_config)
    assert (from_file.lr, from_file.seed, from_file.loss, from_file.device) == (0.5, 3, "l1", "cuda")
    assert from_file.model == model_config(chunk=4)
    flags, _ = _training_config(
        build_parser().parse_args([*base, "--lr", "0.01", "--seed", "9", "--loss", "mse", "--device", "cpu"]),
        model_config,
    )
    assert (flags.lr, flags.seed, flags.loss, flags.device) == (0.01, 9, "mse", "cpu")
    assert flags.torch_device().type == "cpu"  # the device the trainer moves the model to


@pytest.mark.parametrize(
    ("available", "count", "message"),
    [
        (False, 0, "device cuda:1: PyTorch sees no CUDA device on this machine"),
        (True, 1, "device cuda:1: PyTorch sees 1 CUDA device(s) on this machine, numbered from 0"),
    ],
)
def test_a_cuda_device_this_machine_lacks_is_refused_before_training(monkeypatch, available, count, message):
    # What PyTorch reports of the machine's GPUs is set here (this machine may have none); the check is LangGap's.
    import torch

    from langgap.errors import ParameterError
    from langgap.training.loop import TrainConfig

    monkeypatch.setattr(torch.cuda, "is_available", lambda: available)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: count)
    with pytest.raises(ParameterError) as raised:
        TrainConfig(data=("d",), device="cuda:1").torch_device()
    assert str(raised.value) == message
