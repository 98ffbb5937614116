"""Figures: per-dimension success with 95 % intervals (runs side by side) and per-scene confusion matrices."""

from __future__ import annotations

from pathlib import Path

from langgap.report import aggregate as agg
from langgap.report.render import Run


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def dimension_plot(runs: list[Run], out: Path) -> Path:
    plt = _pyplot()
    groups = ["Original", *(agg.DIMENSION_LABEL[d] for d in agg.DIMENSION_ORDER)]
    fig, ax = plt.subplots(figsize=(8, 4))
    width = 0.8 / max(1, len(runs))
    for i, run in enumerate(runs):
        rates = {agg.DIMENSION_LABEL[r.group]: r for r in agg.by_dimension(run.records)}
        rates["Original"] = agg.by_source(run.records)[0]
        xs, ys, errs = [], [], [[], []]
        for j, name in enumerate(groups):
            r = rates.get(name)
            if r is None or r.episodes == 0:
                continue
            xs.append(j + (i - (len(runs) - 1) / 2) * width)
            ys.append(100 * r.rate)
            errs[0].append(100 * (r.rate - r.ci_low))
            errs[1].append(100 * (r.ci_high - r.rate))
        ax.bar(xs, ys, width, yerr=errs, capsize=3, label=run.name)
    ax.set_xticks(range(len(groups)), groups, rotation=15)
    ax.set_ylabel("success rate (%), 95% Wilson CI")
    ax.set_ylim(0, 105)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "success_by_dimension.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def confusion_plots(run: Run, out: Path) -> list[Path]:
    plt = _pyplot()
    paths = []
    for rows in agg.confusion(run.records).values():
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
        label = "_".join(intended[0].split("/")[:2])
        ax.set_title(f"{run.name}: {label}", fontsize=8)
        fig.tight_layout()
        path = out / f"confusion_{label}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def write_plots(runs: list[Run], out: str | Path) -> list[Path]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    return [dimension_plot(runs, out), *confusion_plots(runs[0], out)]
