"""Starting and stopping real server processes on 127.0.0.1 for tests."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import langgap
from langgap.policies.openpi import wait_for_health

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
SRC = Path(langgap.__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def subprocess_env(**extra: str) -> dict[str, str]:
    """This interpreter's environment with this LangGap source and the `tests` package importable."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC), str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


@contextlib.contextmanager
def running(
    command: list[str], port: int, env: dict[str, str] | None = None, startup: float = 30, host: str = "127.0.0.1"
) -> Iterator[subprocess.Popen]:
    """Run a server command, wait up to `startup` seconds until it answers on `host:port`, and kill it on exit."""
    process = subprocess.Popen(
        command, env=env or subprocess_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        try:
            wait_for_health(host, port, time.monotonic() + startup)
        except Exception:
            process.kill()
            raise RuntimeError(f"server did not start: {process.communicate(timeout=10)[1][-2000:]}") from None
        yield process
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=10)
        if process.stderr:
            process.stderr.close()


def langgap_serve(port: int, policy: str, *pairs: str) -> list[str]:
    """The `langgap serve` command line for `policy` with `--policy-arg` pairs."""
    args = [arg for pair in pairs for arg in ("--policy-arg", pair)]
    return [sys.executable, "-m", "langgap.cli.main", "serve", "--policy", policy, *args, "--port", str(port)]


def helper_server(mode: str, port: int, *rest: str) -> list[str]:
    """The command line of a test server from `tests/support/openpi_servers.py`."""
    return [sys.executable, "-m", "tests.support.openpi_servers", mode, str(port), *rest]
