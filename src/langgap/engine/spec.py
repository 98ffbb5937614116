"""What a run *is* (`RunSpec`) and how it is *executed* (`ExecutionOptions`): two validated values.

A `RunSpec` holds everything that changes a run's results: the policy and its arguments, the
catalog (name and content hash), the tasks, init indices, seed, language conditions, instruction
style and the physics (the stack's versions, and the `fast` stepping when chosen). It is stored
whole with the run and compared whole on `--resume`, so a resumed run can never mix episodes made
under two protocols. `ExecutionOptions` says how the episodes are run (backend, workers, timeouts,
retries, videos, Ray's options): every backend gives the same episodes, so none of it is part of
the run's identity.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

from langgap import stack
from langgap.catalog.catalog import DEFAULT_CATALOG, catalog_hash, load_catalog
from langgap.catalog.task import DEFAULT_STYLE, RUN_STYLES
from langgap.engine.filming import VideoSelection
from langgap.engine.plan import REPEAT_STRIDE, unknown_conditions, unknown_conditions_text
from langgap.errors import LangGapError, ParameterError
from langgap.policies import policy_kwargs
from langgap.vocabulary import Condition, SeedScheme, Stepping, words

PAPER_EPISODES = 20
DEFAULT_TIMEOUT_S = 900.0
DEFAULT_MAX_ATTEMPTS = 3
DEFAULT_FAILURE_STREAK = 3
DEFAULT_MAX_BATCH = 8  # shared policy: the largest batch
DEFAULT_MAX_WAIT_MS = 5.0  # shared policy: how long a query waits for others
# The fields that only say which episodes a run holds: `--extend` lets a resumed run grow them.
PLAN_FIELDS = ("selection", "tasks", "inits", "conditions", "repeats")
# The steppings a run can choose: `robosuite` gives `exact`'s bits, slower (for benchmarks and tests).
RESULT_STEPPINGS = tuple(s for s in Stepping if s is not Stepping.ROBOSUITE)


class SpecError(LangGapError):
    """A run spec or execution option is invalid, or a stored run was made with another spec."""


class SpecParameterError(SpecError, ParameterError):
    """An argument of `RunSpec.create` or `ExecutionOptions` is invalid, named as the caller passed it."""


@dataclass(frozen=True)
class RunSpec:
    """Everything that determines a run's results. Build one with `RunSpec.create` (which validates it).

    Attributes:
        policy: The policy's name (or `module:Class` path).
        policy_args: Its constructor arguments, as strings.
        catalog: The catalog's name (or registry path).
        catalog_hash: The SHA-256 of the catalog's registry file.
        selection: The task selection as given (None: the catalog's default selection).
        tasks: The task ids it resolved to.
        inits: The init-state indices every task runs (episode k uses init state k).
        seed: Episode k's env seed is seed + k (repeat r: seed + r * REPEAT_STRIDE + k).
        repeats: Seeds per init state.
        conditions: The language conditions every task runs under.
        style: The instruction style.
        physics: The installed physics stack and conventions (`langgap.stack.physics_stack`), with the `fast`
            stepping and the `openpi` seed scheme where chosen.
    """

    policy: str
    policy_args: dict[str, str]
    catalog: str
    catalog_hash: str
    selection: str | None
    tasks: tuple[str, ...]
    inits: tuple[int, ...]
    seed: int
    repeats: int
    conditions: tuple[str, ...]
    style: str
    physics: dict[str, str]

    @classmethod
    def create(
        cls,
        policy: str,
        *,
        policy_args: dict[str, str] | None = None,
        catalog: str = DEFAULT_CATALOG,
        tasks: str | None = None,
        episodes: int = PAPER_EPISODES,
        seed: int = 0,
        repeats: int = 1,
        conditions: tuple[str, ...] = (Condition.GIVEN,),
        style: str = DEFAULT_STYLE,
        stepping: str = stack.DEFAULT_STEPPING,
        seed_scheme: str = stack.DEFAULT_SEED_SCHEME,
    ) -> RunSpec:
        """A validated spec: the policy accepts its arguments, the selection resolves, the options exist.

        `tasks` is a task selection (see `Catalog.select`); `episodes` runs init states 0..episodes-1.

        Args:
            policy: A registered policy's name (`noop`, `random`, `blind`, `oracle`, `small-bc`, `openpi`,
                `lerobot`, ...) or the `module:Class` path of a policy class.
            policy_args: The policy's constructor arguments as strings (`{"checkpoint": "bc.safetensors"}`),
                checked against its constructor here and converted to its types when it is built.
            catalog: A shipped catalog's name or a registry file's path (see `load_catalog`).
            tasks: A task selection (see `Catalog.select`); None: the catalog's doable tasks (`feasible`).
            episodes: Episodes per task and condition: init states 0..episodes-1 (at least 1).
            seed: The first episode's environment seed: episode k's is seed + k.
            repeats: Seeds per init state, 1..REPEAT_STRIDE: repeat r of episode k has seed
                seed + r * REPEAT_STRIDE + k.
            conditions: The language conditions (`given`, `empty`, `shuffled`, `source`, `nonsense`,
                `switch:K`; `langgap.engine.plan.CONDITION_HELP`); one named twice runs once.
            style: The instruction style: `libero` or `paper` (the catalog's wording), or `package` (what the
                runner of the benchmark a task was read from sends: LIBERO-PRO's and LIBERO-Plus's `task.language`).
            stepping: How the physics substeps are computed: `exact` or `fast` (`RESULT_STEPPINGS`).
            seed_scheme: How an episode's seed selects its placement: `per-episode` or `openpi`
                (`langgap.vocabulary.SeedScheme`).

        Returns:
            The spec, with the selection resolved to task ids and the catalog's hash and the installed physics
            stack recorded.

        Raises:
            SpecError: `episodes` or `repeats` out of range (a `ParameterError` that names it), an unknown
                style, stepping, seed scheme or condition.
            LangGapError: An unknown policy or policy argument, an unknown catalog, a selection that matches no
                task.
        """
        policy_args = {str(k): str(v) for k, v in (policy_args or {}).items()}
        policy_kwargs(policy, policy_args)
        if episodes < 1:
            raise SpecParameterError("{episodes} must be at least 1, got {got}", got=episodes)
        if not 1 <= repeats <= REPEAT_STRIDE:
            raise SpecParameterError(
                "{repeats} must be between 1 and {most}, got {got}", most=REPEAT_STRIDE, got=repeats
            )
        if style not in RUN_STYLES:
            raise SpecError(f"unknown instruction style {style!r} (known: {', '.join(RUN_STYLES)})")
        if stepping not in RESULT_STEPPINGS:
            raise SpecError(f"unknown stepping {stepping!r} (known: {', '.join(RESULT_STEPPINGS)})")
        if seed_scheme not in tuple(SeedScheme):
            raise SpecError(f"unknown seed scheme {seed_scheme!r} (known: {', '.join(SeedScheme)})")
        conditions = tuple(dict.fromkeys(conditions))
        unknown = unknown_conditions(conditions)
        if unknown or not conditions:
            raise SpecError(unknown_conditions_text(unknown))
        selected = load_catalog(catalog).select(tasks)
        for task in selected:
            task.instruction(style)  # `package`: every task must have a runner's sentence
        return cls(
            policy=policy,
            policy_args=policy_args,
            catalog=catalog,
            catalog_hash=catalog_hash(catalog),
            selection=tasks,
            tasks=tuple(t.id for t in selected),
            inits=tuple(range(episodes)),
            seed=seed,
            repeats=repeats,
            conditions=words(conditions),  # plain strings: the spec is stored, and shown by `repr`
            style=style,
            physics=stack.physics_stack(stepping, seed_scheme),
        )

    @property
    def stepping(self) -> str:
        """How the physics substeps are computed (`exact` unless the spec's physics names `fast`)."""
        return self.physics.get("stepping") or stack.DEFAULT_STEPPING

    @property
    def seed_scheme(self) -> str:
        """How an episode's seed selects its placement (`per-episode` unless the spec's physics names `openpi`)."""
        return self.physics.get("seed_scheme") or stack.DEFAULT_SEED_SCHEME

    def to_dict(self) -> dict:
        """The spec as JSON data (the form stored with a run)."""
        data = asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in data.items()}

    def differences(self, stored: dict) -> list[str]:
        """The fields in which a stored spec (`to_dict` form) differs from this one."""
        return spec_differences(stored, self.to_dict())

    def describe_differences(self, stored: dict, names: list[str]) -> str:
        """One line naming each differing field with its stored and given values."""

        def short(value) -> str:
            text = repr(value)
            return text if len(text) <= 60 else text[:57] + "..."

        mine = self.to_dict()
        return "; ".join(f"{n}: stored {short(stored.get(n))}, given {short(mine[n])}" for n in names)


def spec_differences(a: dict, b: dict) -> list[str]:
    """The `RunSpec` fields in which two specs in their stored (`RunSpec.to_dict`) form differ. None: the two are
    one spec, a run's identity (`--resume` continues a run only under its own). Their physics differs as
    `langgap.stack.stack_differences` says: a run stored before an entry was recorded (`RECORDED_SINCE`) continues."""

    def differs(name: str) -> bool:
        mine, theirs = a.get(name), b.get(name)
        if name == "physics" and mine and theirs:
            return stack.stacks_differ(mine, theirs)
        return mine != theirs

    return [f.name for f in fields(RunSpec) if differs(f.name)]


@dataclass(frozen=True)
class ExecutionOptions:
    """How a run is executed; results do not depend on any of it.

    Args:
        backend: Where the episodes run: a name in `langgap.engine.pools.BACKENDS` (`local`, `ray`).
        workers: Local: worker processes (0: in this process); ray: environment actors.
        timeout_s: Seconds per episode before it is an infrastructure failure; None: DEFAULT_TIMEOUT_S where it
            can be enforced (worker processes, not this process).
        max_attempts: Attempts at a work item before it is given up (an episode becomes a gap).
        max_failure_streak: Consecutive infrastructure failures with the same cause that stop the run.
        video: Which episodes to film (`langgap.engine.filming.VideoSelection`): `first:N`, `per-outcome:N`
            or `N`; empty: none.
        progress: Show a progress bar.
        ray_address: The Ray cluster to join (None: start a local one); needs `backend="ray"`.
        shared_policy: One policy process (local) or actor (ray) batching every worker's queries.
        max_batch: Shared policy: the largest batch (None: DEFAULT_MAX_BATCH).
        max_wait_ms: Shared policy: how long a query waits for others (None: DEFAULT_MAX_WAIT_MS).
        policy_gpus: Ray's shared policy: GPUs for the policy actor (None: 0).
        share_rollouts: Run an instruction-blind policy's episodes that start alike as one rollout
            (`langgap.engine.sharing`); every record is the one its own episode gives.

    Raises:
        SpecError: An option out of range, or one that needs another (a `ParameterError` that names them).
    """

    backend: str = "local"
    workers: int = 1
    timeout_s: float | None = None
    max_attempts: int = DEFAULT_MAX_ATTEMPTS
    max_failure_streak: int = DEFAULT_FAILURE_STREAK
    video: str = ""
    progress: bool = True
    ray_address: str | None = None
    shared_policy: bool = False
    max_batch: int | None = None
    max_wait_ms: float | None = None
    policy_gpus: float | None = None
    share_rollouts: bool = False

    def __post_init__(self) -> None:
        # The backend's name is checked by `langgap.engine.pools.make_pool`, which owns the registry.
        if self.workers < 0 or (self.backend != "local" and self.workers < 1):
            least = 0 if self.backend == "local" else 1
            raise SpecParameterError("{workers} must be at least {least}, got {got}", least=least, got=self.workers)
        if self.timeout_s is not None and self.timeout_s <= 0:
            raise SpecParameterError("{timeout_s} must be positive, got {got}", got=self.timeout_s)
        if self.timeout_s is not None and self.backend == "local" and self.workers == 0:
            raise SpecParameterError("{timeout_s} needs worker processes: an episode in this process cannot be stopped")
        if self.max_attempts < 1:
            raise SpecParameterError("{max_attempts} must be at least 1, got {got}", got=self.max_attempts)
        if self.max_failure_streak < 1:
            raise SpecParameterError("{max_failure_streak} must be at least 1, got {got}", got=self.max_failure_streak)
        try:
            VideoSelection.parse(self.video)
        except ParameterError as exc:
            raise SpecParameterError(exc.template, **exc.values) from None
        if self.ray_address is not None and self.backend != "ray":
            raise SpecParameterError("{ray_address} needs {backend} ray")
        batching = {"max_batch": self.max_batch, "max_wait_ms": self.max_wait_ms, "policy_gpus": self.policy_gpus}
        given = ", ".join(f"{{{name}}}" for name, value in batching.items() if value is not None)
        if given and not self.shared_policy:
            raise SpecParameterError(given + " only apply to a shared policy ({shared_policy})")
        if self.shared_policy and self.workers == 0:
            raise SpecParameterError("{shared_policy} needs worker processes to serve ({workers} 1 or more)")
        if self.policy_gpus is not None and self.backend != "ray":
            raise SpecParameterError(
                "{policy_gpus} needs {backend} ray (a local policy process uses the GPUs it can see)"
            )
        if self.max_batch is not None and self.max_batch < 1:
            raise SpecParameterError("{max_batch} must be at least 1, got {got}", got=self.max_batch)
        if (self.max_wait_ms or 0) < 0 or (self.policy_gpus or 0) < 0:
            raise SpecParameterError("{max_wait_ms} and {policy_gpus} must not be negative")

    @property
    def video_selection(self) -> VideoSelection:
        return VideoSelection.parse(self.video)

    @property
    def batch_limit(self) -> int:
        """The shared policy's largest batch."""
        return DEFAULT_MAX_BATCH if self.max_batch is None else self.max_batch

    @property
    def batch_wait_ms(self) -> float:
        """How long the shared policy's first query of a batch waits for others."""
        return DEFAULT_MAX_WAIT_MS if self.max_wait_ms is None else self.max_wait_ms

    @property
    def episode_timeout_s(self) -> float | None:
        """The enforced per-episode timeout (None in this process, where nothing can stop an episode)."""
        if self.backend == "local" and self.workers == 0:
            return None
        return DEFAULT_TIMEOUT_S if self.timeout_s is None else self.timeout_s
