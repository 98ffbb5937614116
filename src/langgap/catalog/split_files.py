"""Split files: a `Split` (a named selection of a catalog's tasks into training and held-out tasks, tied to the
catalog's registry by its SHA-256), and where splits are stored: shipped ones in `registry/splits/`, one's own
at a path. How splits are made and checked is `langgap.catalog.splits`; the catalog's selection reads a split
term (`split:NAME:PART`) from here.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path

from langgap.atomic import write_text_atomically
from langgap.catalog.task import DEFAULT_STYLE
from langgap.errors import CatalogError

SPLIT_KINDS = ("instruction", "compositional", "novel-word")
PARTS = ("train", "heldout")


@dataclass(frozen=True)
class Split:
    """A named selection of catalog `catalog`'s tasks (its registry's SHA-256 `catalog_sha256` when made) into
    `train` and `heldout` task ids, made by `rule` (the generator's inputs: selection, seed, sizes, style).
    `subsets` maps a size k to the nested subset of k training tasks (each a prefix of the next)."""

    name: str
    kind: str
    catalog: str
    catalog_sha256: str
    train: tuple[str, ...]
    heldout: tuple[str, ...]
    rule: dict = field(default_factory=dict)
    subsets: dict[int, tuple[str, ...]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.kind not in SPLIT_KINDS:
            raise CatalogError(f"split {self.name}: kind {self.kind!r} is not one of {', '.join(SPLIT_KINDS)}")
        object.__setattr__(self, "train", tuple(self.train))
        object.__setattr__(self, "heldout", tuple(self.heldout))
        object.__setattr__(self, "subsets", {int(k): tuple(v) for k, v in self.subsets.items()})

    @property
    def style(self) -> str:
        """The instruction style whose sentences the split's word rules read."""
        return self.rule.get("style", DEFAULT_STYLE)

    def part(self, part: str) -> tuple[str, ...]:
        """The task ids of `part`: `train`, `heldout`, or a number k (the nested subset of k training tasks)."""
        if part in PARTS:
            return getattr(self, part)
        if part.isdigit() and int(part) in self.subsets:
            return self.subsets[int(part)]
        sizes = ", ".join(map(str, sorted(self.subsets))) or "none stored"
        raise CatalogError(f"split {self.name} has no part {part!r} (train, heldout, or a subset size: {sizes})")

    def to_dict(self) -> dict:
        """The split's JSON form (as stored)."""
        data = asdict(self)
        data["train"], data["heldout"] = list(self.train), list(self.heldout)
        data["subsets"] = {str(k): list(v) for k, v in sorted(self.subsets.items())}
        return data


# -- storage ------------------------------------------------------------------------------------------------


def shipped_dir() -> Path:
    """Where the splits that ship with LangGap are stored."""
    return Path(str(resources.files("langgap.catalog") / "registry" / "splits"))


def available_splits() -> list[str]:
    """Names of the shipped splits."""
    return sorted(p.stem for p in shipped_dir().glob("*.json"))


def split_path(name: str) -> Path:
    """The file of split `name`: a shipped split's name, or the path of a split file (`.json`, or holding `/`)."""
    if name.endswith(".json") or "/" in name:
        return Path(name)
    if name not in available_splits():
        raise CatalogError(f"unknown split {name!r} (shipped: {', '.join(available_splits())}; or a split file)")
    return shipped_dir() / f"{name}.json"


def load_split(name: str) -> Split:
    """The split `name` (a shipped name or a file's path), read from its JSON file."""
    path = split_path(name)
    try:
        return Split(**json.loads(path.read_text(encoding="utf-8")))
    except (OSError, json.JSONDecodeError, TypeError) as exc:
        raise CatalogError(f"cannot read split {path}: {exc}") from None


def save_split(split: Split, path: str | Path) -> Path:
    """Write `split` as JSON to `path` (atomically)."""
    path = Path(path)
    write_text_atomically(path, json.dumps(split.to_dict(), indent=1) + "\n")
    return path
