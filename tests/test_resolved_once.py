"""What an evaluation resolves once and hands down: each task's files (`TaskFiles`), resolved once per worker and
given to the simulator, which reads none itself."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from langgap import stack
from langgap.catalog import catalog as catalog_module
from langgap.catalog.files import task_files
from langgap.sim.env import EnvOptions, TaskEnv


def _rebind(monkeypatch, original: Callable, replacement: Callable) -> None:
    """Put `replacement` wherever a LangGap module holds `original` (its own module, and every module that
    imported it by name), for the rest of the test."""
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("langgap"):
            for name, value in list(vars(module).items()):
                if value is original:
                    monkeypatch.setattr(module, name, replacement)


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
