"""Merge LeRobot datasets into one with LeRobot's own aggregation (`lerobot.datasets.aggregate`).

LeRobot aggregates only datasets of the same fps label, robot type and features; this module says which of
those differ, in one line, before LeRobot is asked. LangGap's exports carry the label of the LIBERO datasets
users train on (`export.FPS`), so an extended-task dataset merges with an originals dataset in the
`lerobot/libero` schema. Needs LeRobot (the LeRobot environment).
"""

from __future__ import annotations

import json
from pathlib import Path

from langgap.errors import DependencyNotInstalled, LangGapError

_INFO = Path("meta") / "info.json"
# What LeRobot's aggregation compares (its `validate_all_metadata`); video encoding details are not compared.
_COMPARED = ("fps", "robot_type")


def _info(root: Path) -> dict:
    try:
        return json.loads((root / _INFO).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise LangGapError(f"{root} is not a LeRobot dataset ({_INFO}: {exc})") from None


def _schema(feature: dict) -> dict:
    return {k: v for k, v in feature.items() if k != "info"}


def incompatibilities(roots: list[Path]) -> list[str]:
    """How each dataset after the first differs from the first in what LeRobot's aggregation requires to match."""
    first, *rest = [_info(r) for r in roots]
    problems = []
    for root, info in zip(roots[1:], rest, strict=True):
        for key in _COMPARED:
            if info.get(key) != first.get(key):
                problems.append(f"{root}: {key} {info.get(key)!r}, not {first.get(key)!r} as in {roots[0]}")
        ours, theirs = first["features"], info["features"]
        for name in sorted(set(ours) ^ set(theirs)):
            problems.append(f"{root}: feature {name} is in only one of the datasets")
        for name in sorted(set(ours) & set(theirs)):
            if _schema(ours[name]) != _schema(theirs[name]):
                problems.append(f"{root}: feature {name} is {_schema(theirs[name])}, not {_schema(ours[name])}")
    return problems


def merge_lerobot_datasets(
    sources: list[str | Path], out: str | Path, *, repo_id: str = "local/langgap_merged"
) -> Path:
    """Aggregate the LeRobot datasets at `sources` into a new dataset at `out` (LeRobot's `aggregate_datasets`:
    episodes, tasks, videos and statistics); returns `out`."""
    roots = [Path(s) for s in sources]
    out = Path(out)
    if len(roots) < 2:
        raise LangGapError("merging needs at least two datasets")
    if out.exists():
        raise LangGapError(f"{out} exists already; remove it to merge again")
    problems = incompatibilities(roots)
    if problems:
        raise LangGapError(f"LeRobot cannot aggregate these datasets: {'; '.join(problems)}")
    try:
        from lerobot.datasets.aggregate import aggregate_datasets
    except ImportError:
        raise DependencyNotInstalled(
            "LeRobot is not installed; run this in .venv-lerobot (./setup.sh makes it)"
        ) from None
    aggregate_datasets(
        repo_ids=[f"local/source_{i}" for i in range(len(roots))], aggr_repo_id=repo_id, roots=roots, aggr_root=out
    )
    return out
