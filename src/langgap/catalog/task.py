"""The task record: one entry of a catalog registry file."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from langgap.bddl import Predicate
from langgap.catalog.verdicts import GateResult
from langgap.errors import CatalogError
from langgap.goals import Goal, goal_strings, witness
from langgap.vocabulary import Dimension, InstructionStyle, Split, TaskKind, words

# The words of `langgap.vocabulary` as the plain strings a task's fields, a spec and argparse's choices hold. An
# original task's dimension and split are its kind's word.
DIMENSIONS = words(Dimension)
SPLITS = words(Split)
# The styles every task has a sentence in; `package` only tasks read from a package have.
INSTRUCTION_STYLES = words((InstructionStyle.LIBERO, InstructionStyle.PAPER))
DEFAULT_STYLE = InstructionStyle.LIBERO.value
PACKAGE_STYLE = InstructionStyle.PACKAGE.value
RUN_STYLES = words(InstructionStyle)


@dataclass(frozen=True)
class Origin:
    """Where a task read from another benchmark's package comes from: its BDDL file inside `package`
    (`version`) and that file's SHA-256, and the init states file it ships (`init_file`, the SHA-256 of its
    states array); a task runs that BDDL file unchanged. `init_runs` says which file a run loads: `own` (the
    package's, an `.npz` inside LangGap's LIBERO package) or `source` (the source's, which the package's file
    equals array for array; a file LangGap would have to unpickle to read). `registered` says whether the
    package's own runner reaches the file (its task map lists it; None: the package registers every file)."""

    package: str
    version: str
    file: str
    sha256: str
    init_file: str
    init_sha256: str
    init_runs: str = "own"
    registered: bool | None = None

    def __post_init__(self) -> None:
        if self.init_runs not in ("own", "source"):
            raise CatalogError(f"origin of {self.file}: init_runs must be own or source, not {self.init_runs!r}")


@dataclass(frozen=True)
class Task:
    """A LangGap task: a goal and an instruction on the scene and init states of a LIBERO task.

    `scene_task` is the LIBERO task (suite + name + index) whose BDDL scene and 50 fixed init
    states the task uses; for an original task that is the task itself, for an extended task its
    `source`. `goal` is an expression of `langgap.goals` (for LIBERO's and the paper's tasks, a
    conjunction of atoms); `bddl_goal` is the conjunction its BDDL file states.

    `load_catalog` makes a task of each registry entry; a task checks its fields when it is made.

    Attributes:
        id: The task's id: its suite's short name, its scene and its name (`spatial/s0/black-bowl-1-on-plate`).
        catalog: The name of the catalog it belongs to.
        suite: Its LIBERO suite (`libero_spatial`, `libero_object`, `libero_goal`, `libero_10`).
        kind: Its `TaskKind`'s word: `original` (a LIBERO task) or `extended` (a task set on an original's scene
            and init states).
        dimension: What an extended task changes (one of `DIMENSIONS`: the paper's `change_object`,
            `change_target`, `spatial_description`, `drawer_action`, and the other catalogs'); `original`
            for an original.
        split: `train` or `heldout` for an extended task; `original` for an original.
        source: The id of the original task whose scene and init states it uses (its own for an original).
        scene_task: The LIBERO task whose BDDL scene and init states it uses (see above).
        scene_index: The scene's number in its suite (the `s0` of the id).
        goal: What the episode must achieve (see above).
        obj_of_interest: The objects the goal is about, as the BDDL file lists them.
        instructions: The instruction in each style (`libero`, `paper`; `package` for a task read from a
            package and its catalog's originals); `instruction(style)` reads one.
        max_steps: The episode's step limit.
        paper_id: The task's number in the paper (None: not one of the paper's tasks).
        notes: Remarks the registry keeps on the task.
        in_langgap99: True for a task of the paper's LangGap-99.
        gate: The feasibility gate's verdict (None: not validated by a feasibility gate).
        origin: Where a task read from another benchmark's package comes from (None: LangGap's own).
        gate_from: `catalog:task id` of a task whose gate trial this task's would repeat exactly (`SAME_TRIAL`),
            shown by the generator; the task takes that task's verdict and the gate never re-runs it. None: its
            own verdict.

    Raises:
        CatalogError: A kind, dimension or split that does not exist, or that disagree about being original; an
            instruction style without a sentence; a step limit that is not positive.
    """

    id: str
    catalog: str
    suite: str
    kind: str
    dimension: str
    split: str
    source: str
    scene_task: str
    scene_index: int
    goal: Goal
    obj_of_interest: tuple[str, ...]
    instructions: dict[str, str] = field(hash=False, compare=False)
    max_steps: int = 0
    paper_id: int | None = None
    notes: tuple[str, ...] = ()
    in_langgap99: bool = False
    gate: GateResult | None = None
    origin: Origin | None = None
    gate_from: str | None = None

    def __post_init__(self) -> None:
        checks = {
            "kind": (self.kind, tuple(TaskKind)),
            "dimension": (self.dimension, DIMENSIONS),
            "split": (self.split, SPLITS),
        }
        for name, (value, allowed) in checks.items():
            if value not in allowed:
                raise CatalogError(f"task {self.id}: {name} {value!r} is not one of {', '.join(allowed)}")
        missing = [s for s in INSTRUCTION_STYLES if not self.instructions.get(s)]
        if missing:
            raise CatalogError(f"task {self.id}: missing instruction style(s) {', '.join(missing)}")
        if len({value == TaskKind.ORIGINAL for value in (self.kind, self.dimension, self.split)}) > 1:
            raise CatalogError(f"task {self.id}: kind, dimension and split disagree about being {TaskKind.ORIGINAL}")
        if self.max_steps <= 0:
            raise CatalogError(f"task {self.id}: max_steps must be positive")

    def instruction(self, style: str = DEFAULT_STYLE) -> str:
        """The exact string a policy receives under instruction `style`.

        Args:
            style: An instruction style (`RUN_STYLES`: `libero`, `paper`, or `package`: what the runner of the
                package the task was read from sends).

        Returns:
            The instruction.

        Raises:
            CatalogError: An unknown style, or `package` for a task no package's runner runs.
        """
        if style == PACKAGE_STYLE and style not in self.instructions:
            raise CatalogError(
                f"task {self.id} has no {PACKAGE_STYLE} sentence: it was not read from a benchmark's package "
                "(the libero-pro and libero-plus-language catalogs have them)"
            )
        if style not in self.instructions:
            raise CatalogError(f"unknown instruction style {style!r} (known: {', '.join(RUN_STYLES)})")
        return self.instructions[style]

    @property
    def feasible(self) -> bool:
        """False only when a feasibility gate rejected the task."""
        return self.gate is None or self.gate.feasible

    @property
    def evidence(self) -> str:
        """How the task is shown doable or impossible (`GateResult.evidence`; "not gated" without a verdict)."""
        return "not gated" if self.gate is None else self.gate.evidence

    @property
    def goal_strings(self) -> list[str]:
        """The goal as the registry writes it (a list of expressions, read as their conjunction)."""
        return goal_strings(self.goal)

    @property
    def bddl_goal(self) -> tuple[Predicate, ...]:
        """The conjunction of atoms the task's BDDL file states: the goal itself for a LIBERO-style goal,
        else a final state that satisfies it (LIBERO parses no `Or`, `Not` or order; LangGap judges the goal)."""
        return witness(self.goal)

    def to_dict(self, style: str = DEFAULT_STYLE) -> dict:
        """The JSON form printed by `langgap tasks list --json`."""
        return {
            "id": self.id,
            "catalog": self.catalog,
            "suite": self.suite,
            "kind": self.kind,
            "dimension": self.dimension,
            "split": self.split,
            "source": self.source,
            "instruction": self.instruction(style),
            "instruction_style": style,
            "instructions": dict(self.instructions),
            "goal": self.goal_strings,
            "obj_of_interest": list(self.obj_of_interest),
            "max_steps": self.max_steps,
            "paper_id": self.paper_id,
            "scene_task": self.scene_task,
            "scene_index": self.scene_index,
            "notes": list(self.notes),
            "in_langgap99": self.in_langgap99,
            "validated": self.gate is not None,
            "feasible": self.feasible,
            "evidence": self.evidence,
            "gate": None
            if self.gate is None
            else {**asdict(self.gate), "rate": self.gate.rate, "other_stack": self.gate.other_stack},
            "origin": None if self.origin is None else asdict(self.origin),
            "gate_from": self.gate_from,
        }
