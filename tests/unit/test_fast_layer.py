"""The fast layer alone imports no simulator and no PyTorch: collecting it loads none of them, skips no module
(a module skipped for a refused import would hide its tests), and leaves the guard of `conftest.py` on."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.unit.conftest import HEAVY

UNIT = Path(__file__).resolve().parent

_COLLECT = """
import json, sys
import pytest

skipped = []


class Skips:
    def pytest_collectreport(self, report):
        if report.skipped:
            skipped.append(report.nodeid)


code = pytest.main(["--collect-only", "-q", "-p", "no:cacheprovider", sys.argv[1]], plugins=[Skips()])
try:
    import mujoco  # noqa: F401
    guarded = False
except ImportError as exc:
    guarded = "fast test layer" in str(exc)
loaded = sorted(m for m in sys.argv[2:] if m in sys.modules)
print("COLLECTED", json.dumps({"code": int(code), "loaded": loaded, "skipped": skipped, "guarded": guarded}))
"""


def test_collecting_the_fast_layer_alone_loads_no_simulator_and_no_torch():
    result = subprocess.run(
        [sys.executable, "-c", _COLLECT, str(UNIT), *HEAVY],
        cwd=UNIT.parents[1],
        capture_output=True,
        text=True,
        timeout=300,
    )
    line = next((line for line in result.stdout.splitlines() if line.startswith("COLLECTED ")), None)
    assert line is not None, result.stdout[-2000:] + result.stderr[-2000:]
    found = json.loads(line.removeprefix("COLLECTED "))
    assert found["code"] == 0, result.stdout[-2000:]
    assert found["loaded"] == []
    assert found["skipped"] == []
    assert found["guarded"]
