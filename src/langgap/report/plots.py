"""Figures: per-dimension success with 95 % intervals (runs side by side) and per-scene confusion matrices."""

from __future__ import annotations

from pathlib import Path

from langgap.report.labels import DIMENSION_LABEL, label
from langgap.report.summary import RunResults, Summary, shown_dimensions
from langgap.vocabulary import TaskKind


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def dimension_plot(summary: Summary, out: Path) -> Path:
    """Success per dimension (and on the originals) with 95 % intervals, runs side by side."""
    plt = _pyplot()
    groups = [TaskKind.ORIGINAL, *shown_dimensions(summary.runs)]
    fig, ax = plt.subplots(figsize=(8, 4))
    runs = summary.runs
    width = 0.8 / max(1, len(runs))
    for i, run in enumerate(runs):
        rates = {r.group: r for r in run.by_dimension} | {TaskKind.ORIGINAL: run.source(TaskKind.ORIGINAL)}
        xs, ys, errs = [], [], [[], []]
        for j, name in enumerate(groups):
            r = rates.get(name)
            if r is None or r.episodes == 0:
                continue
            low, high = r.ci
            xs.append(j + (i - (len(runs) - 1) / 2) * width)
            ys.append(100 * r.rate)
            errs[0].append(100 * (r.rate - low))
            errs[1].append(100 * (high - r.rate))
        ax.bar(xs, ys, width, yerr=errs, capsize=3, label=run.label)
    ax.set_xticks(range(len(groups)), [label(DIMENSION_LABEL, g) for g in groups], rotation=15)
    ax.set_ylabel("success rate (%), 95% Wilson CI")
    ax.set_ylim(0, 105)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "success_by_dimension.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def confusion_plots(run: RunResults, out: Path) -> list[Path]:
    """One heatmap per scene with two or more tasks: intended × achieved episode counts."""
    plt = _pyplot()
    paths = []
    for rows in run.confusion.values():
        intended = sorted(rows)
        if len(intended) < 2:
            continue
        columns = intended + sorted({a for row in rows.values() for a in row} - set(intended))
        matrix = [[rows[t].get(c, 0) for c in columns] for t in intended]
        short = [c.split("/")[-1] for c in columns]
        fig, ax = plt.subplots(figsize=(1.2 + 0.45 * len(columns), 1.2 + 0.4 * len(intended)))
        ax.imshow(matrix, cmap="Blues")
        ax.set_xticks(range(len(columns)), short, rotation=60, ha="right", fontsize=7)
        ax.set_yticks(range(len(intended)), [t.split("/")[-1] for t in intended], fontsize=7)
        for y, row in enumerate(matrix):
            for x, value in enumerate(row):
                if value:
                    ax.text(x, y, str(value), ha="center", va="center", fontsize=7)
        ax.set_xlabel("achieved")
        ax.set_ylabel("intended")
        scene = "_".join(intended[0].split("/")[:2])
        ax.set_title(f"{run.label}: {scene}", fontsize=8)
        fig.tight_layout()
        path = out / f"confusion_{scene}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def write_plots(summary: Summary, out: str | Path) -> list[Path]:
    """Write the figures of a report to the folder `out`; returns their paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    return [dimension_plot(summary, out), *confusion_plots(summary.runs[0], out)]
