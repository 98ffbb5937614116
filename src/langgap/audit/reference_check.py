"""The audit's reference check: on every init state, does each referring expression of a task's sentence pick
the object its goal names, from the robot's viewpoint, from the agentview camera's (its raw, unrotated render)
and in the image a policy is given (that render rotated 180°, as openpi's and OpenVLA's LIBERO runners and
LangGap give it: the camera's picture mirrored left to right)?

For each task, the expressions that must tell objects apart (`langgap.audit.references`: a category the
scene holds more than once, or one with a relation or side) are resolved on the scene as a policy first sees
it (init state k, seed 0, after the settle steps), with the objects' positions and LIBERO's `On` / `In`
decided by the simulator. An expression picks the goal's object, another, none, or several; the last three
are findings, each with what the expression picks from every viewpoint on which init states. Every expression
found is judged or counted as unread: one with words the reader does not follow, or whose object the reader
cannot find in the goal (its role there), is unread, never judged nor left out. Tasks set in the same scene
with the same init states share one simulator (their goals move nothing at t0).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from langgap.audit.findings import Finding
from langgap.audit.references import (
    Layout,
    Mention,
    View,
    expected_entity,
    instances,
    mentions,
    outcome,
    resolve,
)
from langgap.audit.starts import SEED, inits_text
from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import files
from langgap.catalog.task import Task

CAMERA = "agentview"
VIEWS = ("robot", "camera", "policy image")
# How a finding names each viewpoint.
VIEW_NAMES = {"robot": "robot", "camera": "camera (raw render)", "policy image": "policy's image"}
OUTCOME_FINDING = {
    "other": "sentence picks another object",
    "none": "sentence picks no object",
    "ambiguous": "sentence is ambiguous",
}
STYLES = ("libero", "paper")


@dataclass
class Checked:
    """What the check read in a catalog's tasks, by task: the expressions judged and those it could not read
    (each with its sentence, and for an unread one why)."""

    judged: dict[str, list[str]] = field(default_factory=dict)
    unread: dict[str, list[str]] = field(default_factory=dict)

    @property
    def judged_count(self) -> int:
        return sum(map(len, self.judged.values()))

    @property
    def unread_count(self) -> int:
        return sum(map(len, self.unread.values()))


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
    """The robot's viewpoint (its base's axes: forward x, left y), the agentview camera's (its raw render's
    right, MuJoCo's camera x; it looks along its -z) and the policy's image's (that render rotated 180°: its
    right is the camera's left; MuJoCo's render comes bottom row first, so the rotation turns it upright and
    mirrors it, and what is nearer the camera stays in front)."""
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
        "policy image": View("policy image", right=flat(-camera[:, 0]), forward=flat(-camera[:, 2])),
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
        scene = scenes[task.id]
        for sentence, mention, found in _expressions(task, scene):
            expected = expected_entity(mention, found, task.goal, scene)
            if mention.unread or expected is None:
                why = "words not read" if mention.unread else f"no single {mention.category} of the goal in its role"
                checked.unread.setdefault(task.id, []).append(f"{mention.phrase} (in {sentence!r}: {why})")
            else:
                todo.setdefault(task.id, []).append((sentence, mention, expected))
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
        for sentence, mention, expected in todo.get(task.id, []):
            checked.judged.setdefault(task.id, []).append(f"{mention.phrase} (in {sentence!r})")
            by_view = {v: picks[(task.id, sentence, mention, v)] for v in VIEWS}
            of = len(instances(mention.category, scenes[task.id]))
            found += judged_findings(task.id, sentence, mention, expected, by_view, of)
    return found, checked


Picks = list[tuple[int, tuple[str, ...]]]  # (init state, the entities an expression picked on it)


def _named(picked: tuple[str, ...], expected: str, of: int) -> str:
    """What an expression picked among `of` objects, in words: `the goal's`, the entities, `neither` or `none`."""
    if picked == (expected,):
        return "the goal's"
    return ", ".join(picked) or ("neither" if of == 2 else "none")


def judged_findings(
    task: str, sentence: str, mention: Mention, expected: str, by_view: dict[str, Picks], of: int
) -> list[Finding]:
    """The findings of one expression of `task` naming one of `of` objects, the goal's `expected`, from what it
    picked per viewpoint (`by_view`): one per outcome that is a finding, naming what it picks most often with
    that outcome and, for every viewpoint, what it picks on which init states."""
    every = [picked for results in by_view.values() for _, picked in results]
    views = "; ".join(f"{VIEW_NAMES[view]}: {_picks_text(results, expected, of)}" for view, results in by_view.items())
    found = []
    for kind, name in OUTCOME_FINDING.items():
        hit = [picked for picked in every if outcome(picked, expected) == kind]
        if hit:
            picked = _named(Counter(hit).most_common(1)[0][0], expected, of)
            goal = f", not the goal's {expected}" if kind == "other" else ""
            found.append(Finding(name, task, f"'{mention.phrase}' picks {picked}{goal} — {views} — in {sentence!r}"))
    return found


def _picks_text(results: Picks, expected: str, of: int) -> str:
    """`plate_2 on init state(s) 0–49 (50 of 50)`: what was picked on which init states, the most frequent first."""
    by_pick: dict[tuple[str, ...], list[int]] = {}
    for index, picked in results:
        by_pick.setdefault(picked, []).append(index)
    ranked = sorted(by_pick.items(), key=lambda item: (-len(item[1]), item[1][0]))
    return ", ".join(f"{_named(picked, expected, of)} on {inits_text(inits, len(results))}" for picked, inits in ranked)
