"""The diversity sweep's table and figure, from the pooled tables experiments/diversity_sweep.sh writes.

    python experiments/diversity_plot.py OUT [--figure PNG] [--beside LABEL=DIR ...] [--label LABEL]

Reads OUT/pooled-<set>.json (`langgap report --pool --format json` of each set: compositional, novel-word,
trained; one pool per K and width, labelled `k<K>-d<W>`, its runs the training seeds, and `blind`) and writes
OUT/sweep.md (a row per K and width: each set's success with its Wilson 95 % interval over the pooled episodes,
then each seed's successes) and the figure (default OUT/sweep.png: each set's success against K, a line per width,
the intervals as bars, `blind` dashed). A pool's report groups its episodes by the catalog's own split (original,
training, held-out), which is not the sweep's: here every group of a run is counted together. `--beside LABEL=DIR`
adds another sweep's points on the same tasks (e.g. `small-vla=runs/diversity_sweep_vla`: the same sweep with
another policy), as squares and as rows after OUT's, their width column naming LABEL; `--label` names OUT's own
policy in the legend.
"""

from __future__ import annotations

import argparse
import json
import re
from dataclasses import dataclass
from pathlib import Path

from langgap.report.pooled import DEFAULT_TASK
from langgap.report.stats import wilson

SETS = {"trained": "its own K trained tasks", "compositional": "compositional held-out (4 tasks)",
        "novel-word": "novel-word held-out (3 tasks)"}  # fmt: skip
LABEL = re.compile(r"k(?P<k>\d+)-d(?P<width>\d+)$")


@dataclass(frozen=True)
class Cell:
    """One pool on one set: every episode of its runs, and each run's successes and episodes in order."""

    successes: int
    episodes: int
    runs: tuple[tuple[int, int], ...]

    @property
    def rate(self) -> float:
        return self.successes / self.episodes if self.episodes else 0.0

    @property
    def interval(self) -> tuple[float, float]:
        return wilson(self.successes, self.episodes)

    def text(self) -> str:
        """`12.5 [5.4, 26.1]; 3, 1, 1 of 40`: pooled rate, interval, each run's successes (`3/40, 1/30` if sizes
        differ)."""
        low, high = self.interval
        sizes = {n for _, n in self.runs}
        counts = (
            ", ".join(str(s) for s, _ in self.runs) + f" of {sizes.pop()}"
            if len(sizes) == 1
            else ", ".join(f"{s}/{n}" for s, n in self.runs)
        )
        return f"{100 * self.rate:.1f} [{100 * low:.1f}, {100 * high:.1f}]; {counts}"


def cells(pooled: dict) -> dict[str, Cell]:
    """Each pool's label -> its cell: the split groups of every run added up (the default-task group, a count of
    what failed episodes did instead, is not a success)."""
    out = {}
    for pool in pooled["pools"]:
        groups = [c for c in pool["cells"] if c["group"] != DEFAULT_TASK]
        runs = tuple(
            (sum(g["replicates"][i]["successes"] for g in groups), sum(g["replicates"][i]["episodes"] for g in groups))
            for i in range(len(pool["runs"]))
        )
        out[pool["label"]] = Cell(sum(s for s, _ in runs), sum(n for _, n in runs), runs)
    return out


def read(out: Path) -> dict[str, dict[str, Cell]]:
    """Set -> pool label -> cell, for each set whose pooled table exists."""
    return {
        s: cells(json.loads((out / f"pooled-{s}.json").read_text()))
        for s in SETS
        if (out / f"pooled-{s}.json").exists()
    }


def policies(table: dict[str, dict[str, Cell]]) -> list[tuple[int, int]]:
    """Every (K, width) some set holds, by width then K."""
    found = {(int(m["k"]), int(m["width"])) for by_label in table.values() for m in map(LABEL.match, by_label) if m}
    return sorted(found, key=lambda kw: (kw[1], kw[0]))


def markdown(table: dict[str, dict[str, Cell]], beside: dict[str, dict[str, dict[str, Cell]]] | None = None) -> str:
    """The sweep's table: `blind` first, then a row per width and K; then those of each sweep `beside` (label ->
    its table), the label in the width column."""
    head = "| K | width (d_model) | " + " | ".join(f"{SETS[s]} %" for s in SETS) + " |"
    lines = [head, "|" + "---|" * (2 + len(SETS))]

    def row(of: dict[str, dict[str, Cell]], k: str, width: str, label: str) -> str:
        texts = [of[s][label].text() if label in of.get(s, {}) else "–" for s in SETS]
        return f"| {k} | {width} | " + " | ".join(texts) + " |"

    lines.append(row(table, "`blind`", "–", "blind"))
    lines += [row(table, str(k), str(width), f"k{k}-d{width}") for k, width in policies(table)]
    for name, other in (beside or {}).items():
        lines += [row(other, str(k), f"{width}, {name}", f"k{k}-d{width}") for k, width in policies(other)]
    return "\n".join(lines) + "\n"


def seeds_text(points: list[tuple[int, Cell]]) -> str:
    """How many training seeds the points of one line pool: one number, or the range while a sweep runs."""
    counts = sorted({len(cell.runs) for _, cell in points})
    if len(counts) == 1:
        return f"{counts[0]} seed{'s' if counts[0] > 1 else ''}"
    return f"{counts[0]}–{counts[-1]} seeds per point"


def figure(
    table: dict[str, dict[str, Cell]],
    path: Path,
    beside: dict[str, dict[str, dict[str, Cell]]] | None = None,
    label: str | None = None,
) -> None:
    """A panel per set: success against K (log scale), a line per width with its intervals, `blind` dashed; each
    sweep `beside` (label -> its table) as squares, its label in the legend (and `label`, if given, OUT's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    own = f"{label}, " if label else ""
    lines = [(f"{own}d_model {w}", "o", table, w) for w in sorted({w for _, w in policies(table)})]
    for name, other in (beside or {}).items():
        lines += [(f"{name}, d_model {w}", "s", other, w) for w in sorted({w for _, w in policies(other)})]
    ks = sorted({k for _, _, of, _ in lines for k, _ in policies(of)})
    fig, axes = plt.subplots(1, len(SETS), figsize=(4.2 * len(SETS), 3.6), sharey=True)
    for ax, s in zip(axes, SETS, strict=True):
        for offset, (name, marker, of, width) in enumerate(lines):
            by_label = of.get(s, {})
            points = [(k, by_label[f"k{k}-d{width}"]) for k in ks if f"k{k}-d{width}" in by_label]
            if not points:
                continue
            shift = 1 + 0.06 * (offset - (len(lines) - 1) / 2)  # side by side, so every line's bars show
            x = [k * shift for k, _ in points]
            y = [100 * c.rate for _, c in points]
            low = [100 * (c.rate - c.interval[0]) for _, c in points]
            high = [100 * (c.interval[1] - c.rate) for _, c in points]
            ax.errorbar(x, y, yerr=[low, high], marker=marker, capsize=3, label=f"{name} ({seeds_text(points)})")
        by_label = table.get(s, {})
        if "blind" in by_label:
            ax.axhline(100 * by_label["blind"].rate, color="grey", linestyle="--", label="blind")
        ax.set_xscale("log")
        ax.set_xlim(0.7, 34)  # the split's subsets, 1 to 24 tasks, whichever have finished
        ax.set_xticks(ks or [1], [str(k) for k in ks] or ["1"])
        ax.minorticks_off()
        ax.set_xlabel("K: training tasks of the scene")
        ax.set_title(SETS[s], fontsize=10)
        ax.set_ylim(-3, 103)
    axes[0].set_ylabel("success % (Wilson 95 % interval)")
    axes[0].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the sweep's output directory")
    parser.add_argument("--figure", type=Path, help="where the PNG goes (default: OUT/sweep.png)")
    parser.add_argument(
        "--beside",
        action="append",
        default=[],
        metavar="LABEL=DIR",
        help="another sweep's OUT on the same tasks, drawn beside this one (e.g. small-vla=runs/diversity_sweep_vla)",
    )
    parser.add_argument("--label", help="OUT's policy, named in the figure's legend when --beside adds another")
    args = parser.parse_args(argv)
    beside = {}
    for item in args.beside:
        name, _, directory = item.partition("=")
        beside[name] = read(Path(directory)) if name and directory else {}
        if not beside[name]:
            parser.error(f"--beside {item}: expected LABEL=DIR, DIR a sweep's OUT with pooled tables")
    table = read(args.out)
    (args.out / "sweep.md").write_text(markdown(table, beside))
    figure(table, args.figure or args.out / "sweep.png", beside, args.label)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
