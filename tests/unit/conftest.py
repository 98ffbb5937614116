"""The fast layer: pure code only, no simulator.

When the layer runs on its own (`./test.sh --fast`, or paths under tests/unit), importing the simulator stack
or PyTorch is an error from the start, collection included, so a unit test that starts to need MuJoCo fails at
once instead of quietly making the layer slow (and a test module that imports one lies in tests/, not here).
In a full run the other tests load the stack and the guard stays off.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
from pathlib import Path

HEAVY = ("mujoco", "robosuite", "libero", "torch", "ray")
_HERE = Path(__file__).resolve().parent


class _Refuse(importlib.abc.Loader):
    def create_module(self, spec):
        raise ImportError(f"the fast test layer may not import {spec.name}")

    def exec_module(self, module):  # never reached: create_module refuses
        raise ImportError(module.__name__)


class _BlockHeavy(importlib.abc.MetaPathFinder):
    """Finds the simulator stack's packages (so their data files can be located) but refuses to load them."""

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] not in HEAVY:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is not None:
            spec.loader = _Refuse()
        return spec


def pytest_configure(config):
    # Decided from the paths asked for, before any test module is imported: a module-level import of a heavy
    # package (or `pytest.importorskip` of one) must meet the guard, not switch it off.
    asked = [(config.invocation_params.dir / str(arg).split("::")[0]).resolve() for arg in config.args]
    if asked and all(path == _HERE or _HERE in path.parents for path in asked):
        sys.meta_path.insert(0, _BlockHeavy())
