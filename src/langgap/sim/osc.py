"""robosuite's operational-space arm control for the substeps between two policy steps, without its overhead.

Between two actions robosuite runs its controller at every physics substep (25 per control step in
LIBERO) through several layers of Python: action-dimension checks that rebuild the action limits,
name-to-id lookups, each Jacobian computed twice (once for the velocity, once for the matrix),
torque limits and actuator ranges read anew. `OscSubsteps` holds what does not change within an
episode and computes each substep's torques and gripper controls with robosuite's own functions and
the same numpy operations on the same operands, so every bit of the result is robosuite's (a test
compares full simulator states over real rollouts). The policy step itself (new goal, robosuite's
bookkeeping buffers) still runs through robosuite.

With `compiled=True` the same equations run as one numba-compiled function on the arm's own
columns: a few times faster, and the same torques up to the last bits (LAPACK's and numpy's
orderings differ), which is why it serves only the `fast` stepping (see sim/stepping.py).

Only the configuration LIBERO uses is handled: one arm, `OperationalSpaceController` with fixed
impedance, delta actions, orientation control and no interpolators, and a one-dof gripper;
`OscSubsteps.supports` says whether an environment has it.
"""

from __future__ import annotations

import mujoco
import numba
import numpy as np
from robosuite.controllers.osc import OperationalSpaceController
from robosuite.utils.control_utils import nullspace_torques, opspace_matrices, orientation_error


class OscSubsteps:
    """Runs one non-policy substep of robosuite's control for the one robot of a robosuite environment."""

    def __init__(self, env, compiled: bool = False):
        self.compiled = compiled
        robot = env.robots[0]
        self.robot = robot
        self.controller = robot.controller
        sim = env.sim
        self.model, self.data = sim.model._model, sim.data._data
        controller = self.controller
        self.site = sim.model.site_name2id(controller.eef_name)
        self.qpos_index = controller.qpos_index
        self.qvel_index = controller.qvel_index
        self.torque_low, self.torque_high = robot.torque_limits
        self.arm_actuators = robot._ref_joint_actuator_indexes
        gripper = robot.gripper
        self.gripper_actuators = [sim.model.actuator_name2id(a) for a in gripper.actuators]
        ctrl_range = sim.model.actuator_ctrlrange[self.gripper_actuators]
        self.gripper_bias = 0.5 * (ctrl_range[:, 1] + ctrl_range[:, 0])
        self.gripper_weight = 0.5 * (ctrl_range[:, 1] - ctrl_range[:, 0])
        self.arm_dims = controller.control_dim
        self.mass_matrix = np.ndarray(shape=(self.model.nv, self.model.nv), dtype=np.float64, order="C")
        # the compiled path's buffers and index slices (the arm's joints are consecutive in LIBERO's models)
        self.jacobian = np.zeros((6, self.model.nv))
        self.arm_columns = _as_slice(self.qvel_index)
        self.arm_positions = _as_slice(self.qpos_index)

    @staticmethod
    def supports(env) -> bool:
        """Whether `env` runs the control configuration this class reproduces."""
        if len(env.robots) != 1:
            return False
        robot = env.robots[0]
        controller = robot.controller
        return (
            type(controller) is OperationalSpaceController
            and controller.impedance_mode == "fixed"
            and controller.use_delta
            and controller.use_ori
            and controller.interpolator_pos is None
            and controller.interpolator_ori is None
            and robot.has_gripper
            and robot.gripper.dof == 1
        )

    def controls(self, env) -> bool:
        """Whether this instance was built for `env`'s current simulator, robot and controller."""
        robot = env.robots[0]
        return self.robot is robot and self.controller is robot.controller and self.data is env.sim.data._data

    def control(self, action: np.ndarray) -> None:
        """Write the arm torques and gripper controls of one substep for the current goal and state
        (what `robot.control(action, policy_step=False)` writes)."""
        c, data = self.controller, self.data
        if self.compiled:
            self._control_compiled(action)
            return
        self._update_controller()
        # OperationalSpaceController.run_controller, without interpolators
        desired_pos = np.array(c.goal_pos)
        ori_error = orientation_error(np.array(c.goal_ori), c.ee_ori_mat)
        position_error = desired_pos - c.ee_pos
        vel_pos_error = -c.ee_pos_vel
        desired_force = np.multiply(np.array(position_error), np.array(c.kp[0:3])) + np.multiply(
            vel_pos_error, c.kd[0:3]
        )
        vel_ori_error = -c.ee_ori_vel
        desired_torque = np.multiply(np.array(ori_error), np.array(c.kp[3:6])) + np.multiply(vel_ori_error, c.kd[3:6])
        lambda_full, lambda_pos, lambda_ori, nullspace_matrix = opspace_matrices(
            c.mass_matrix, c.J_full, c.J_pos, c.J_ori
        )
        if c.uncoupling:
            decoupled_wrench = np.concatenate([np.dot(lambda_pos, desired_force), np.dot(lambda_ori, desired_torque)])
        else:
            decoupled_wrench = np.dot(lambda_full, np.concatenate([desired_force, desired_torque]))
        torques = np.dot(c.J_full.T, decoupled_wrench) + data.qfrc_bias[self.qvel_index]
        torques += nullspace_torques(c.mass_matrix, nullspace_matrix, c.initial_joint, c.joint_pos, c.joint_vel)
        c.torques = torques
        self._write_controls(action, np.clip(torques, self.torque_low, self.torque_high))

    def _control_compiled(self, action: np.ndarray) -> None:
        c, model, data = self.controller, self.model, self.data
        jac = self.jacobian
        mujoco.mj_jacSite(model, data, jac[:3], jac[3:], self.site)
        mujoco.mj_fullM(model, self.mass_matrix, data.qM)
        arm = self.arm_columns
        torques = _osc_torques(
            jac[:, arm],
            self.mass_matrix[arm, arm],
            data.qfrc_bias[arm],
            data.site_xpos[self.site],
            data.site_xmat[self.site].reshape(3, 3),
            data.qpos[self.arm_positions],
            data.qvel[arm],
            c.goal_pos,
            c.goal_ori,
            c.initial_joint,
            c.kp,
            c.kd,
            c.uncoupling,
            self.torque_low,
            self.torque_high,
        )
        self._write_controls(action, torques)

    def _write_controls(self, action: np.ndarray, torques: np.ndarray) -> None:
        """`SingleArm.control`'s end: the clipped arm torques and the gripper's controls (`grip_action`)."""
        self.controller.new_update = True  # the next `update()` recomputes, as after `run_controller`
        self.robot.torques = torques
        gripper_action = self.robot.gripper.format_action(action[self.arm_dims :])
        self.data.ctrl[self.gripper_actuators] = self.gripper_bias + self.gripper_weight * gripper_action
        self.data.ctrl[self.arm_actuators] = torques

    def _update_controller(self) -> None:
        """The controller's `update()` after its `sim.forward()`: end-effector pose and velocity, joint
        state, Jacobians and the arm's mass matrix, each computed once."""
        c, model, data = self.controller, self.model, self.data
        c.ee_pos = np.array(data.site_xpos[self.site])
        c.ee_ori_mat = np.array(data.site_xmat[self.site].reshape([3, 3]))
        jacp = np.zeros((3, model.nv))
        jacr = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, jacr, self.site)
        c.ee_pos_vel = np.array(np.dot(jacp, data.qvel))
        c.ee_ori_vel = np.array(np.dot(jacr, data.qvel))
        c.joint_pos = np.array(data.qpos[self.qpos_index])
        c.joint_vel = np.array(data.qvel[self.qvel_index])
        c.J_pos = np.array(jacp.reshape((3, -1))[:, self.qvel_index])
        c.J_ori = np.array(jacr.reshape((3, -1))[:, self.qvel_index])
        c.J_full = np.array(np.vstack([c.J_pos, c.J_ori]))
        mujoco.mj_fullM(model, self.mass_matrix, data.qM)
        c.mass_matrix = self.mass_matrix[self.qvel_index, :][:, self.qvel_index]


def _as_slice(indexes) -> slice | list[int]:
    """`indexes` as a slice when they are consecutive (a view instead of a copy), else as they are."""
    first = indexes[0]
    if list(indexes) == list(range(first, first + len(indexes))):
        return slice(first, first + len(indexes))
    return list(indexes)


@numba.njit(cache=True)
def _inverse(matrix):
    """`np.linalg.pinv` for the symmetric positive-definite operational-space matrices: their inverse
    (the same up to rounding), falling back to the pseudo-inverse when it is not finite (a singular arm)."""
    inverse = np.linalg.inv(matrix)
    if np.all(np.isfinite(inverse)):
        return inverse
    return np.linalg.pinv(matrix)


@numba.njit(cache=True)
def _osc_torques(
    jac,
    mass,
    bias,
    ee_pos,
    ee_ori,
    joint_pos,
    joint_vel,
    goal_pos,
    goal_ori,
    initial_joint,
    kp,
    kd,
    uncoupling,
    low,
    high,
):
    """robosuite's OSC torques (`OperationalSpaceController.run_controller`, `opspace_matrices`,
    `nullspace_torques`, then the torque limits) for the arm's Jacobian `jac` (6 x n) and mass matrix
    (views into the whole model's: copied contiguous here, where it costs least)."""
    jac = np.ascontiguousarray(jac)
    mass = np.ascontiguousarray(mass)
    velocity = jac @ joint_vel
    ori_error = 0.5 * (
        np.cross(ee_ori[:, 0], goal_ori[:, 0])
        + np.cross(ee_ori[:, 1], goal_ori[:, 1])
        + np.cross(ee_ori[:, 2], goal_ori[:, 2])
    )
    force = (goal_pos - ee_pos) * kp[0:3] - velocity[0:3] * kd[0:3]
    torque = ori_error * kp[3:6] - velocity[3:6] * kd[3:6]
    mass_inv = np.linalg.inv(mass)
    lambda_full = _inverse(jac @ mass_inv @ jac.T)
    if uncoupling:
        j_pos, j_ori = jac[0:3], jac[3:6]
        wrench = np.concatenate(
            (_inverse(j_pos @ mass_inv @ j_pos.T) @ force, _inverse(j_ori @ mass_inv @ j_ori.T) @ torque)
        )
    else:
        wrench = lambda_full @ np.concatenate((force, torque))
    torques = jac.T @ wrench + bias
    jbar = mass_inv @ jac.T @ lambda_full
    nullspace = np.eye(jac.shape[1]) - jbar @ jac
    joint_kp = 10.0
    pose_torques = mass @ (joint_kp * (initial_joint - joint_pos) - np.sqrt(joint_kp) * 2 * joint_vel)
    torques += nullspace.T @ pose_torques
    return np.minimum(np.maximum(torques, low), high)
