"""The fast layer: pure code only, no simulator.

When the layer runs on its own (`./test.sh tests/unit`), importing the simulator stack is an error,
so a unit test that starts to need MuJoCo fails at once instead of quietly making the layer slow.
In a full run the other tests have loaded the stack already and the guard stays off.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
from pathlib import Path

HEAVY = ("mujoco", "robosuite", "libero", "torch", "ray")
_HERE = Path(__file__).parent


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


def pytest_collection_modifyitems(session, config, items):
    alone = all(_HERE in Path(item.fspath).parents for item in items)
    if alone and not any(m in sys.modules for m in HEAVY):
        sys.meta_path.insert(0, _BlockHeavy())
