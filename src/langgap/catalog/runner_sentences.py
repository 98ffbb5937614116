"""What the field's own runners send as a task's instruction, computed as their packages compute it.

A LIBERO-style runner (openpi's LIBERO example, OpenVLA's) sends `task.language` from its package's
`libero.libero.benchmark`, not the BDDL file's `(:language)`:

- LIBERO's and LIBERO-PRO's `grab_language_from_filename` make it of the file's *name*. LIBERO-PRO's `_lan` and
  `_task` files carry their original's name, so its runners send the original's sentence for both.
- LIBERO-Plus's makes it of the `(:language)` of a `_language_N` file, read by bddl's `scan_tokens`: lowercased,
  with everything after a `;` on a line cut off as a comment, and the word `task` when that leaves the file
  unparsable. Its runner reaches a file only when its `libero_suite_task_map` registers it.

The registry keeps each sentence as the task's `package` instruction (`langgap generate`), and tests check these
functions against the packages' own on every file.
"""

from __future__ import annotations

import ast
import functools

from bddl.parsing import scan_tokens

from langgap.catalog import packages
from langgap.errors import CatalogError

# The word LIBERO-Plus's `get_problem_info` falls back to when a file does not parse.
PLUS_FALLBACK = "task"
_PLUS_TASK_MAP = "liberoplus/liberoplus/benchmark/libero_suite_task_map.py"


def file_name_sentence(file_name: str) -> str:
    """`task.language` as LIBERO's and LIBERO-PRO's `grab_language_from_filename` make it of a BDDL file's name
    (libero_10's and libero_90's names lose their `..._SCENE<n>_` prefix)."""
    name = file_name.rsplit("/", 1)[-1]
    if name[0].isupper():
        start = name.find("SCENE") + (8 if "SCENE10" in name else 7)
        name = name[start:]
    words = " ".join(name.split("_"))
    return words[: words.find(".bddl")]


def plus_sentence(text: str) -> str:
    """`task.language` as LIBERO-Plus's benchmark makes it of a `_language_N` BDDL file's `text`: the
    `(:language)` tokens as bddl's `scan_tokens` reads them, joined by spaces; `PLUS_FALLBACK` when the file
    does not parse or names no problem."""
    try:
        tokens = scan_tokens(string=text)
    except Exception:  # scan_tokens raises bare Exceptions; LIBERO-Plus catches them all the same way
        return PLUS_FALLBACK
    if not isinstance(tokens, list) or not tokens or tokens[0] != "define":
        return PLUS_FALLBACK
    problem, language = "unknown", []
    for group in tokens[1:]:
        if group and group[0] == "problem":
            problem = group[-1]
        elif group and group[0] == ":language":
            language = group[1:]
    return " ".join(language) if problem != "unknown" else PLUS_FALLBACK


@functools.cache
def plus_registered() -> dict[str, frozenset[str]]:
    """Per suite, the `_language_N` files (their names without `.bddl`) that LIBERO-Plus's runner reaches: those
    its `libero_suite_task_map` registers (as `<file>_view_..._initstate_0`)."""
    source = packages.plus_wheel().read(_PLUS_TASK_MAP).decode("utf-8")
    try:
        tree = ast.parse(source)
        node = next(
            n.value
            for n in tree.body
            if isinstance(n, ast.Assign) and any(getattr(t, "id", None) == "libero_task_map" for t in n.targets)
        )
        task_map = ast.literal_eval(node)
    except (SyntaxError, ValueError, StopIteration) as exc:
        raise CatalogError(f"cannot read LIBERO-Plus's task map {_PLUS_TASK_MAP}: {exc}") from None
    return {
        suite: frozenset(name.split("_view_")[0] for name in names if "_language_" in name)
        for suite, names in task_map.items()
    }


def is_plus_registered(suite: str, file: str) -> bool:
    """Whether LIBERO-Plus's runner reaches the `_language_N` BDDL `file` (a path inside the wheel) of `suite`."""
    stem = file.rsplit("/", 1)[-1].removesuffix(".bddl")
    return stem in plus_registered().get(suite, frozenset())
