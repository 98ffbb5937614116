"""The per-episode table, for pandas and friends (CSV always; Parquet when pyarrow is installed)."""

from __future__ import annotations

import csv
import json
from dataclasses import asdict, fields
from pathlib import Path

from langgap.errors import DependencyNotInstalled, LangGapError
from langgap.records import EpisodeRecord, achieved
from langgap.report.load import load_runs

COLUMNS = ["run", *(f.name for f in fields(EpisodeRecord)), "achieved"]


def episode_rows(paths: list[str | Path]) -> list[dict]:
    rows = []
    for run in load_runs(paths):
        for record in run.records:
            data = asdict(record)
            for key in ("reached", "goals_at_start", "goals_at_end", "physics"):
                data[key] = json.dumps(data[key], sort_keys=True)
            # Every instruction sent, [[step, instruction], ...] (an older store's: its one instruction at step 0).
            data["instructions"] = json.dumps(record.timeline)
            rows.append({"run": run.name, **data, "achieved": achieved(record)})
    return rows


def write_episode_table(paths: list[str | Path], out: str | Path) -> Path:
    """Write every episode of the runs to `out` (.csv or .parquet)."""
    out = Path(out)
    rows = episode_rows(paths)
    if out.suffix == ".csv":
        with out.open("w", newline="", encoding="utf-8") as handle:
            writer = csv.DictWriter(handle, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
    elif out.suffix == ".parquet":
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise DependencyNotInstalled(
                "Parquet output needs pyarrow (pip install pyarrow); or use a .csv file"
            ) from None
        pq.write_table(pa.Table.from_pylist(rows), out)
    else:
        raise LangGapError(f"episode table must end in .csv or .parquet, got {out.name}")
    return out
