"""What an evaluation resolves once and hands down: the catalog, loaded once per `evaluate` in this process, and
each task's files (`TaskFiles`), resolved once per worker and given to the simulator, which reads none itself."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from langgap import stack
from langgap.catalog import catalog as catalog_module
from langgap.catalog import files as files_module
from langgap.catalog import packages
from langgap.catalog.files import scene_key, task_files
from langgap.engine.evaluate import evaluate
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.sim.env import EnvOptions, TaskEnv
from tests.support.harness import store_rows


def _rebind(monkeypatch, original: Callable, replacement: Callable) -> None:
    """Put `replacement` wherever a LangGap module holds `original` (its own module, and every module that
    imported it by name), for the rest of the test."""
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("langgap"):
            for name, value in list(vars(module).items()):
                if value is original:
                    monkeypatch.setattr(module, name, replacement)


def _counted(monkeypatch, original: Callable) -> list:
    """The arguments of every call of `original` from now on (it still does its work)."""
    calls = []

    def counting(*args, **kwargs):
        calls.append(args)
        return original(*args, **kwargs)

    _rebind(monkeypatch, original, counting)
    return calls


def test_an_evaluation_here_loads_its_catalog_once_and_resolves_each_tasks_files_once(
    short_catalog, tmp_path, monkeypatch
):
    spec = RunSpec.create("noop", catalog=short_catalog, episodes=2, conditions=("given", "shuffled"))
    loads = _counted(monkeypatch, catalog_module.load_catalog)
    resolved = _counted(monkeypatch, files_module.task_files)
    summary = evaluate(spec, tmp_path / "run", ExecutionOptions(workers=0, progress=False))
    assert (summary.ran, summary.gaps) == (12, 0)
    assert loads == [(short_catalog,)]  # the plan, the gate snapshot and the worker in this process share it
    assert sorted(task.id for (task,) in resolved) == sorted(spec.tasks)  # each task's files once, for 4 episodes
    catalog = catalog_module.load_catalog(short_catalog)
    # The scene the plan found for each task is the one its records carry.
    assert {(r["task_id"], r["scene"]) for r in store_rows(tmp_path / "run")} == {
        (t, scene_key(catalog.get(t))) for t in spec.tasks
    }


class FileRead(Exception):
    """The simulator read a task's file itself."""


def _file_readers() -> Iterator[Callable]:
    """Every function through which a task's files are read: the catalog's file modules', and the stack's."""
    for name in ("langgap.catalog.files", "langgap.catalog.packages"):
        module = importlib.import_module(name)
        for value in vars(module).values():
            if callable(value) and not isinstance(value, type) and getattr(value, "__module__", None) == name:
                yield value
    yield from (stack.bddl_path, stack.init_states_path, stack.load_init_states)


def test_the_simulator_runs_on_the_files_it_is_given_and_reads_none_itself(short_catalog, monkeypatch):
    catalog = catalog_module.load_catalog(short_catalog)
    first, sibling = catalog.tasks[:2]
    files, sibling_files = task_files(first), task_files(sibling)

    def refuse(*_args, **_kwargs):
        raise FileRead("a task's file was read")

    for reader in _file_readers():
        _rebind(monkeypatch, reader, refuse)
    with pytest.raises(FileRead):
        TaskEnv(first)  # left to itself, the simulator resolves the files: what it must not do when given them
    with TaskEnv(first, EnvOptions(), files) as env:
        env.reset(0, seed=0)
        env.step(np.zeros(7))
        assert env.can_switch_to(sibling, sibling_files)
        env.switch_task(sibling, sibling_files)
        env.reset(1, seed=1)
        assert env.task is sibling and env.files is sibling_files and env.init_states is sibling_files.init_states


@pytest.mark.parametrize("catalog", ["libero-pro", "libero-plus-language"])
def test_a_package_tasks_files_are_resolved_in_one_pass(catalog, monkeypatch):
    # One read and one SHA-256 check of the package's BDDL file gives the file LIBERO loads (installed, or
    # extracted from the wheel: written once), the check against the registry and the scene key.
    task = next(t for t in catalog_module.load_catalog(catalog).tasks if t.origin is not None)
    checked = _counted(monkeypatch, packages.checked_bytes)
    files = task_files(task)
    assert checked == [(task.origin,)]
    assert files.bddl.read_bytes() == packages.checked_bytes(task.origin)
    assert files.scene == scene_key(task)
