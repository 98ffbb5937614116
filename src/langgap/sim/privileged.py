"""Privileged state: simulator facts a scripted policy may read, as a flat dict of arrays.

Keys are `eef_pos`, `eef_quat` (xyzw), `gripper_qpos`, `body/<name>` (position + wxyz quaternion of
the root body of each object and fixture), `site/<entity>` (position of each region site) and
`joint/<name>` (qpos of each articulated fixture joint). Being plain arrays, it crosses a process
or network boundary unchanged, so a scripted policy can also be served remotely.
"""

from __future__ import annotations

import numpy as np


def privileged_state(env) -> dict[str, np.ndarray]:
    """The privileged state of a `TaskEnv` at its current simulator state."""
    inner = env.robosuite_env
    sim = env.sim
    robot = inner.robots[0]
    out: dict[str, np.ndarray] = {
        "eef_pos": np.array(sim.data.site_xpos[robot.eef_site_id]),
        "eef_mat": np.array(sim.data.site_xmat[robot.eef_site_id]).reshape(3, 3),
        "gripper_qpos": np.array([sim.data.qpos[i] for i in robot._ref_gripper_joint_pos_indexes]),
    }
    for name, obj in {**inner.objects_dict, **inner.fixtures_dict}.items():
        body_id = sim.model.body_name2id(obj.root_body)
        out[f"body/{name}"] = np.concatenate([sim.data.body_xpos[body_id], sim.data.body_xquat[body_id]])
    for name in inner.object_sites_dict:
        out[f"site/{name}"] = np.array(sim.data.get_site_xpos(name))
    for joint_name in sim.model.joint_names:
        if joint_name and any(joint_name.startswith(f) for f in inner.fixtures_dict):
            out[f"joint/{joint_name}"] = np.array([sim.data.get_joint_qpos(joint_name)]).ravel()
    return out
