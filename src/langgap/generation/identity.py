"""Gate trials that repeat a LangGap-99 task's exactly (`SAME_TRIAL`): a task whose trial would take the same
oracle episodes takes that task's verdict (`gate_from`) instead of being re-run."""

from __future__ import annotations

from dataclasses import replace

from langgap.audit.findings import scene_findings
from langgap.catalog.catalog import DEFAULT_CATALOG
from langgap.catalog.files import task_bddl_text
from langgap.catalog.task import Task
from langgap.vocabulary import Dimension


def original_in(source: Task, catalog: str) -> Task:
    """LangGap-99's original `source` as a task of `catalog`: the same task, so it takes LangGap-99's verdict."""
    return replace(source, catalog=catalog, gate=None, gate_from=f"{DEFAULT_CATALOG}:{source.id}")


def same_trial(task: Task, source: Task, text: str, *, starts_from_source: bool) -> str | None:
    """`langgap99:<source id>` when `task`'s gate trial would repeat its source's exactly: its file `text`
    differs from the source's only in `(:language)`, it starts from the source's init states
    (`starts_from_source`), and its goal and step limit are the source's. None otherwise: the task needs its
    own verdict."""
    same = (
        starts_from_source
        and task.goal == source.goal
        and task.max_steps == source.max_steps
        and not any(
            f.name == "changes the scene"
            for f in scene_findings(task.id, Dimension.LANGUAGE, text, task_bddl_text(source))
        )
    )
    return f"{DEFAULT_CATALOG}:{source.id}" if same else None
