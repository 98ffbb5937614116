"""The plan of a run and the validation of what a run is and how it runs."""

from __future__ import annotations

import dataclasses
import hashlib

import pytest

from langgap import stack
from langgap.catalog.catalog import Catalog, catalog_hash, load_catalog, load_catalog_file, registry_path
from langgap.engine.plan import (
    build_plan,
    condition_instruction,
    episode_seed,
    repeat_of,
    switch_episode,
    switch_note,
    switch_source,
    unknown_conditions_text,
    without_switch_source,
)
from langgap.engine.pools import make_pool
from langgap.engine.spec import ExecutionOptions, RunSpec, SpecError
from langgap.errors import LangGapError
from langgap.records import EpisodeKey

BOWL_1 = "spatial/s0/black-bowl-1-on-plate"
RAMEKIN = "spatial/s0/ramekin-on-plate"
STOVE = "goal/s7/turn-on-stove"


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def test_every_task_condition_and_init_index_once_with_shared_seeds(catalog):
    tasks = catalog.select("spatial/s0/black-bowl-1-on-plate,spatial/s0/ramekin-on-plate,goal/s7/turn-on-stove")
    plan = build_plan(tasks, catalog, episodes=3, seed=10, conditions=("given", "empty"), first_init=2)
    assert len(plan) == 3 * 2 * 3 and len({p.key for p in plan}) == len(plan)
    assert {(p.key.init_index, p.key.seed) for p in plan} == {(k, episode_seed(10, k)) for k in (2, 3, 4)}
    assert episode_seed(10, 3) == 13  # the init index, not the task: siblings start from the identical scene
    scenes = {p.key.task_id: p.scene for p in plan}
    assert scenes["spatial/s0/black-bowl-1-on-plate"] == scenes["spatial/s0/ramekin-on-plate"]
    assert scenes["goal/s7/turn-on-stove"] != scenes["spatial/s0/ramekin-on-plate"]
    empty = [p for p in plan if p.key.condition == "empty"]
    assert empty and all(p.instruction == "" for p in empty)
    given = next(p for p in plan if p.key == p.key.__class__("goal/s7/turn-on-stove", 2, 12, "given"))
    assert given.instruction == catalog.get("goal/s7/turn-on-stove").instruction("libero")


def test_conditions_are_deterministic_and_come_from_the_scene(catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    assert condition_instruction(task, catalog, "source", "paper", 0) == catalog.get(task.source).instruction("paper")
    shuffled = [condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(10)]
    assert shuffled == [condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(10)]
    assert task.instruction() not in shuffled
    assert set(shuffled) <= {t.instruction() for t in catalog.scene_mates(task)}


def test_init_indices_past_the_fifty_states_are_an_error(catalog):
    with pytest.raises(LangGapError, match="has 50 init states; init indices 45..50 are out of range"):
        build_plan(catalog.select("spatial/s0/black-bowl-1-on-plate"), catalog, episodes=6, first_init=45)
    with pytest.raises(LangGapError, match="unknown condition"):
        build_plan(catalog.select("spatial/s0/black-bowl-1-on-plate"), catalog, episodes=1, conditions=("loud",))
    with pytest.raises(LangGapError, match="init indices -1..0 are out of range"):
        build_plan(catalog.select(BOWL_1), catalog, episodes=2, first_init=-1)
    with pytest.raises(LangGapError, match="^episodes must be at least 1, got 0$"):
        build_plan(catalog.select(BOWL_1), catalog, episodes=0)
    assert len(build_plan(catalog.select(BOWL_1), catalog, episodes=5, first_init=45)) == 5  # 45..49: the last five


def test_the_plan_order_is_task_then_condition_then_init_then_repeat(catalog):
    tasks = [catalog.get(RAMEKIN), catalog.get(STOVE)]
    plan = build_plan(tasks, catalog, episodes=2, seed=7, conditions=("empty", "given"), first_init=4, repeats=2)
    assert [p.key for p in plan] == [
        EpisodeKey(task, init, 7 + repeat * 1000 + init, condition)
        for task in (RAMEKIN, STOVE)
        for condition in ("empty", "given")
        for init in (4, 5)
        for repeat in (0, 1)
    ]


def test_every_episode_knows_its_scene(catalog):
    plan = build_plan(catalog.select("spatial/s0/*,spatial/s1/*,goal/s1/*,goal/s7/*"), catalog, episodes=1)
    scenes = {}
    for p in plan:
        scenes.setdefault(p.scene, set()).add(p.key.task_id.rsplit("/", 1)[0])
    # one scene per spatial layout; every libero_goal task shares one layout
    assert sorted(scenes.values(), key=sorted) == [{"goal/s1", "goal/s7"}, {"spatial/s0"}, {"spatial/s1"}]
    assert all(len(scene) == 16 for scene in scenes)


def test_every_episode_watches_the_goals_of_its_scene_as_the_plan_found_them(catalog):
    from langgap.engine.episode import scene_goals, watched_goals

    plan = build_plan(catalog.select("spatial/s0/*,goal/s1/*"), catalog, episodes=2, conditions=("given", "switch:5"))
    for planned in plan:
        task = catalog.get(planned.task_id)
        assert planned.watched == tuple(mate.id for mate in catalog.scene_mates(task))
        # What a worker judges every step: the goals the plan named, the same its scene's tasks have.
        assert watched_goals(planned, catalog) == scene_goals(task, catalog)
    # Every episode of a task shares the one tuple the plan found for it.
    assert len({id(p.watched) for p in plan if p.task_id == plan[0].task_id}) == 1


def test_a_plan_reads_each_scene_once_however_many_episodes_its_tasks_have(monkeypatch):
    from langgap.catalog import files

    catalog = load_catalog_file(registry_path("langgap99"))  # a catalog of its own: none of its scenes read yet
    read = []
    scene_key = files.scene_key

    def reading(task):
        read.append(task.id)
        return scene_key(task)

    monkeypatch.setattr(files, "scene_key", reading)
    tasks = catalog.select(f"{BOWL_1},{RAMEKIN}")
    plan = build_plan(tasks, catalog, episodes=5, conditions=("given", "shuffled", "switch:5"), repeats=2)
    assert len(plan) == 2 * 3 * 5 * 2
    # The shuffled and switch pools need the scene of every task of the suite: each is read once, for 60 episodes.
    assert sorted(read) == sorted(t.id for t in catalog if t.suite == "libero_spatial")


def test_the_instruction_style_reaches_the_plan(catalog):
    task = catalog.get(BOWL_1)
    (libero,) = build_plan([task], catalog, episodes=1, style="libero")
    (paper,) = build_plan([task], catalog, episodes=1, style="paper")
    assert libero.instruction == "pick up the black bowl between the plate and the ramekin and place it on the plate"
    assert paper.instruction == "Pick the akita black bowl between the plate and the ramekin and place it on the plate"
    assert libero.instruction_sha256 == hashlib.sha256(libero.instruction.encode()).hexdigest()


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"workers": -1}, "^workers must be at least 0, got -1$"),
        ({"backend": "ray", "workers": 0}, "^workers must be at least 1, got 0$"),
        ({"workers": 0, "timeout_s": 10}, "^timeout_s needs worker processes"),
        ({"timeout_s": 0}, "^timeout_s must be positive, got 0$"),
        ({"max_batch": 4}, "^max_batch only apply to a shared policy \\(shared_policy\\)$"),
        ({"backend": "ray", "shared_policy": True, "max_batch": 0}, "^max_batch must be at least 1, got 0$"),
        ({"max_attempts": 0}, "^max_attempts must be at least 1, got 0$"),
        ({"max_failure_streak": 0}, "^max_failure_streak must be at least 1, got 0$"),
        ({"video": "-1"}, "^video must film at least 0 episodes, got '-1'$"),
        ({"ray_address": "10.0.0.1:6379"}, "^ray_address needs backend ray$"),
        (
            {"shared_policy": True, "workers": 0},
            "^shared_policy needs worker processes to serve \\(workers 1 or more\\)$",
        ),
        ({"shared_policy": True, "policy_gpus": 1.0}, "^policy_gpus needs backend ray"),
        (
            {"backend": "ray", "max_wait_ms": 2.0, "policy_gpus": 1.0},
            "^max_wait_ms, policy_gpus only apply to a shared policy \\(shared_policy\\)$",
        ),
        (
            {"backend": "ray", "shared_policy": True, "max_wait_ms": -1.0},
            "^max_wait_ms and policy_gpus must not be negative$",
        ),
        (
            {"backend": "ray", "shared_policy": True, "policy_gpus": -0.5},
            "^max_wait_ms and policy_gpus must not be negative$",
        ),
    ],
)
def test_execution_options_are_validated(options, message):
    with pytest.raises(SpecError, match=message):
        ExecutionOptions(**options)


def test_execution_defaults():
    assert ExecutionOptions().episode_timeout_s == 900 and ExecutionOptions(workers=0).episode_timeout_s is None
    assert ExecutionOptions(timeout_s=30).episode_timeout_s == 30
    assert ExecutionOptions(backend="ray", workers=2).episode_timeout_s == 900
    defaults = ExecutionOptions()
    assert (defaults.backend, defaults.workers, defaults.max_attempts, defaults.max_failure_streak) == (
        "local",
        1,
        3,
        3,
    )
    # what a valid shared-policy configuration looks like
    shared = ExecutionOptions(backend="ray", workers=4, shared_policy=True, max_batch=8, max_wait_ms=0, policy_gpus=0)
    assert (shared.batch_limit, shared.batch_wait_ms) == (8, 0)
    local = ExecutionOptions(workers=2, shared_policy=True)
    assert (local.batch_limit, local.batch_wait_ms) == (8, 5)


def test_an_unknown_backend_is_refused_by_the_pool_registry():
    with pytest.raises(LangGapError, match="unknown backend 'slurm' \\(known: local, ray\\)"):
        make_pool(None, ExecutionOptions(backend="slurm", workers=2))


def test_a_spec_resolves_its_selection_and_records_what_determines_results():
    spec = RunSpec.create("random", policy_args={"scale": 0.5}, tasks="spatial/s0/*&original,goal/s7/*", episodes=3,
                          seed=4, repeats=2, conditions=("given", "empty", "given"), style="paper")  # fmt: skip
    assert spec.tasks == (BOWL_1, STOVE)
    assert spec.selection == "spatial/s0/*&original,goal/s7/*"
    assert (spec.inits, spec.seed, spec.repeats, spec.style) == ((0, 1, 2), 4, 2, "paper")
    assert spec.conditions == ("given", "empty")  # duplicates dropped, order kept
    assert spec.policy_args == {"scale": "0.5"}  # stored as the strings given
    assert spec.catalog == "langgap99" and spec.catalog_hash == catalog_hash("langgap99")
    assert spec.physics == stack.physics_stack() and "mujoco" in spec.physics
    default = RunSpec.create("noop", episodes=1)
    feasible = {task.id for task in load_catalog("langgap99") if task.feasible}  # the recorded verdicts
    assert default.selection is None and set(default.tasks) == feasible  # all 99 since the bottom drawers open


@pytest.mark.parametrize(
    ("arguments", "error", "message"),
    [
        ({"episodes": 0}, SpecError, "^episodes must be at least 1, got 0$"),
        ({"repeats": 0}, SpecError, "^repeats must be between 1 and 1000, got 0$"),
        ({"repeats": 1001}, SpecError, "^repeats must be between 1 and 1000, got 1001$"),
        ({"style": "shouting"}, SpecError, "unknown instruction style 'shouting' \\(known: libero, paper, package\\)"),
        ({"conditions": ("given", "loud")}, SpecError, "unknown condition\\(s\\) \\['loud'\\]"),
        ({"conditions": ()}, SpecError, "unknown condition\\(s\\) \\[\\]"),
        ({"tasks": "spatial&libero10"}, LangGapError, "selection 'spatial&libero10' matches no task"),
        ({"catalog": "langgap100"}, LangGapError, "langgap100"),
        ({"policy": "levitate"}, LangGapError, "unknown policy 'levitate'"),
        (
            {"policy": "my_policy.MyPolicy"},
            LangGapError,
            "unknown policy 'my_policy.MyPolicy'; a policy of your own is named module:Class, with a colon: "
            "my_policy:MyPolicy",
        ),
        ({"policy_args": {"speed": "2"}}, LangGapError, "policy 'random' has no argument 'speed'"),
        ({"policy_args": {"scale": "fast"}}, LangGapError, "policy 'random' argument scale"),
        ({"stepping": "robosuite"}, SpecError, "unknown stepping 'robosuite' \\(known: exact, fast\\)"),
    ],
)
def test_a_spec_is_validated(arguments, error, message):
    arguments = {"policy": "random", "tasks": BOWL_1, "episodes": 2} | arguments
    with pytest.raises(error, match=message):
        RunSpec.create(arguments.pop("policy"), **arguments)


def test_the_fast_stepping_is_part_of_what_a_run_is():
    """`fast` changes results (in their last bits): its spec's physics says so and differs from `exact`'s,
    while `exact` keeps the physics of runs stored before steppings were named (they resume)."""
    exact = RunSpec.create("noop", tasks=BOWL_1, episodes=1)
    fast = RunSpec.create("noop", tasks=BOWL_1, episodes=1, stepping="fast")
    assert exact.stepping == "exact" and exact.physics == stack.physics_stack() and "stepping" not in exact.physics
    assert fast.stepping == "fast" and fast.physics == stack.physics_stack() | {"stepping": "fast"}
    assert fast.differences(exact.to_dict()) == ["physics"]


def test_a_spec_names_every_field_that_differs():
    spec = RunSpec(
        policy="noop", policy_args={}, catalog="langgap99", catalog_hash="abc", selection=None, tasks=("a", "b"),
        inits=(0, 1), seed=0, repeats=1, conditions=("given",), style="libero", physics={"mujoco": "3.2.3"},
    )  # fmt: skip
    stored = spec.to_dict()
    assert spec.differences(stored) == []
    other = dataclasses.replace(spec, seed=5, inits=(0, 1, 2))
    assert other.differences(stored) == ["inits", "seed"]
    assert other.describe_differences(stored, ["seed"]) == "seed: stored 0, given 5"
    assert stored["tasks"] == ["a", "b"]  # stored as JSON lists
    assert spec.differences({k: v for k, v in stored.items() if k != "style"}) == ["style"]  # a missing field differs
    assert spec.differences(stored | {"physics": {"mujoco": "3.3.0"}}) == ["physics"]
    assert (
        other.describe_differences(stored, ["seed", "inits"])
        == "seed: stored 0, given 5; inits: stored [0, 1], given [0, 1, 2]"
    )
    longer = dataclasses.replace(spec, tasks=tuple(f"spatial/s0/task-{k}" for k in range(10)))
    described = longer.describe_differences(stored, ["tasks"])
    given = described.split(", given ")[1]
    assert len(given) == 60 and given.endswith("...") and given.startswith("['spatial/s0/task-0'")


def test_repeats_run_each_init_state_with_other_seeds(catalog):
    tasks = catalog.select("spatial/s0/black-bowl-1-on-plate")
    plan = build_plan(tasks, catalog, episodes=2, seed=3, repeats=3)
    assert sorted((p.key.init_index, p.key.seed) for p in plan) == [
        (0, 3), (0, 1003), (0, 2003), (1, 4), (1, 1004), (1, 2004)
    ]  # fmt: skip
    assert {repeat_of(p.key.seed, p.key.init_index, 3) for p in plan} == {0, 1, 2}


def test_a_spec_defaults_to_seed_zero_one_repeat_and_keeps_its_policy():
    spec = RunSpec.create("noop", tasks=BOWL_1, episodes=1)
    assert (spec.policy, spec.seed, spec.repeats, spec.inits) == ("noop", 0, 1, (0,))
    assert RunSpec.create("noop", tasks=BOWL_1, episodes=1, repeats=1000).repeats == 1000  # REPEAT_STRIDE: the most
    with pytest.raises(SpecError, match=r"^unknown seed scheme 'daily' \(known: per-episode, openpi\)$"):
        RunSpec.create("noop", tasks=BOWL_1, episodes=1, seed_scheme="daily")


def test_a_difference_is_shown_whole_up_to_sixty_characters():
    spec = RunSpec(
        policy="noop", policy_args={}, catalog="langgap99", catalog_hash="abc", selection=None, tasks=("a",),
        inits=(0,), seed=0, repeats=1, conditions=("given",), style="libero", physics={},
    )  # fmt: skip
    sixty, sixty_one = "x" * 58, "x" * 59  # their reprs: 60 and 61 characters
    assert spec.describe_differences({"selection": sixty}, ["selection"]) == f"selection: stored '{sixty}', given None"
    shown = spec.describe_differences({"selection": sixty_one}, ["selection"])
    assert shown == f"selection: stored '{'x' * 56}..., given None"


@pytest.mark.parametrize(
    "options",
    [
        {"timeout_s": 0.5},
        {"max_attempts": 1},
        {"max_failure_streak": 1},
        {"backend": "ray", "ray_address": "10.0.0.1:6379"},
        {"shared_policy": True, "max_batch": 1},
    ],
)
def test_the_least_valid_execution_options_are_accepted(options):
    made = ExecutionOptions(**options)
    assert all(getattr(made, name) == value for name, value in options.items())


def test_gpus_for_the_policy_need_ray():
    with pytest.raises(
        SpecError, match=r"^policy_gpus needs backend ray \(a local policy process uses the GPUs it can see\)$"
    ):
        ExecutionOptions(shared_policy=True, policy_gpus=1.0)


def test_a_repeat_is_read_back_from_its_seed():
    for run_seed, init_index, repeat in ((10, 3, 2), (600, 7, 1), (0, 600, 1), (5, 0, 0)):
        found = repeat_of(episode_seed(run_seed, init_index, repeat), init_index, run_seed)
        assert found == repeat and isinstance(found, int)


def test_nonsense_has_as_many_words_drawn_from_the_catalogs_sentences(catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    words = {w for t in catalog for w in t.instruction("libero").split()}
    drawn = [condition_instruction(task, catalog, "nonsense", "libero", k) for k in range(3)]
    assert all(len(s.split()) == len(task.instruction("libero").split()) for s in drawn)
    assert all(set(s.split()) <= words for s in drawn) and len(set(drawn)) == 3
    assert drawn == [condition_instruction(task, catalog, "nonsense", "libero", k) for k in range(3)]
    other = catalog.get("spatial/s0/ramekin-on-plate")
    assert condition_instruction(other, catalog, "nonsense", "libero", 0) != drawn[0]  # seeded by the task too
    paper = condition_instruction(task, catalog, "nonsense", "paper", 0)
    assert len(paper.split()) == len(task.instruction("paper").split())


def test_the_drawn_instructions_are_pinned_so_a_plan_never_changes_between_versions(catalog):
    """Which sibling a shuffled episode and an original's switch episode start under, and the nonsense words, are
    part of a run's identity: a resumed or re-run plan must draw the same."""
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    assert [condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(3)] == [
        "pick up the cookie box and place it on the wooden cabinet",
        "pick up the ramekin and place it on the cookie box",
        "pick up the cookie box and place it on the ramekin",
    ]
    assert condition_instruction(task, catalog, "nonsense", "libero", 0).split()[:4] == [
        "tomato",
        "top",
        "bowl",
        "middle",
    ]
    plan = build_plan(catalog.select("spatial/s0/black-bowl-1-on-plate"), catalog, episodes=1, conditions=("switch:5",))
    assert [p.started_as for p in plan] == ["spatial/s0/open-cabinet-top-drawer"]


def test_a_scene_with_one_task_shuffles_in_its_suites_other_instructions(catalog):
    task = catalog.get("libero10/s5/book-in-caddy-back")
    own = task.instruction("libero")
    suite = {t.instruction("libero") for t in catalog if t.suite == task.suite} - {own}
    shuffled = {condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(8)}
    assert shuffled <= suite and len(shuffled) > 1
    alone = Catalog("alone", [task])
    with pytest.raises(LangGapError, match="^no other instruction to shuffle in for libero10/s5/book-in-caddy-back$"):
        condition_instruction(task, alone, "shuffled", "libero", 0)
    with pytest.raises(LangGapError, match=r"^unknown condition\(s\) \['loud'\]"):
        condition_instruction(task, catalog, "loud", "libero", 0)


def test_unknown_conditions_are_named_together():
    assert unknown_conditions_text(["switch:0", "switch:x"]).startswith("'switch:0', 'switch:x': switch:K takes K")
    both = unknown_conditions_text(["loud", "switch:0"])
    assert both.startswith("unknown condition(s) ['loud'] (") and "); 'switch:0': switch:K takes K" in both


def test_a_switch_episode_starts_under_another_tasks_instruction_and_changes_at_k(catalog):
    extended = catalog.get("spatial/s0/black-bowl-2-on-plate")
    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    lone = catalog.get("libero10/s5/book-in-caddy-back")
    tasks = [original, extended, lone]
    plan = build_plan(tasks, catalog, episodes=2, seed=4, conditions=("given", "switch:5"))
    switched = [p for p in plan if p.key.condition == "switch:5"]
    assert [(p.task_id, p.key.init_index, p.key.seed) for p in switched] == [
        (original.id, 0, 4),
        (original.id, 1, 5),
        (extended.id, 0, 4),
        (extended.id, 1, 5),
    ]  # the lone task has no switch episode, but its given ones
    assert [p.task_id for p in plan if p.key.condition == "given"] == [t.id for t in tasks for _ in range(2)]
    for p in switched:
        task = catalog.get(p.task_id)
        first = catalog.get(p.started_as)
        assert p.instruction == first.instruction("libero") and p.changes == ((5, task.instruction("libero")),)
        assert p.scene == next(q.scene for q in plan if q.task_id == p.task_id and q.key.condition == "given")
    assert {p.started_as for p in switched if p.task_id == extended.id} == {original.id}  # an extended: its source
    pool = {p.started_as for p in switched if p.task_id == original.id}
    assert pool and all(catalog.get(s).goal != original.goal and s != original.id for s in pool)
    assert without_switch_source(tasks, catalog) == [lone.id]
    note = switch_note(tasks, catalog, ("switch:5",))
    assert note == (
        "note: 1 task(s) have no other task in their scene to start under; their switch:K episodes are not "
        f"planned: {lone.id}"
    )
    assert switch_note(tasks, catalog, ("given",)) == ""
    lone_ones = without_switch_source(catalog.select("libero10/*"), catalog)  # 8 of libero_10's 10 scenes
    many = switch_note(catalog.select("libero10/*"), catalog, ("switch:5",))
    assert many.startswith(f"note: {len(lone_ones)} task(s)")
    assert many.endswith(f"planned: {', '.join(lone_ones[:4])}, … ({len(lone_ones) - 4} more)")


def test_switch_episodes_that_cannot_be_planned_are_errors(catalog):
    lone = catalog.get("libero10/s5/book-in-caddy-back")
    with pytest.raises(LangGapError, match="^switch: no selected task has another task in its scene to start under$"):
        build_plan([lone], catalog, episodes=1, conditions=("switch:5",))
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    with pytest.raises(LangGapError, match=f"^switch:220: {task.id} ends at step 220, before its instruction would"):
        build_plan([task], catalog, episodes=1, conditions=("switch:220",))
    assert build_plan([task], catalog, episodes=1, conditions=("switch:219",))[0].changes[0][0] == 219
    with pytest.raises(LangGapError, match="switch:K takes K"):
        switch_episode(EpisodeKey(task.id, 0, 0, "switch:0"), task, catalog, "libero", catalog.scene_key(task), ())
    with pytest.raises(LangGapError, match=f"^switch: {lone.id} has no sibling task in its scene to start under$"):
        switch_source(lone, catalog, "libero", 0)


def test_an_original_starts_under_a_sibling_of_another_instruction_and_another_goal_only(catalog):
    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    extended = catalog.get("spatial/s0/ramekin-on-plate")
    same_sentence = dataclasses.replace(extended, instructions=original.instructions)  # another goal, its sentence
    same_goal = dataclasses.replace(catalog.get("spatial/s0/ramekin-on-stove"), goal=original.goal)
    # in the paper's wording only, a sibling says what the original says
    paper_twin = dataclasses.replace(
        catalog.get("spatial/s0/cookie-box-on-plate"),
        instructions=extended.instructions | {"paper": original.instruction("paper")},
    )
    for sibling in (same_sentence, same_goal, paper_twin):
        assert without_switch_source([original], Catalog("two", [original, sibling]), "paper") == [original.id]
    assert without_switch_source([original], Catalog("two", [original, paper_twin])) == []  # libero: they differ
    with pytest.raises(LangGapError, match="^switch: no selected task"):
        build_plan(
            [original], Catalog("two", [original, paper_twin]), episodes=1, conditions=("switch:5",), style="paper"
        )


def test_the_switch_sibling_is_drawn_from_the_task_and_the_seed(catalog):
    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    drawn = [p.started_as.split("/")[-1] for p in build_plan([original], catalog, episodes=6, conditions=("switch:5",))]
    assert drawn == [
        "open-cabinet-top-drawer",
        "open-cabinet-top-drawer",
        "open-cabinet-top-drawer",
        "black-bowl-1-on-stove",
        "ramekin-on-cookie-box",
        "cookie-box-on-plate",
    ]
    plan = build_plan([original], catalog, episodes=3, seed=100, conditions=("switch:5",))
    assert [p.started_as.split("/")[-1] for p in plan] == [
        "cookie-box-on-stove",
        "cookie-box-on-plate",
        "ramekin-on-plate",
    ]
    assert [p.key.seed for p in build_plan([original], catalog, episodes=2)] == [0, 1]  # the run seed is 0 by default


def test_the_switch_note_shows_four_tasks_and_counts_the_rest(catalog):
    lone = [catalog.get(i) for i in without_switch_source(list(catalog), catalog)]
    four = switch_note(lone[:4], catalog, ("switch:5",))
    assert four.endswith(f"planned: {', '.join(t.id for t in lone[:4])}")
    five = switch_note(lone[:5], catalog, ("switch:5",))
    assert five.endswith(f"planned: {', '.join(t.id for t in lone[:4])}, … (1 more)")


def test_a_shuffled_instruction_is_never_the_tasks_own_even_from_a_sibling_that_says_it(catalog):
    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    twin = dataclasses.replace(catalog.get("spatial/s0/ramekin-on-plate"), instructions=original.instructions)
    other = catalog.get("spatial/s0/cookie-box-on-plate")
    small = Catalog("three", [original, twin, other])
    shuffled = {condition_instruction(original, small, "shuffled", "libero", k) for k in range(10)}
    assert shuffled == {other.instruction("libero")}


def test_the_plan_draws_each_episodes_instruction_for_its_own_init_state(catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    plan = build_plan([task], catalog, episodes=4, conditions=("shuffled", "nonsense", "source"))
    assert [p.instruction for p in plan] == [
        condition_instruction(task, catalog, p.key.condition, "libero", p.key.init_index) for p in plan
    ]
    with pytest.raises(LangGapError, match=r"^unknown condition\(s\) \['loud', 'quiet'\]"):
        build_plan([task], catalog, episodes=1, conditions=("given", "loud", "quiet"))


def test_a_task_without_a_switch_source_keeps_the_episodes_of_its_other_conditions(catalog):
    lone, task = catalog.get("libero10/s5/book-in-caddy-back"), catalog.get("spatial/s0/black-bowl-2-on-plate")
    plan = build_plan([lone, task], catalog, episodes=1, conditions=("switch:5", "given", "empty"))
    assert [(p.task_id, p.key.condition) for p in plan] == [
        (lone.id, "given"),
        (lone.id, "empty"),
        (task.id, "switch:5"),
        (task.id, "given"),
        (task.id, "empty"),
    ]


def test_one_switch_episode_rebuilt_alone_is_the_plans_under_its_style(catalog):
    # What the Gymnasium environment and the instruction checks call for one episode: the plan's own episode
    # of that task, key, scene and style, and the task it starts under.
    extended = catalog.get("spatial/s0/cookie-box-on-plate")
    for style in ("libero", "paper"):
        (planned,) = build_plan([extended], catalog, episodes=1, seed=4, conditions=("switch:5",), style=style)
        assert switch_episode(planned.key, extended, catalog, style, planned.scene, planned.watched) == planned
        assert switch_source(extended, catalog, style, planned.key.seed).id == planned.started_as
        assert planned.instruction == catalog.get(planned.started_as).instruction(style)
    paper = build_plan([extended], catalog, episodes=1, seed=4, conditions=("switch:5",), style="paper")[0]
    again = switch_episode(paper.key, extended, catalog, "libero", paper.scene, paper.watched)
    assert paper.instruction != again.instruction
    # an original starts under one of several scene mates, drawn by the episode's seed
    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    plan = build_plan([original], catalog, episodes=8, conditions=("switch:5",))
    assert [switch_source(original, catalog, "libero", p.key.seed).id for p in plan] == [p.started_as for p in plan]
    assert len({p.started_as for p in plan}) > 1


def test_the_switch_note_asks_about_the_runs_own_style():
    # In LIBERO-PRO's package style 28 of its tasks (its originals) have no scene mate that sends another
    # sentence with another goal, so they have nothing to start under; in LangGap's styles every task has one.
    pro = load_catalog("libero-pro")
    tasks = list(pro)
    assert switch_note(tasks, pro, ("switch:5",), "libero") == ""
    assert switch_note(tasks, pro, ("switch:5",), "package").startswith("note: 28 task(s) have no other task")
