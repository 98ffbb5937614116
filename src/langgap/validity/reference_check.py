"""The audit's reference check: on every init state, does each referring expression of a task's sentence pick
the object its goal names, from the robot's viewpoint and from the agentview camera's?

For each task, the expressions that must tell objects apart (`langgap.validity.references`: a category the
scene holds more than once, or one with a relation or side) are resolved on the scene as a policy first sees
it (init state k, seed 0, after the settle steps), with the objects' positions and LIBERO's `On` / `In`
decided by the simulator. An expression picks the goal's object, another, none, or several; the last three
are findings, with the init states on which they happen. An expression the reader does not follow is counted
as unread, never judged. Tasks set in the same scene with the same init states share one simulator (their
goals move nothing at t0).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import files
from langgap.catalog.task import Task
from langgap.validity.audit import Finding
from langgap.validity.references import (
    Layout,
    Mention,
    View,
    expected_entity,
    instances,
    mentions,
    outcome,
    resolve,
)
from langgap.validity.starts import SEED, inits_text

CAMERA = "agentview"
VIEWS = ("robot", "camera")
OUTCOME_FINDING = {
    "other": "sentence picks another object",
    "none": "sentence picks no object",
    "ambiguous": "sentence is ambiguous",
}
STYLES = ("libero", "paper")


@dataclass
class Checked:
    """What the check read in a catalog's tasks: expressions judged, and those it could not read (by task)."""

    judged: int = 0
    unread: dict[str, list[str]] = field(default_factory=dict)


def needs_resolving(mention: Mention, scene: BddlProblem) -> bool:
    """Whether `mention` must tell objects apart: a moved, target or excluded object (not a landmark, not "both")
    whose category the scene holds more than once. (Of a category the scene holds once, the noun says which; what
    follows it may as well be where it goes.)"""
    if mention.role == "landmark" or mention.plural:
        return False
    return len(instances(mention.category, scene)) > 1


def _expressions(task: Task, scene: BddlProblem) -> list[tuple[str, Mention, list[Mention]]]:
    """(sentence, mention, all its mentions) for each expression to resolve, over the task's distinct sentences."""
    out = []
    for sentence in dict.fromkeys(task.instruction(style) for style in STYLES):
        found = mentions(sentence, scene)
        out += [(sentence, m, found) for m in found if needs_resolving(m, scene)]
    return out


def _layout_group(task: Task) -> tuple[str, str]:
    """Tasks with equal keys start with the same layout: the same scene (outside the task's sections) and init
    states file; their goals may differ (they do not move anything at t0)."""
    return files.scene_key(task), str(files.init_states_path(task))


def _views(env) -> dict[str, View]:
    """The robot's viewpoint (its base's axes: forward x, left y) and the agentview camera's (its image's right;
    it looks along its -z)."""
    import mujoco

    model, data = env.sim.model._model, env.sim.data._data
    base = data.xmat[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "robot0_base")].reshape(3, 3)
    camera = data.cam_xmat[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, CAMERA)].reshape(3, 3)

    def flat(v: np.ndarray) -> np.ndarray:
        v = np.array([v[0], v[1], 0.0])
        return v / np.linalg.norm(v)

    return {
        "robot": View("robot", right=flat(-base[:, 1]), forward=flat(base[:, 0])),
        "camera": View("camera", right=flat(camera[:, 0]), forward=flat(-camera[:, 2])),
    }


def _layout(env, scene: BddlProblem) -> Layout:
    """The scene at the current state: positions of objects, fixtures and regions, which `On` / `In` hold."""
    from langgap.sim.privileged import privileged_state

    state = privileged_state(env)
    positions = {k[len("body/") :]: np.array(v[:3]) for k, v in state.arrays.items() if k.startswith("body/")}
    positions |= {k[len("site/") :]: np.array(v) for k, v in state.arrays.items() if k.startswith("site/")}
    receivers = [n for n in (*scene.objects, *(r.entity for r in scene.regions)) if n in positions]
    supports = set()
    for obj in scene.objects:
        for receiver in receivers:
            if receiver != obj and any(_holds(env, name, obj, receiver) for name in ("On", "In")):
                supports.add((obj, receiver))
    center = next((v for k, v in positions.items() if k.endswith("table_center")), None)
    return Layout(positions, frozenset(supports), center)


def _holds(env, name: str, obj: str, receiver: str) -> bool:
    try:
        return env.predicate_holds(Predicate(name, (obj, receiver)))
    except Exception:  # a pair LIBERO's predicate cannot judge (a region it does not contain things in)
        return False


def reference_findings(
    tasks: list[Task], inits: int, progress: Callable[[str], None] = lambda _: None
) -> tuple[list[Finding], Checked]:
    """The reference check's findings on `tasks` over init states 0..`inits`-1, and what it read."""
    from langgap.sim.env import TaskEnv

    checked = Checked()
    scenes = {task.id: files.scene_problem(task) for task in tasks}  # parsed once: the loops below are per init
    todo: dict[str, list] = {}
    for task in tasks:
        for sentence, mention, found in _expressions(task, scenes[task.id]):
            if mention.unread:
                checked.unread.setdefault(task.id, []).append(f"{mention.phrase} (in {sentence!r})")
            else:
                todo.setdefault(task.id, []).append((sentence, mention, found))
    groups: dict[tuple[str, str], list[Task]] = {}
    for task in tasks:
        if task.id in todo:
            groups.setdefault(_layout_group(task), []).append(task)
    picks: dict[tuple, list[tuple[int, tuple[str, ...]]]] = {}
    for number, members in enumerate(groups.values(), 1):
        progress(f"[{number}/{len(groups)}] {members[0].id} and {len(members) - 1} other(s)")
        with TaskEnv(members[0]) as env:
            views = _views(env)
            count = min(inits, len(env.init_states))
            for index in range(count):
                env.reset(index, seed=SEED, render=False)
                env.settle()
                scene = scenes[members[0].id]  # the group's tasks share their scene's objects and placements
                layout = _layout(env, scene)
                resolved: dict[tuple[Mention, str], tuple[str, ...]] = {}  # tasks of a scene repeat expressions
                for task in members:
                    for sentence, mention, _ in todo[task.id]:
                        for view in VIEWS:
                            if (mention, view) not in resolved:
                                resolved[mention, view] = resolve(mention, scene, layout, views[view])
                            picks.setdefault((task.id, sentence, mention, view), []).append(
                                (index, resolved[mention, view])
                            )
    found = []
    for task in tasks:
        for sentence, mention, all_mentions in todo.get(task.id, []):
            checked.judged += 1
            expected = expected_entity(mention, all_mentions, task.goal, scenes[task.id])
            found += _judged(
                task, sentence, mention, expected, {v: picks[(task.id, sentence, mention, v)] for v in VIEWS}
            )
    return found, checked


def _judged(task: Task, sentence: str, mention: Mention, expected: str | None, by_view: dict) -> list[Finding]:
    """The findings of one expression: per outcome, the viewpoints and init states it happens on."""
    found = []
    for kind, name in OUTCOME_FINDING.items():
        parts = []
        for view, results in by_view.items():
            hit = [(i, picked) for i, picked in results if outcome(picked, expected) == kind]
            if hit:
                which = Counter(", ".join(picked) or "nothing" for _, picked in hit).most_common(1)[0][0]
                parts.append((view, [i for i, _ in hit], len(results), which))
        if not parts:
            continue
        views = " and ".join(
            f"from the {view}'s viewpoint on {inits_text(inits, total)}" for view, inits, total, _ in parts
        )
        picked = parts[0][3]
        goal = f", not the goal's {expected}" if expected and kind == "other" else ""
        detail = f"'{mention.phrase}' picks {picked}{goal} {views} — in {sentence!r}"
        found.append(Finding(name, task.id, detail))
    return found
