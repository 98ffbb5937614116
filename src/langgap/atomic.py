"""Writing a file so that no reader ever sees it half-written."""

from __future__ import annotations

import os
import secrets
from pathlib import Path


def write_text_atomically(path: Path, text: str) -> None:
    """Write `text` to `path` through a new file beside it and a rename.

    Concurrent readers (workers, another run) see the old file or the new one, never a part. The new
    file is created like any other (mode 0o666 less the umask), not owner-only as `tempfile`'s are.
    """
    write_bytes_atomically(path, text.encode("utf-8"))


def write_bytes_atomically(path: Path, data: bytes) -> None:
    """Write `data` to `path` as `write_text_atomically` writes text."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.{secrets.token_hex(8)}.tmp")
    with open(os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "wb") as out:
        out.write(data)
    os.replace(partial, path)
