"""Where LangGap keeps files it makes or fetches once: generated BDDL files, downloaded package files."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """Where generated files go (`$LANGGAP_CACHE`, else `$XDG_CACHE_HOME/langgap`, else `~/.cache/langgap`)."""
    if os.environ.get("LANGGAP_CACHE"):
        return Path(os.environ["LANGGAP_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "langgap"
