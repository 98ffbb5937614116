"""What reaches the policy under each instruction style is the style's sentence, and the one the run stores."""

from __future__ import annotations

import json
from collections import defaultdict

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.catalog.task import RUN_STYLES
from langgap.engine.evaluate import evaluate
from langgap.engine.plan import switch_source
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.records import EpisodeKey
from langgap.store import RunStore
from tests.test_external import short_copy

# An original and two of its LIBERO-PRO perturbations: the three styles send different sentences to each
# (libero = package for the original, libero = paper for the perturbations), so no style passes for another.
TASKS = ("spatial/s1/black-bowl-1-on-plate", "spatial/s1/pro-lan", "spatial/s1/pro-task")
SWITCH_AT = 5


@pytest.fixture(scope="module")
def short_pro(tmp_path_factory) -> str:
    return short_copy(tmp_path_factory.mktemp("catalog"), "libero-pro", set(TASKS))


@pytest.mark.parametrize("style", RUN_STYLES)
def test_the_policy_is_sent_its_styles_sentence_at_reset_and_every_step_as_stored(short_pro, style, tmp_path):
    log, run = tmp_path / "sent.jsonl", tmp_path / "run"
    spec = RunSpec.create("tests.support.policies:SentInstructionRecorder", policy_args={"path": str(log)},
                          catalog=short_pro, tasks=",".join(TASKS), episodes=1,
                          conditions=("given", f"switch:{SWITCH_AT}"), style=style)  # fmt: skip
    summary = evaluate(spec, run, ExecutionOptions(workers=0, progress=False))
    sent = defaultdict(list)
    for line in log.read_text().splitlines():
        query = json.loads(line)
        sent[EpisodeKey(*query["key"])].append(query)
    with RunStore.open(run) as store:
        records = store.records()
    assert len(records) == summary.planned == summary.ran and set(sent) == {r.key for r in records}

    catalog = load_catalog(short_pro)
    for record in records:
        task, queries = catalog.get(record.task_id), sent[record.key]
        if record.condition == "given":
            wanted = [(0, task.instruction(style))]
        else:
            first = switch_source(task, catalog, style, record.seed)
            wanted = [(0, first.instruction(style)), (SWITCH_AT, task.instruction(style))]
        assert [(step, text) for step, text in record.instructions] == wanted, record.key
        assert record.instruction == wanted[0][1], record.key
        assert {q["reset"] for q in queries} == {record.instruction}, record.key
        # One query per policy step (chunk 1): query i is sent the instruction in force at step i.
        assert len(queries) == record.policy_calls == record.steps, record.key
        in_force = [next(text for step, text in reversed(wanted) if step <= i) for i in range(len(queries))]
        assert [q["sent"] for q in queries] == in_force, record.key
