"""Report values as plain data (the JSON report): one walk over dataclasses, enumerations, paths, tuples and
mappings.

A dataclass gives its fields in order, unless its class says otherwise in a `DATA` spec: a tuple of entries,
each an attribute's name (a field or a property, under its own name), a `(key, attribute name)` or
`(key, function of the object)` pair, `FIELDS` (every field, in order) or `(MERGED, attribute or function)`
(the entries of the mapping it gives, in place). Values are walked again, so a row's rates and tests
become their own data.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import fields, is_dataclass
from enum import Enum
from pathlib import Path
from typing import Any

FIELDS = "*"  # in a `DATA` spec: every field of the dataclass, in order
MERGED = "**"  # as an entry's key: the entries of the mapping its value gives, in place

Entry = str | tuple[str, str | Callable[[Any], Any]]
Spec = tuple[Entry, ...]


def to_data(value: Any, spec: Spec | None = None) -> Any:
    """`value` as JSON-ready data: dataclasses by their `DATA` spec (or `spec`, given), enumerations by their
    value, paths as text, tuples as lists; mappings keep their keys."""
    if spec is not None or is_dataclass(value):
        return _entries(value, spec or getattr(value, "DATA", (FIELDS,)))
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, Mapping):
        return {key: to_data(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [to_data(item) for item in value]
    return value


def _entries(value: Any, spec: Spec) -> dict:
    out: dict = {}
    for entry in spec:
        if entry == FIELDS:
            out.update((f.name, to_data(getattr(value, f.name))) for f in fields(value))
            continue
        key, source = (entry, entry) if isinstance(entry, str) else entry
        item = getattr(value, source) if isinstance(source, str) else source(value)
        if key == MERGED:
            out.update(to_data(item))
        else:
            out[key] = to_data(item)
    return out
