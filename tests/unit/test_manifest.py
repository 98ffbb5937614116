"""A collection's `collection.json` is checked when read: what every reader needs is there, or one error."""

from __future__ import annotations

import json

import pytest

from langgap.demos.compact import DemoFileError, read_manifest


@pytest.mark.parametrize(
    ("manifest", "problem"),
    [
        ({}, "no catalog, demos, tasks"),
        ([], "a JSON list, not an object"),
        ({"catalog": "langgap99", "demos": 12}, "no tasks"),
        ({"catalog": "langgap99", "demos": 12, "tasks": {"spatial/s0/x": {"attempts": 3}}}, "`tasks` is not"),
        ({"catalog": "langgap99", "demos": 12, "tasks": ["spatial/s0/x"]}, "`tasks` is not"),
    ],
)
def test_a_manifest_without_what_readers_need_is_one_clear_error(tmp_path, manifest, problem):
    (tmp_path / "collection.json").write_text(json.dumps(manifest))
    with pytest.raises(DemoFileError, match="is not a collection's manifest") as raised:
        read_manifest(tmp_path)
    assert problem in str(raised.value) and "langgap collect" in str(raised.value)


def test_a_whole_manifest_is_read_as_written(tmp_path):
    manifest = {"catalog": "langgap99", "demos": 2, "tasks": {"spatial/s0/x": {"kept": [1000, 1003]}}, "seed": 1000}
    (tmp_path / "collection.json").write_text(json.dumps(manifest))
    assert read_manifest(tmp_path) == manifest
