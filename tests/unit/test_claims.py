"""The benchmark's own claims, checked on a validation's episodes."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.gate.claims import benchmark_claims
from tests.support.reports import episode

ORIGINAL, RAMEKIN = "spatial/s0/black-bowl-1-on-plate", "spatial/s0/ramekin-on-plate"


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def _record(task: str, init: int, *, success=True, t0="", at_start=(), kind="extended"):
    record = episode("spatial/s0/ramekin-on-plate", init, success=success)
    return dataclasses.replace(
        record, task_id=task, kind=kind, source=ORIGINAL, scene="libero_spatial/s0",
        t0_hash=t0 or f"state-{init}", goals_at_start=list(at_start),
    )  # fmt: skip


def _gate_episodes():
    return [_record(ORIGINAL, k, kind="original") for k in range(2)] + [_record(RAMEKIN, k) for k in range(2)]


def test_claims_hold_on_a_sound_scene(catalog):
    blind = [_record(ORIGINAL, k, kind="original") for k in range(2)]
    blind += [_record(RAMEKIN, k, success=False) for k in range(2)]
    claims = benchmark_claims(catalog, _gate_episodes(), blind)
    assert [(c.holds, c.checked) for c in claims] == [(True, 2), (True, 4), (True, 2), (True, 2)]


def test_each_claim_catches_its_violation(catalog):
    episodes = _gate_episodes()
    episodes[3] = dataclasses.replace(episodes[3], t0_hash="another state")  # RAMEKIN at init 1
    episodes[0] = dataclasses.replace(episodes[0], goals_at_start=[RAMEKIN])
    blind = [_record(ORIGINAL, 0, kind="original"), _record(ORIGINAL, 1, success=False, kind="original")]
    blind += [_record(RAMEKIN, 0, success=True), _record(RAMEKIN, 1, success=False)]
    same_state, nothing_at_t0, originals, never = benchmark_claims(catalog, episodes, blind)
    assert same_state.violations == [f"{ORIGINAL} init 1: 2 different t0 states"]
    assert nothing_at_t0.violations == [f"{ORIGINAL} init 0: {RAMEKIN}"]
    assert originals.violations == [f"{ORIGINAL} init 1: blind False, oracle True"]
    assert never.violations == [f"{RAMEKIN} init 0"]
    assert not any(c.holds for c in (same_state, nothing_at_t0, originals, never))
