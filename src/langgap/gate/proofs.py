"""Proofs that no policy can do a task: arguments that hold for every policy, stated with their assumptions.

A task is shown doable by a demonstration (the oracle's episodes, or a searched one). It is shown
impossible only by an argument that no sequence of actions meets its goal; that the oracle, or any
enumeration of strategies, fails shows nothing of the kind (such a task is *unproven*). The provers
here take a task and `Facts` read from the simulator at an episode's start (plain numbers, so their
logic is tested without MuJoCo) and return a `Proof`, or None when their bound is not exceeded. None
shows nothing either way.

* `out_of_reach`: every way to meet the goal needs an atom that can never hold: an object On or In a
  target farther from the arm's shoulder than the object's origin can be carried, or an articulated
  part moved that nothing the gripper holds can touch.
* `too_few_steps`: the grip site must travel farther (to the object, then with it to its target) than
  the controller lets it move in the task's step limit.

Both bound distances from above (reach) or below (travel) with numbers a reader can check: every
figure the argument uses is in the proof's text, and so is every assumption it rests on.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from langgap.bddl import Predicate
from langgap.catalog.task import Task
from langgap.errors import LangGapError
from langgap.goals import Atom, Goal, Not, Or, atoms

# Franka Emika Panda datasheet: "maximum reach 855 mm", from the shoulder (joint 2's axis, 333 mm above
# the base) to the flange; the hand is extra (measured in the simulator: `Facts.hand`).
PANDA_REACH_M = 0.855
# robosuite's OSC_POSE controller, which LIBERO uses (robosuite/controllers/config/osc_pose.json): actions
# are clipped to [-1, 1] (input_max 1) and scaled to at most 0.05 m per axis (output_max), the furthest
# the position target is set from the hand in one control step.
OSC_STEP_M = 0.05
MAX_STEP_M = OSC_STEP_M * math.sqrt(3)
# LIBERO's predicates (libero/libero/envs): On an object, the origins within 3 cm horizontally and the
# object's not below the target's; On a region, the origin within the site's half-sizes in its frame,
# from 5 mm below its top face to 10 cm above; In a region, within the site's box, 1 cm lower at the floor.
ON_OBJECT_RADIUS_M = 0.03
ON_REGION_BELOW_M = 0.005
ON_REGION_ABOVE_M = 0.10
IN_REGION_FLOOR_M = 0.01
_PLACEMENTS = ("On", "In")
_STATES = ("Open", "Close", "Turnon", "Turnoff")

PLACEMENT_ASSUMPTIONS = (
    "LIBERO's predicates as its code states them: On an object means the origins within 3 cm horizontally, "
    "the object's not below the target's; On a region, the origin within the region site's half-sizes "
    "(up to 10 cm above its top face); In a region, the origin within the site's box. The target sets "
    "used here contain every point where they hold.",
)


@dataclass(frozen=True)
class Proof:
    """An argument that no policy meets a task's goal: what it claims, what it assumes, its numbers."""

    claim: str
    assumptions: tuple[str, ...]
    figures: dict[str, float | str] = field(default_factory=dict)

    def text(self) -> str:
        """The whole argument on one line: the claim, every figure, every assumption."""
        figures = "; ".join(f"{name} {_figure(value)}" for name, value in self.figures.items())
        assumptions = " ".join(f"({i}) {a}" for i, a in enumerate(self.assumptions, 1))
        return f"{self.claim} Figures: {figures}. Assumptions: {assumptions}"


def _figure(value: float | str) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


# -- facts -------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Body:
    """An object or fixture at t0: its origin (what LIBERO's predicates read), a world box around all of it
    (a fixture's jointed parts included), and for a fixture with joints, `travel`: how far any point of
    its jointed parts can move from where it is (0: no joints)."""

    origin: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    movable: bool
    travel: float = 0.0

    def __post_init__(self) -> None:
        for name in ("origin", "lo", "hi"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))

    def _corners(self) -> np.ndarray:
        pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        return np.where(pick == 0, self.lo, self.hi)

    @property
    def radius(self) -> float:
        """An upper bound on how far any point of the body is from its origin (the box's farthest corner)."""
        return self.farthest(self.origin)

    @property
    def diameter(self) -> float:
        """An upper bound on the distance between two points of the body (its box's diagonal)."""
        return float(np.linalg.norm(self.hi - self.lo))

    def distance(self, point: np.ndarray) -> float:
        """A lower bound on the distance from `point` to any point of the body (0 inside its box)."""
        point = np.asarray(point, dtype=np.float64)
        return float(np.linalg.norm(np.maximum(0.0, np.maximum(self.lo - point, point - self.hi))))

    def farthest(self, point: np.ndarray) -> float:
        """An upper bound on the distance from `point` to any point of the body (its box's farthest corner)."""
        return float(np.linalg.norm(self._corners() - np.asarray(point, dtype=np.float64), axis=1).max())


@dataclass(frozen=True)
class Site:
    """A region site at t0: its centre and half-sizes (LIBERO's `size`), the entity it belongs to, and
    whether it is bound to a joint (a drawer's inside moves with the drawer)."""

    pos: np.ndarray
    size: np.ndarray
    owner: str
    jointed: bool = False

    def __post_init__(self) -> None:
        for name in ("pos", "size"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))


@dataclass(frozen=True)
class Facts:
    """What the provers read from the simulator at an episode's start (after settling).

    `shoulder`: the arm's shoulder (joint 2's axis), world frame; `hand`: from the flange to the farthest
    point of the hand and fingers; `eef`: the grip site; `grip_span`: from the grip site to the farthest
    point of the hand and fingers; `bodies`: every object and fixture; `sites`: every region site;
    `holding`: the goal's atoms that hold at t0."""

    shoulder: np.ndarray
    hand: float
    eef: np.ndarray
    grip_span: float
    bodies: Mapping[str, Body]
    sites: Mapping[str, Site]
    holding: frozenset[Predicate] = frozenset()
    init_index: int = 0

    def __post_init__(self) -> None:
        for name in ("shoulder", "eef"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.float64))

    @property
    def gripper_reach(self) -> float:
        """How far from the shoulder any point of the gripper can be: the arm's reach plus the hand."""
        return PANDA_REACH_M + self.hand

    def widest(self, besides: str = "") -> float:
        """The largest diameter of a loose object other than `besides` (0 when there is none): how much
        farther than the gripper an object it holds can touch."""
        return max((b.diameter for n, b in self.bodies.items() if b.movable and n != besides), default=0.0)

    def carriers(self, besides: str = "") -> dict[str, Body]:
        """The fixtures with joints (but `besides`) that the gripper, or a loose object it holds, can touch:
        their jointed parts may move, and push or carry what they touch (a drawer what lies in it)."""
        held = self.gripper_reach + self.widest()
        return {
            n: b
            for n, b in self.bodies.items()
            if n != besides and b.travel > 0.0 and b.distance(self.shoulder) <= held
        }

    def touch(self, besides: str = "") -> float:
        """How far from the shoulder anything that moves can touch another body: the gripper, a loose object
        it holds (but `besides`), or a jointed part it moves (anywhere its fixture's box reaches, moved by
        the joints' travel)."""
        moved = (b.farthest(self.shoulder) + b.travel for b in self.carriers(besides).values())
        return max([self.gripper_reach + self.widest(besides), *moved])

    def near(self, besides: str = "") -> float:
        """How far from the grip site anything that moves with it can touch another body: the hand's span
        plus the widest loose object it may hold (but `besides`), or a jointed part's fixture it pushes."""
        parts = (b.diameter for b in self.carriers(besides).values())
        return self.grip_span + max([self.widest(besides), *parts])


# -- target sets -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Target:
    """A set that contains every origin where a placement atom holds: a ball (`column` False) or a
    vertical half-cylinder rising from `centre` (LIBERO's On an object)."""

    centre: np.ndarray
    radius: float
    column: bool = False

    def distance(self, point: np.ndarray) -> float:
        """A lower bound on the distance from `point` to any point of the set (0 inside it)."""
        delta = np.asarray(point, dtype=np.float64) - self.centre
        if not self.column:
            return max(0.0, float(np.linalg.norm(delta)) - self.radius)
        across = max(0.0, float(np.linalg.norm(delta[:2])) - self.radius)
        below = max(0.0, float(-delta[2]))  # the set lies at and above the centre's height
        return math.hypot(across, below)


def _target(facts: Facts, predicate: Predicate) -> Target | None:
    """A set that contains every origin where `predicate` (On or In) can hold, wherever its target goes
    (None: the target is unknown, or a loose object something can move)."""
    name, place = predicate.args
    if place in facts.sites:
        site = facts.sites[place]
        size = site.size
        if predicate.name == "In":
            radius = float(np.linalg.norm(size)) + IN_REGION_FLOOR_M
        else:
            height = max(abs(size[2] - ON_REGION_BELOW_M), size[2] + ON_REGION_ABOVE_M)
            radius = math.sqrt(size[0] ** 2 + size[1] ** 2 + height**2)
        owner = facts.bodies.get(site.owner)
        if owner is not None and owner.movable and not _untouchable(facts, site.owner, besides=site.owner):
            return None  # a region of a loose object (a basket's inside) goes where the object goes
        if site.jointed and not _untouchable(facts, site.owner, besides=site.owner):
            # a drawer's inside moves with the drawer: at most its fixture's travel
            if owner is None or not math.isfinite(owner.travel):
                return None
            radius += owner.travel
        return Target(site.pos, radius)
    if predicate.name == "On" and place in facts.bodies and place != name:
        body = facts.bodies[place]
        if body.movable and not _untouchable(facts, place, besides=place):
            return None
        return Target(body.origin, ON_OBJECT_RADIUS_M, column=True)
    return None


def _untouchable(facts: Facts, name: str, besides: str = "") -> bool:
    """True when nothing that moves (but `besides`) can touch body `name`: it stays where it is."""
    body = facts.bodies.get(name)
    return body is not None and body.distance(facts.shoulder) > facts.touch(besides)


def _owner(facts: Facts, name: str) -> str:
    """The body whose joint decides an Open/Close/Turnon/Turnoff atom on `name` (empty: unknown)."""
    if name in facts.bodies:
        return name
    site = facts.sites.get(name)
    return site.owner if site is not None and site.owner in facts.bodies else ""


# -- the three-valued goal ---------------------------------------------------------------------------


def _never(goal: Goal, impossible: set[Predicate]) -> bool | None:
    """Kleene's logic over the goal: False when it cannot hold given atoms in `impossible` never hold,
    True when it holds whatever the others do, None when undecided. (`Then` needs all its parts.)"""
    if isinstance(goal, Atom):
        return False if goal.predicate in impossible else None
    if isinstance(goal, Not):
        inner = _never(goal.part, impossible)
        return None if inner is None else not inner
    values = [_never(p, impossible) for p in goal.parts]
    if isinstance(goal, Or):
        return True if True in values else (False if all(v is False for v in values) else None)
    return False if False in values else (True if all(v is True for v in values) else None)


def _least(goal: Goal, need: Callable[[Predicate], float]) -> float:
    """A lower bound on the grip site's travel to meet `goal`, from each atom's (`need`): every part of a
    conjunction (or order) is needed, one part of a disjunction, nothing can be said of a negation."""
    if isinstance(goal, Atom):
        return need(goal.predicate)
    if isinstance(goal, Not):
        return 0.0
    values = [_least(p, need) for p in goal.parts]
    return min(values) if isinstance(goal, Or) else max(values)


# -- out of reach ------------------------------------------------------------------------------------

MOVED_BY_TOUCH = (
    "An object moves only while the gripper, a loose object the gripper holds, or a jointed part (a drawer, "
    "a door) the gripper or what it holds moves, touches it; a jointed part moves only while the gripper or "
    "what it holds touches it. A pushing chain (a held object pushes a second that pushes a third), a throw, "
    "a toppling or a roll could break this, so the bound is stated with this assumption."
)
REACH_ASSUMPTIONS = (
    "The robot's base does not move (LIBERO mounts the arm on a fixed pedestal), nor do the fixtures but "
    "for their jointed parts.",
    f"No point of the gripper is farther from the shoulder than the Panda's maximum reach, {PANDA_REACH_M} m "
    "from the shoulder to the flange (Franka's datasheet), plus the hand's length from the flange to its "
    "farthest point (measured in the simulator).",
    MOVED_BY_TOUCH,
    *PLACEMENT_ASSUMPTIONS,
)


def _placement_out_of_reach(facts: Facts, predicate: Predicate, figures: dict) -> bool:
    """Whether an On/In atom can never hold: its object stays out of its target set, or cannot be carried
    as far as the target set."""
    name = predicate.args[0]
    target = _target(facts, predicate)
    body = facts.bodies.get(name)
    if body is None or target is None or target.distance(body.origin) <= 0.0:
        return False  # unknown, a target that may come to the object, or the object there already
    if not body.movable or _untouchable(facts, name, besides=name):
        figures[f"{predicate}: {name} is never touched (its nearest point from the shoulder, m)"] = body.distance(
            facts.shoulder
        )
        figures[f"{predicate}: so its origin stays this far from the target set, m"] = target.distance(body.origin)
        return True
    far = target.distance(facts.shoulder)
    carried = facts.touch(name) + body.radius  # its farthest point touched, its origin at most its extent on
    if far <= carried:
        return False
    figures[f"{predicate}: the target set's nearest point from the shoulder, m"] = far
    how = f"anything that moves touches {facts.touch(name):.3f} + its extent {body.radius:.3f}"
    figures[f"{predicate}: the farthest {name}'s origin can be carried ({how}), m"] = carried
    return True


def _state_out_of_reach(facts: Facts, predicate: Predicate, figures: dict) -> bool:
    """Whether an Open/Close/Turnon/Turnoff atom can never hold: it does not hold now, and nothing that moves
    can touch the fixture whose joint it reads."""
    owner = _owner(facts, predicate.args[0])
    if not owner or predicate in facts.holding or not _untouchable(facts, owner, besides=owner):
        return False
    nearest = facts.bodies[owner].distance(facts.shoulder)
    figures[f"{predicate}: {owner}'s nearest point from the shoulder, m"] = nearest
    return True


def out_of_reach(task: Task, facts: Facts) -> Proof | None:
    """A proof that the goal needs an atom that can never hold, because its target, or the part it moves,
    lies beyond anything the gripper can reach (None: no atom is that far)."""
    figures: dict[str, float | str] = {}
    tests = {**dict.fromkeys(_PLACEMENTS, _placement_out_of_reach), **dict.fromkeys(_STATES, _state_out_of_reach)}
    impossible = {
        p for p in atoms(task.goal) if p not in facts.holding and p.name in tests and tests[p.name](facts, p, figures)
    }
    if not impossible or _never(task.goal, impossible) is not False:
        return None
    never = ", ".join(str(p) for p in sorted(impossible, key=str))
    claim = (
        f"Out of reach, on init state {facts.init_index}: {never} can never hold, and the goal {task.goal} "
        f"cannot hold without it. The gripper reaches at most {facts.gripper_reach:.3f} m from the shoulder; "
        f"anything that moves touches at most {facts.touch():.3f} m from it."
    )
    shown = {
        "shoulder (x, y, z)": _point(facts.shoulder),
        "arm's reach, shoulder to flange, m": PANDA_REACH_M,
        "hand, flange to its farthest point, m": facts.hand,
        "widest loose object, m": facts.widest(),
        **figures,
    }
    return Proof(claim, REACH_ASSUMPTIONS, shown)


# -- too few steps -----------------------------------------------------------------------------------

STEPS_ASSUMPTIONS = (
    f"The grip site moves at most {MAX_STEP_M:.4f} m per control step: the OSC target is clipped to "
    f"{OSC_STEP_M} m per axis from the hand (robosuite's OSC_POSE output_max, actions clipped to [-1, 1]), "
    "and the hand does not overshoot its target.",
    MOVED_BY_TOUCH + " Nor does anything slide, roll or fall on toward its target once nothing touches it.",
    "The robot's base and the fixtures do not move, but for the fixtures' jointed parts.",
    *PLACEMENT_ASSUMPTIONS,
)


def _travel(facts: Facts, predicate: Predicate, figures: dict) -> float:
    """A lower bound on the grip site's travel before `predicate` holds (0 when nothing can be said)."""
    if predicate in facts.holding:
        return 0.0
    if predicate.name in _STATES:
        owner = _owner(facts, predicate.args[0])
        if not owner:
            return 0.0
        near = facts.near(owner)
        need = max(0.0, facts.bodies[owner].distance(facts.eef) - near)
        if need > 0.0:
            figures[f"{predicate}: the grip site to within {near:.3f} of {owner}, m"] = need
        return need
    name = predicate.args[0] if predicate.name in _PLACEMENTS else ""
    body, target = facts.bodies.get(name), _target(facts, predicate) if name else None
    if body is None or target is None or target.distance(body.origin) <= 0.0:
        return 0.0
    # Whenever the object moves, something within `near` of the grip site touches it, its origin at most
    # its extent from there: the grip site comes that close to where the object starts and to where it ends.
    near = facts.near(name) + body.radius
    to_object = max(0.0, float(np.linalg.norm(facts.eef - body.origin)) - near)
    carry = target.distance(body.origin)
    with_it = max(0.0, carry - 2 * near)
    if to_object + with_it > 0.0:
        figures[f"{predicate}: the grip site to within {near:.3f} of {name}'s origin, m"] = to_object
        figures[f"{predicate}: {name}'s origin to the target set ({carry:.3f}) less twice {near:.3f}, m"] = with_it
    return to_object + with_it


def too_few_steps(task: Task, facts: Facts) -> Proof | None:
    """A proof that the grip site cannot travel as far as the goal needs within the task's step limit
    (None: the travel it must make fits in the step limit)."""
    figures: dict[str, float | str] = {}
    travel = _least(task.goal, lambda p: _travel(facts, p, figures))
    steps = travel / MAX_STEP_M
    if steps <= task.max_steps:
        return None
    claim = (
        f"Too few steps, on init state {facts.init_index}: the goal {task.goal} needs the grip site to travel "
        f"at least {travel:.3f} m (to each object it must move, then with it to its target, in straight lines), "
        f"{steps:.1f} control steps at {MAX_STEP_M:.4f} m each, more than the task's {task.max_steps}."
    )
    shown = {
        "grip site at t0 (x, y, z)": _point(facts.eef),
        "grip site to the hand's farthest point, m": facts.grip_span,
        "widest loose object, m": facts.widest(),
        "largest step, m": MAX_STEP_M,
        **figures,
    }
    return Proof(claim, STEPS_ASSUMPTIONS, shown)


PROVERS: tuple[Callable[[Task, Facts], Proof | None], ...] = (out_of_reach, too_few_steps)


def prove(task: Task, facts: Facts) -> Proof | None:
    """The first prover's proof that `task` is impossible from the state `facts` describe (None: none)."""
    for prover in PROVERS:
        proof = prover(task, facts)
        if proof is not None:
            return proof
    return None


def _point(point: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.3f}" for v in point) + ")"


# -- reading the facts from the simulator ------------------------------------------------------------


def read_facts(env, init_index: int) -> Facts:
    """The facts of `env` (a `TaskEnv` built with privileged observations) at its current state."""
    from langgap.policies.oracle.scene import Scene
    from langgap.sim.privileged import privileged_state

    scene = Scene(privileged_state(env))
    inner = env.robosuite_env
    robot = inner.robots[0]
    model, data = env.sim.model, env.sim.data
    shoulder = np.array(data.xanchor[model.joint_name2id(robot.robot_joints[1])])
    flange = np.array(data.xpos[model.body_name2id(robot.robot_model.eef_name)])
    corners = _hand_corners(env, model.body_name2id(robot.robot_model.eef_name))
    bodies = {}
    for name in scene.entities:
        box = scene.bbox(name)
        body = Body(scene.pos(name), box[:3], box[3:], scene.movable(name))
        fixture = inner.fixtures_dict.get(name)
        joints = [j for j in (getattr(fixture, "joints", None) or []) if j in model.joint_names]
        bodies[name] = replace(body, travel=_travel_of(env, joints, body.diameter)) if joints else body
    sites = {}
    for name in scene.regions:
        region = scene.region(name)
        site = inner.object_sites_dict[name]
        sites[name] = Site(region.pos, region.size, site.parent_name, bool(site.joints))
    goal_atoms = atoms(env.task.goal)
    return Facts(
        shoulder=shoulder,
        hand=float(np.linalg.norm(corners - flange, axis=1).max()),
        eef=scene.eef_pos,
        grip_span=float(np.linalg.norm(corners - scene.eef_pos, axis=1).max()),
        bodies=bodies,
        sites=sites,
        holding=frozenset(p for p in goal_atoms if env.predicate_holds(p)),
        init_index=init_index,
    )


def _travel_of(env, joints: list[str], diameter: float) -> float:
    """An upper bound on how far any point of a fixture's jointed parts moves over its joints' ranges: a
    slide's range; for a hinge, the box's diameter (no point is farther from the axis) times the chord of
    its angle range, at most 2. Summed over the joints; infinite for an unlimited slide."""
    import mujoco

    model = env.sim.model._model
    travel = 0.0
    for joint in joints:
        index = env.sim.model.joint_name2id(joint)
        low, high = model.jnt_range[index]
        span = float(high - low) if model.jnt_limited[index] else math.inf
        if model.jnt_type[index] == mujoco.mjtJoint.mjJNT_SLIDE:
            travel += span
        else:
            travel += diameter * min(2.0, span)
    return travel


def _hand_corners(env, flange_body: int) -> np.ndarray:
    """Corners (n, 3) of boxes around every collision geom of the hand and fingers (the flange's subtree)."""
    model = env.sim.model._model
    data = env.sim.data._data
    bodies = {flange_body}
    for body in range(flange_body + 1, model.nbody):
        if model.body_parentid[body] in bodies:
            bodies.add(body)
    collides = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    geoms = np.flatnonzero(np.isin(model.geom_bodyid, list(bodies)) & collides)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
    corners = []
    for geom in geoms:
        rot = data.geom_xmat[geom].reshape(3, 3)
        local = model.geom_aabb[geom, :3] + signs * model.geom_aabb[geom, 3:]
        corners.append(data.geom_xpos[geom] + local @ rot.T)
    return np.concatenate(corners)


def prove_tasks(tasks: list[Task], inits: int) -> dict[str, Proof]:
    """Proofs that tasks are impossible on every init state 0..`inits`-1, each state read from the simulator
    as the gate's episode starts (after settling): task id -> proof, for the tasks that have one. Tasks of
    one scene share a simulator; a task the simulator cannot build has none."""
    from langgap.sim.env import EnvOptions, TaskEnv

    found = {}
    env = None
    try:
        for task in sorted(tasks, key=lambda t: (t.suite, t.scene_task)):
            try:
                if env is not None and env.can_switch_to(task):
                    env.switch_task(task)
                else:
                    if env is not None:
                        env.close()
                    env = None
                    env = TaskEnv(task, EnvOptions(privileged=True))
                proof = _prove_on(env, task, inits)
            except LangGapError:
                continue
            if proof is not None:
                found[task.id] = proof
    finally:
        if env is not None:
            env.close()
    return found


def _prove_on(env, task: Task, inits: int) -> Proof | None:
    from langgap.engine.plan import episode_seed

    proofs = []
    for index in range(max(1, min(inits, len(env.init_states)))):
        env.reset(index, seed=episode_seed(0, index), render=False)  # the gate's episode's start
        env.settle()
        proof = prove(task, read_facts(env, index))
        if proof is None:
            return None
        proofs.append(proof)
    if len(proofs) == 1:
        return proofs[0]
    scope = f"On each of init states 0–{len(proofs) - 1} a proof holds (each checked); init state 0's: "
    return replace(proofs[0], claim=scope + proofs[0].claim)
