"""The documentation's pictures, the code each one shows, and the stamp that says which code made it.

A picture is stale when the code whose output it shows has changed since it was taken. Each picture
carries a stamp: a PNG tEXt chunk `LangGap-sources-SHA256` holding the fingerprint of its source files
(`fingerprint`). `tools/docs_pictures.py` writes it; `tests/unit/test_docs_pictures.py` recomputes it
and fails, naming the command that regenerates the picture, when the two differ or the stamp is missing.

Standard library only: the guard test runs in the fast layer.
"""

from __future__ import annotations

import hashlib
import re
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
STAMP_KEY = b"LangGap-sources-SHA256"
MAKER = "tools/docs_pictures.py"
_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class Picture:
    """One picture of the documentation and the files whose output it shows."""

    path: str  # the PNG, relative to the repository root
    group: str  # the argument of tools.docs_pictures that regenerates it
    sources: tuple[str, ...]  # glob patterns relative to the root (`__pycache__` is never a source)

    @property
    def command(self) -> str:
        """The command that regenerates the picture, run from the repository root."""
        return f"python -m tools.docs_pictures {self.group}"


# The report's pictures show the page the report package writes (its Python and the published figures it
# prints) as the maker screenshots it; reflection.png shows the environment's renders (TaskEnv: its steps,
# render path and reflection switch) as bench_render.py lays them out (on | off | difference).
_REPORT = ("src/langgap/report/**/*", MAKER)
PICTURES = (
    Picture("docs/report.png", "report", _REPORT),
    Picture("docs/report-gallery.png", "report", _REPORT),
    Picture("docs/reflection.png", "reflection", ("src/langgap/sim/env.py", "bench/bench_render.py", MAKER)),
)


# The quick start's `langgap report --summary`, printed by the command that makes the report's pictures (so it is
# as new as they are: it carries their stamp, its first line). The README quotes it, and a test checks that what
# the README shows is in it (tests/unit/test_readme_outputs.py).
QUICK_START_SUMMARY = "tests/unit/report_outputs/quickstart.summary.md"
_TEXT_STAMP = re.compile(f"<!-- {STAMP_KEY.decode()}: ([0-9a-f]+) -->\n")


def stamped_text(text: str, stamp: str) -> str:
    """A stored output with `stamp` as its first line."""
    return f"<!-- {STAMP_KEY.decode()}: {stamp} -->\n{text}"


def read_text_stamp(text: str) -> tuple[str | None, str]:
    """The stamp of a stored output (None when it carries none) and the output after it."""
    if match := _TEXT_STAMP.match(text):
        return match[1], text[match.end() :]
    return None, text


class PictureError(Exception):
    """A picture cannot be made, stamped or checked (a failed run, a source pattern that matches no file, ...)."""


def source_digests(picture: Picture, root: Path = REPO) -> dict[str, str]:
    """SHA-256 of each source file of `picture` under `root`, by path relative to it (sorted)."""
    digests = {}
    for pattern in picture.sources:
        matched = [
            path for path in root.glob(pattern) if path.is_file() and "__pycache__" not in path.relative_to(root).parts
        ]
        if not matched:
            raise PictureError(f"{picture.path}: the source pattern {pattern!r} matches no file under {root}")
        for path in matched:
            digests[path.relative_to(root).as_posix()] = hashlib.sha256(path.read_bytes()).hexdigest()
    return dict(sorted(digests.items()))


def fingerprint(picture: Picture, root: Path = REPO) -> str:
    """The SHA-256 over the source files of `picture` (path and content of each): the stamp it must carry."""
    digest = hashlib.sha256()
    for path, content in source_digests(picture, root).items():
        digest.update(f"{path}\0{content}\n".encode())
    return digest.hexdigest()


def _chunks(data: bytes) -> list[tuple[bytes, bytes, int, int]]:
    """(type, body, start, end) of every chunk of a PNG file's bytes."""
    if not data.startswith(_SIGNATURE):
        raise PictureError("not a PNG file")
    chunks, start = [], len(_SIGNATURE)
    while start < len(data):
        (length,) = struct.unpack(">I", data[start : start + 4])
        kind = data[start + 4 : start + 8]
        end = start + 12 + length
        chunks.append((kind, data[start + 8 : start + 8 + length], start, end))
        start = end
    return chunks


def read_stamp(data: bytes) -> str | None:
    """The fingerprint stamped in a PNG file's bytes, None when it carries none."""
    for kind, body, _, _ in _chunks(data):
        key, _, text = body.partition(b"\0")
        if kind == b"tEXt" and key == STAMP_KEY:
            return text.decode("latin-1")
    return None


def stamped(data: bytes, stamp: str) -> bytes:
    """A PNG file's bytes with `stamp` as its only stamp (a tEXt chunk right after the header)."""
    body = STAMP_KEY + b"\0" + stamp.encode("latin-1")
    chunk = struct.pack(">I", len(body)) + b"tEXt" + body + struct.pack(">I", zlib.crc32(b"tEXt" + body))
    parts = [_SIGNATURE]
    for kind, body_of, start, end in _chunks(data):
        if kind == b"tEXt" and body_of.partition(b"\0")[0] == STAMP_KEY:
            continue
        parts.append(data[start:end])
        if kind == b"IHDR":
            parts.append(chunk)
    return b"".join(parts)


def stamp_file(path: Path, stamp: str) -> None:
    """Stamp the PNG file at `path` in place."""
    path.write_bytes(stamped(path.read_bytes(), stamp))


def staleness(picture: Picture, root: Path = REPO) -> str | None:
    """Why `picture` under `root` is stale (missing, unstamped, or stamped for other sources), with the
    command that regenerates it; None when its stamp is the fingerprint of its sources as they are."""
    path = root / picture.path
    stamp = read_stamp(path.read_bytes()) if path.is_file() else None
    if stamp == fingerprint(picture, root):
        return None
    if not path.is_file():
        why = "is missing"
    elif stamp is None:
        why = "carries no stamp of the code it shows"
    else:
        why = "is older than the code it shows"
    return (
        f"{picture.path} {why} ({', '.join(picture.sources)}): regenerate it with `{picture.command}` "
        "from the repository root (see docs/development.md, 'The documentation's pictures')"
    )
