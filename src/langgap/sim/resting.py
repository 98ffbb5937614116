"""`(Moved o)`: LangGap's own goal atom for "put it anywhere (but ...)", read off the simulator.

LIBERO's atoms say where an object is relative to a named place (`On`, `In`); a sentence such as "pick up
the bowl and place it anywhere but on the plate" allows every place, the bare table included. `(Moved o)`
holds when `o`

* was moved by the hand: a geom of the gripper touched it at some step since step 0 (LIBERO's own contact
  test) — a bowl carried off by the drawer it stands in, or by the box it stands on, was not put anywhere;
* lies more than `MOVED_M` from where it was at step 0 (its body origin, in 3-D): more than LIBERO's
  3 cm radius for one object on another, and more than its init regions are wide (2–5 cm: LIBERO starts an
  object anywhere inside such a box, so a smaller shift is not a new place);
* is out of the hand now: no geom of the gripper touches it — carried is not put;
* is at rest: its origin moves less than `RESTING_M_S` (1 mm per 20 Hz control step) — still falling,
  rolling or sliding is not put down yet.

A fixture never moves, so it is never `Moved`.
"""

from __future__ import annotations

import numpy as np

MOVED_M = 0.05
RESTING_M_S = 0.02


class Placements:
    """What `(Moved o)` needs from an episode's past: where every body was at step 0, and which objects the
    hand has touched since. `restart` at step 0, `observe` after every step."""

    def __init__(self, env):
        self.env = env  # the robosuite (LIBERO) environment
        self.start = np.zeros((0, 3))
        self.handled: set[str] = set()

    def restart(self) -> None:
        """Step 0: measure from the bodies' origins now; nothing handled yet (but what the hand touches now)."""
        self.start = np.array(self.env.sim.data.body_xpos, dtype=np.float64)
        self.handled = set()
        self.observe()

    def observe(self) -> None:
        """Note the objects the hand touches in the current state (one pass over the contacts, every step: the
        `ContactIndex` installed on the env lists the geoms touching the gripper's)."""
        env = self.env
        touching = np.concatenate([env.check_contact.partners(robot.gripper) for robot in env.robots])
        if touching.size:
            model = env.sim.model._model
            bodies = set(model.body_rootid[model.geom_bodyid[touching]].tolist())
            self.handled |= {name for name in env.objects_dict if env.obj_body_id[name] in bodies}

    def _in_hand(self, name: str) -> bool:
        obj = self.env.get_object(name)
        return any(self.env.check_contact(robot.gripper, obj) for robot in self.env.robots)

    def moved(self, name: str) -> bool:
        """Whether LIBERO object `name` was moved by the hand and now rests out of it, more than `MOVED_M` from
        where it was at step 0."""
        if name not in self.handled:  # fixtures and regions too: the hand moves objects only
            return False
        env = self.env
        body = env.obj_body_id[name]
        if np.linalg.norm(env.sim.data.body_xpos[body] - self.start[body]) <= MOVED_M or self._in_hand(name):
            return False
        speed = np.linalg.norm(env.sim.data.get_joint_qvel(env.get_object(name).joints[-1])[:3])
        return bool(speed < RESTING_M_S)
