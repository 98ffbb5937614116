"""The task record: one entry of a catalog registry file."""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field

from langgap.bddl import Predicate
from langgap.errors import CatalogError
from langgap.goals import Goal, goal_strings, witness
from langgap.stack import installed_differences
from langgap.vocabulary import CEILING_TARGET, TaskKind, Verdict

# The paper's four dimensions, then the four of the `langgap-beyond` catalog (`generation/beyond.py`).
PAPER_DIMENSIONS = ("change_object", "change_target", "spatial_description", "drawer_action")
BEYOND_DIMENSIONS = ("ordering", "negation", "paraphrase", "attribute_reference")
# The perturbations of the field's benchmarks read from their packages (`generation/external.py`): another goal on
# the same scene (LIBERO-PRO's *task*), and a reworded instruction (LIBERO-PRO's *lan*, LIBERO-Plus's language).
EXTERNAL_DIMENSIONS = ("task", "language")
# An original task's dimension and split are its kind's word.
DIMENSIONS = (TaskKind.ORIGINAL.value, *PAPER_DIMENSIONS, *BEYOND_DIMENSIONS, *EXTERNAL_DIMENSIONS)
# Dimensions whose tasks ask for their source's own goal in other words: a policy that ignores its instruction
# does them as well as their sources, so they alone cannot show whether it reads.
SAME_GOAL_DIMENSIONS = ("paraphrase", "language")
SPLITS = (TaskKind.ORIGINAL.value, "train", "heldout")
INSTRUCTION_STYLES = ("libero", "paper")
DEFAULT_STYLE = "libero"
# The sentence the task's own package's runner sends (`langgap.catalog.runner_sentences`): a style only tasks
# read from a package, and their catalogs' originals, have.
PACKAGE_STYLE = "package"
RUN_STYLES = (*INSTRUCTION_STYLES, PACKAGE_STYLE)


# The gate's check that a task's starts come to rest; a verdict's `reason` names the checks it failed, and one
# that failed this one is `Verdict.UNSETTLED`.
SETTLE_CHECK = "scene settles"
# Why a task may take another's verdict: the gate's oracle reads the goal, never the instruction, so two tasks
# with the same scene file outside `(:language)`, the same init states, goal and step limit get the same episodes.
SAME_TRIAL = "the same scene file outside (:language), init states, goal and step limit"


def unproven(successes: int, episodes: int) -> str:
    """How a task the oracle fails, with no proof that a policy cannot do it, reads wherever it is shown."""
    return f"{Verdict.UNPROVEN}: the oracle does not do it ({successes}/{episodes}); no proof that a policy cannot"


def unsettled(successes: int, episodes: int) -> str:
    """How a task rejected because its starts do not come to rest reads wherever it is shown, with what the
    oracle did on it."""
    return f"{Verdict.UNSETTLED}: its starts do not come to rest (the oracle did it {successes}/{episodes})"


def infeasible(proof: str = "") -> str:
    """How a task proven impossible reads wherever it is shown (with the proof, when given)."""
    return f"{Verdict.INFEASIBLE}: a proof that no policy can do it" + (f": {proof}" if proof else "")


def verdict_of(feasible: bool, proof: str, reason: str) -> Verdict:
    """The word for a gate's decision on a task: admitted (`feasible`), rejected with a `proof`, or rejected for
    `reason` (the checks it failed, joined by "; "): its starts do not come to rest, or anything else."""
    if feasible:
        return Verdict.DOABLE
    if proof:
        return Verdict.INFEASIBLE
    return Verdict.UNSETTLED if SETTLE_CHECK in reason.split("; ") else Verdict.UNPROVEN


def verdict_counts(
    verdicts: Iterable[Verdict], always: tuple[Verdict, ...] = (Verdict.DOABLE, Verdict.UNPROVEN)
) -> str:
    """How many of each verdict, in `Verdict`'s order (`3 doable, 1 unproven`): those in `always`, and any other
    that occurs."""
    counts = Counter(verdicts)
    return ", ".join(f"{counts[v]} {v}" for v in Verdict if v in always or counts[v])


@dataclass(frozen=True)
class GateResult:
    """A feasibility gate's verdict on one task: how a scripted oracle did, and whether the task is kept.

    The gate runs init states 0..`inits`-1; `failed_inits` lists those the oracle failed (None in
    verdicts recorded before per-init results were kept), so the oracle's ceiling can be given for
    exactly the init states a run used. `made_by` says which policy, code version and stepping ran the
    gate for this verdict (a file mixes verdicts of several recordings when tasks are re-validated one
    by one; empty in verdicts recorded before it was kept), and `physics` the physics stack and conventions
    it ran on (`langgap.stack.physics_stack`, as results record it; empty: not recorded).

    What a verdict shows: a task is doable when a demonstration did it — the oracle, at the gate's
    rate, or `demonstration`, a stored replayable episode (a path relative to the registry's directory)
    that does a task the oracle fails; it is impossible only by `proof`, an argument that holds for
    every policy, printed with its assumptions (`langgap.validity.proofs`). A task the oracle fails without
    either is *unproven*: nobody has shown it doable or impossible. A task whose starts do not come to
    rest is *unsettled*, whatever the oracle did (`verdict`: the word, `langgap.vocabulary.Verdict`).
    """

    episodes: int
    successes: int
    feasible: bool
    reason: str = ""
    inits: int = 0
    failed_inits: tuple[int, ...] | None = None
    made_by: str = ""
    proof: str = ""
    demonstration: str = ""
    demonstrated_inits: tuple[int, ...] = ()  # init states the oracle failed that a searched episode did
    physics: dict = field(default_factory=dict)
    # `catalog:task id` whose verdict this is, by identity (the task's `gate_from`); empty: the task's own.
    inherited_from: str = ""

    def __post_init__(self) -> None:
        if not 0 <= self.successes <= self.episodes:
            raise CatalogError(f"gate result: {self.successes} successes in {self.episodes} episodes")
        if self.failed_inits is not None:
            object.__setattr__(self, "failed_inits", tuple(self.failed_inits))  # JSON gives a list
        object.__setattr__(self, "demonstrated_inits", tuple(self.demonstrated_inits))
        if self.proof and self.feasible:
            raise CatalogError("gate result: feasible, yet with a proof that the task is impossible")

    @property
    def rate(self) -> float:
        """Oracle success rate (0 when no episode ran)."""
        return self.successes / self.episodes if self.episodes else 0.0

    def oracle_on(self, inits: list[int] | tuple[int, ...]) -> tuple[int, int]:
        """(successes, episodes) of the oracle on the init states `inits` that the gate ran; the gate's
        whole result when it kept no per-init results or ran none of them."""
        covered = [i for i in inits if i < self.inits]
        if self.failed_inits is None or not covered:
            return self.successes, self.episodes
        failed = set(self.failed_inits)
        return sum(i not in failed for i in covered), len(covered)

    @property
    def verdict(self) -> Verdict:
        """The verdict's word (`verdict_of`)."""
        return verdict_of(self.feasible, self.proof, self.reason)

    def capped_because(self, successes: int, episodes: int) -> str | None:
        """Why the task is marked ⚠ beside a policy's results, given the oracle's `successes` in `episodes`
        on the init states in question (None: it is not), led by its verdict's word: proven infeasible, its
        starts do not come to rest, or an oracle below `CEILING_TARGET` — which shows only that the oracle does
        not do it, not that no policy can (an admitted task too: the gate admits at a lower rate)."""
        verdict = self.verdict
        if verdict is Verdict.INFEASIBLE:
            return infeasible()
        if verdict is Verdict.UNSETTLED:
            return unsettled(successes, episodes)
        if not episodes or successes / episodes >= CEILING_TARGET:
            return None
        if verdict is Verdict.UNPROVEN:
            return unproven(successes, episodes)
        if self.demonstrated:
            return f"{verdict} by a searched demonstration; the oracle does {successes}/{episodes} of these init states"
        return f"{verdict}, but the oracle does only {successes}/{episodes} of these init states"

    @property
    def demonstrated(self) -> bool:
        """True when a stored demonstration, not the oracle's rate, is what makes the task doable."""
        return self.feasible and bool(self.demonstration)

    @property
    def evidence(self) -> str:
        """How the verdict is shown, led by its word: by the oracle's episodes or a searched demonstration
        (doable), a proof (infeasible), starts that do not come to rest (unsettled), or not at all (unproven);
        an inherited verdict says whose it is."""
        if self.inherited_from:
            own = dataclasses.replace(self, inherited_from="").evidence
            return f"{own} — the verdict of {self.inherited_from}: {SAME_TRIAL}"
        verdict = self.verdict
        if verdict is Verdict.INFEASIBLE:
            return infeasible(self.proof)
        if verdict is Verdict.DOABLE:
            made_by = f"made by {self.made_by}" if self.made_by else "recorded before who made it was kept"
            text = f"{verdict}: oracle {self.successes}/{self.episodes} init states ({made_by})"
            if self.demonstrated:
                shown = ", ".join(map(str, self.demonstrated_inits)) or "?"
                text += f"; searched demonstration on init state(s) {shown}: {self.demonstration}"
            return text
        if verdict is Verdict.UNSETTLED:
            text = unsettled(self.successes, self.episodes)
        elif self.oracle_short:
            text = unproven(self.successes, self.episodes)
        else:
            text = f"{verdict}: the gate's checks fail (the oracle did it {self.successes}/{self.episodes}); no proof "
            text += "that a policy cannot"
        if self.demonstration and self.demonstrated_inits:
            shown = ", ".join(map(str, self.demonstrated_inits))
            text += f"; a searched demonstration does init state(s) {shown}: {self.demonstration}"
        if self.reason and self.reason != f"oracle {self.successes}/{self.episodes}":
            text += f"; the gate's reason: {self.reason}"
        return text

    @property
    def oracle_short(self) -> bool:
        """Whether the verdict was rejected for the oracle's rate (its reason names the oracle's count; a verdict
        rejected with no reason recorded is taken to be)."""
        return not self.feasible and (not self.reason or any(c.startswith("oracle ") for c in self.reason.split("; ")))

    @property
    def other_stack(self) -> list[str]:
        """How the physics stack the verdict was made on differs from the installed one (empty: it does not;
        `langgap.stack.installed_differences`)."""
        return installed_differences(self.physics)

    @property
    def capped(self) -> bool:
        """True when the task is marked ⚠ on the init states the gate ran (`capped_because`)."""
        return self.capped_because(self.successes, self.episodes) is not None


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
