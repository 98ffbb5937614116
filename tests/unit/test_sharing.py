"""Which planned episodes share a rollout (`langgap.engine.sharing`), and what an instruction-blind policy is told."""

from __future__ import annotations

from dataclasses import replace

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.catalog.files import scene_key
from langgap.engine.context import task_context
from langgap.engine.plan import PlannedEpisode
from langgap.engine.sharing import SharedRollout, rollout_key, share_rollouts
from langgap.policies.base import config_hash, policy_config
from langgap.policies.oracle.policy import BlindPolicy, OraclePolicy
from langgap.policies.simple import NoopPolicy, RandomPolicy
from langgap.records import EpisodeKey

SIBLINGS = ("spatial/s0/black-bowl-1-on-plate", "spatial/s0/black-bowl-2-on-plate", "spatial/s0/ramekin-on-stove")


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def _planned(catalog, task_id: str, *, seed: int = 0, condition: str = "given", instruction: str | None = None):
    task = catalog.get(task_id)
    key = EpisodeKey(task_id, 0, seed, condition)
    return PlannedEpisode(
        key,
        task.instruction("libero") if instruction is None else instruction,
        scene=scene_key(task),
        watched=tuple(t.id for t in catalog.scene_mates(task)),
    )


@pytest.mark.parametrize("policy", [BlindPolicy, NoopPolicy, RandomPolicy])
def test_sibling_tasks_of_a_blind_policy_share_whatever_their_instruction(catalog, policy):
    spec = policy().spec
    plan = [_planned(catalog, t) for t in SIBLINGS] + [
        _planned(catalog, SIBLINGS[0], condition="empty", instruction="")
    ]
    (item,) = share_rollouts(plan, catalog, spec, "libero")
    assert isinstance(item, SharedRollout) and item.members == tuple(plan)
    assert rollout_key(_planned(catalog, SIBLINGS[0], seed=1), catalog, spec, "libero") != rollout_key(
        plan[0], catalog, spec, "libero"
    )


def test_what_cannot_be_cut_from_a_shared_rollout_runs_on_its_own(catalog):
    blind = BlindPolicy.spec
    planned = _planned(catalog, SIBLINGS[0])
    assert rollout_key(planned, catalog, blind, "libero") is not None
    assert rollout_key(replace(planned, film=True), catalog, blind, "libero") is None
    # A switch asks the policy again at its step: only episodes switching at the same steps share.
    switched = rollout_key(replace(planned, changes=((5, "other"),)), catalog, blind, "libero")
    assert switched is not None and switched != rollout_key(planned, catalog, blind, "libero")
    assert switched == rollout_key(replace(planned, changes=((5, "another"),)), catalog, blind, "libero")
    assert switched != rollout_key(replace(planned, changes=((6, "other"),)), catalog, blind, "libero")
    assert rollout_key(planned, catalog, OraclePolicy.spec, "libero") is None
    plan = [_planned(catalog, t) for t in SIBLINGS]
    assert share_rollouts(plan, catalog, OraclePolicy.spec, "libero") == plan


def test_a_blind_policy_is_told_nothing_that_tells_siblings_apart(catalog):
    contexts = [
        task_context(catalog.get(t), catalog, init_index=3, seed=3, condition=c).for_policy(BlindPolicy.spec)
        for t in SIBLINGS
        for c in ("given", "nonsense")
    ]
    assert len(set(contexts)) == 1
    (told,) = set(contexts)
    assert told.instruction == "" and told.privileged.source_goal == ("(On akita_black_bowl_1 plate_1)",)
    assert told.privileged.goal == () and told.privileged.task_id == ""
    # The oracle reads its instruction and is told its own goal.
    oracle = task_context(catalog.get(SIBLINGS[1]), catalog, init_index=3, seed=3).for_policy(OraclePolicy.spec)
    assert oracle.instruction and oracle.privileged.task_id == SIBLINGS[1]


def test_the_declaration_leaves_a_policys_config_hash_as_it_was():
    """Stored runs keep their `policy_config_hash`: `noop`'s as before the declaration existed, and `blind`'s."""
    assert config_hash(policy_config(NoopPolicy())) == "bcf1029da64c98fb"
    assert config_hash(policy_config(BlindPolicy())) == "a627e8aac3365afa"
