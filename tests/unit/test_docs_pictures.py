"""The documentation's pictures are as new as the code they show: each PNG carries the fingerprint of its
source files (tools/picture_stamps.py), and one whose stamp is missing or differs fails here, naming the
command that regenerates it (tools/docs_pictures.py, a developer command: it runs the simulator)."""

from __future__ import annotations

import shutil
import struct
import zlib

from tools.picture_stamps import (
    PICTURES,
    REPO,
    fingerprint,
    read_stamp,
    source_digests,
    staleness,
    stamp_file,
    stamped,
)


def _png() -> bytes:
    """A valid 1×1 grey PNG with no text chunk."""

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0))
    return b"\x89PNG\r\n\x1a\n" + header + chunk(b"IDAT", zlib.compress(b"\0\x80")) + chunk(b"IEND", b"")


def test_every_picture_of_the_docs_is_stamped_with_the_code_it_shows():
    stale = [why for picture in PICTURES if (why := staleness(picture))]
    assert not stale, "\n".join(stale)


def test_a_picture_without_a_stamp_or_older_than_its_code_is_stale(tmp_path):
    # The report picture's real sources, copied, and a picture for them.
    picture = next(p for p in PICTURES if p.path == "docs/report.png")
    for source in source_digests(picture):
        (tmp_path / source).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(REPO / source, tmp_path / source)
    assert "is missing" in staleness(picture, tmp_path)
    image = tmp_path / picture.path
    image.parent.mkdir()
    image.write_bytes(_png())
    assert read_stamp(image.read_bytes()) is None
    why = staleness(picture, tmp_path)
    assert why.startswith("docs/report.png carries no stamp") and "`python -m tools.docs_pictures report`" in why
    # Stamped with its sources' fingerprint, it is current; stamping again replaces the stamp.
    stamp_file(image, "an old fingerprint")
    assert "is older than the code it shows" in staleness(picture, tmp_path)
    stamp_file(image, fingerprint(picture, tmp_path))
    assert staleness(picture, tmp_path) is None
    assert stamped(image.read_bytes(), "x").count(b"LangGap-sources-SHA256") == 1
    # A comment edited in the code the picture shows makes it stale.
    html = tmp_path / "src/langgap/report/html.py"
    html.write_text(html.read_text() + "# a comment\n")
    why = staleness(picture, tmp_path)
    assert why.startswith("docs/report.png is older than the code it shows (src/langgap/report/**/*, ")
    assert "`python -m tools.docs_pictures report`" in why
