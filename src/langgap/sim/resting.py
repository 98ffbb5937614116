"""`(Moved o)`: LangGap's own goal atom for "put it anywhere (but ...)", read off the simulator.

LIBERO's atoms say where an object is relative to a named place (`On`, `In`); a sentence such as "place
it anywhere but on the plate" allows every place, the bare table included. `(Moved o)` holds when `o`

* lies more than `MOVED_M` from where it was at step 0 (its body origin, in 3-D): more than LIBERO's
  3 cm radius for one object on another, and more than its init regions are wide (2–5 cm: LIBERO starts an
  object anywhere inside such a box, so a smaller shift is not a new place);
* is out of the hand: no geom of the gripper touches it (LIBERO's own contact test) — carried is not put;
* is at rest: its origin moves less than `RESTING_M_S` (1 mm per 20 Hz control step) — still falling,
  rolling or sliding is not put down yet.

A fixture never moves, so it is never `Moved`.
"""

from __future__ import annotations

import numpy as np

MOVED_M = 0.05
RESTING_M_S = 0.02


def start_positions(env) -> np.ndarray:
    """Every body's origin now (world frame, (nbody, 3)): the reference `moved_and_resting` measures from."""
    return np.array(env.sim.data.body_xpos, dtype=np.float64)


def moved_and_resting(env, name: str, start: np.ndarray) -> bool:
    """Whether LIBERO object `name` of robosuite env `env` lies more than `MOVED_M` from `start` (from
    `start_positions` at step 0), untouched by the gripper and at rest."""
    if name not in env.objects_dict:  # fixtures (and regions) stay where they are
        return False
    body = env.obj_body_id[name]
    if np.linalg.norm(env.sim.data.body_xpos[body] - start[body]) <= MOVED_M:
        return False
    obj = env.get_object(name)
    if any(env.check_contact(robot.gripper, obj) for robot in env.robots):
        return False
    speed = np.linalg.norm(env.sim.data.get_joint_qvel(obj.joints[-1])[:3])
    return bool(speed < RESTING_M_S)
