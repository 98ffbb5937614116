"""Files written through a temporary file and a rename."""

from __future__ import annotations

import stat

from langgap.atomic import write_text_atomically


def test_a_file_written_atomically_replaces_the_old_one_with_plain_permissions(tmp_path):
    path = tmp_path / "registry" / "catalog.gate.json"
    write_text_atomically(path, "old\n")
    write_text_atomically(path, "new\n")
    assert path.read_text() == "new\n"
    assert [p.name for p in path.parent.iterdir()] == [path.name]  # no temporary file left behind
    plain = tmp_path / "plain"
    plain.write_text("")  # what `open` gives under this process's umask (a temporary file: owner-only)
    assert stat.S_IMODE(path.stat().st_mode) == stat.S_IMODE(plain.stat().st_mode)
