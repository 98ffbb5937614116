"""Child processes that end with the process that started them."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable


def exit_with_parent(parent_pid: int, cleanup: Callable[[], None] | None = None) -> None:
    """Exit this process (after `cleanup`) once `parent_pid` is no longer its parent.

    A watcher thread, so it also fires while the main thread is busy: a `kill -9` of `langgap eval`
    leaves no worker simulating and no policy process holding a GPU.
    """

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        if cleanup is not None:
            cleanup()
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="exit-with-parent").start()
