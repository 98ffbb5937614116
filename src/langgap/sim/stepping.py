"""Faster physics stepping for one robosuite environment instance: bit-identical (`exact`) or `fast`.

For every physics substep of a control step, robosuite computes MuJoCo's full forward dynamics three
times on the same state: `sim.forward()` in its step loop, again in the controller's `update()`, and
once more inside `mj_step`. Only the first needs the position and velocity stages (kinematics,
collision detection, mass matrix), the most expensive part; the state they depend on (qpos, qvel,
act, mocap, time) does not change until the integrator runs. The `exact` stepping therefore runs the
later two from the acceleration stage on (`mj_forwardSkip`), and integrates with the model's own
integrator after the same checks `mj_step` performs. The acceleration stage and its constraint
solver still run as often as before: each leaves its solution as the next one's warm start, so none
can be dropped without changing the last bits. The trajectory is the same to the last bit (a test
compares full simulator states over real rollouts). The substeps between two actions run the arm's
controller through `OscSubsteps` (sim/osc.py), robosuite's computation without its overhead.

The `fast` stepping computes each substep's dynamics once, as `mj_step` alone would: the position
and velocity stages before the controller, the acceleration stage (with the new controls) before
the integration; its controller is compiled. Only the constraint solver's warm start and the
controller's rounding differ from robosuite's, so states agree to the last bits at first and then
drift apart the way two runs on different CPUs do; `bench/bench_stepping_drift.py` measures the
drift and checks that the oracle's verdicts do not change.

Whenever the state is not the one the position stage last saw, the full computation runs, so a
caller that edits the state in between is safe.
"""

from __future__ import annotations

import mujoco

from langgap.sim.osc import OscSubsteps

_INTEGRATE = {
    mujoco.mjtIntegrator.mjINT_EULER: mujoco.mj_Euler,
    mujoco.mjtIntegrator.mjINT_IMPLICIT: mujoco.mj_implicit,
    mujoco.mjtIntegrator.mjINT_IMPLICITFAST: mujoco.mj_implicit,
}


def _positions_and_velocities(model, data) -> None:
    """`mj_forward` without its acceleration stage: everything the controller reads."""
    energy = model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_ENERGY
    mujoco.mj_fwdPosition(model, data)
    mujoco.mj_sensorPos(model, data)
    if energy:
        mujoco.mj_energyPos(model, data)
    mujoco.mj_fwdVelocity(model, data)
    mujoco.mj_sensorVel(model, data)
    if energy:
        mujoco.mj_energyVel(model, data)


def _state_key(data) -> tuple:
    return (
        data.time,
        data.qpos.tobytes(),
        data.qvel.tobytes(),
        data.act.tobytes(),
        data.mocap_pos.tobytes(),
        data.mocap_quat.tobytes(),
    )


class FastStepping:
    """Wraps `env.step` so that the physics substeps it runs skip recomputing what they may skip."""

    def __init__(self, env, fast: bool = False):
        self.env = env
        self.fast = fast
        self._robosuite_step = env.step
        self._positions_of: tuple | None = None  # state key for which the position stage is current
        self._osc: OscSubsteps | None = None

    @classmethod
    def install(cls, env, fast: bool = False) -> None:
        """Make `env.step` (a robosuite `MujocoEnv`) step through a new `FastStepping`."""
        env.step = cls(env, fast)

    def __call__(self, action):
        sim = self.env.sim  # looked up per step: a hard reset builds a new simulator
        model, data = sim.model._model, sim.data._data
        integrate = _INTEGRATE.get(model.opt.integrator)
        if integrate is None or model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_FWDINV:
            # RK4 evaluates dynamics at intermediate states, and the forward/inverse comparison runs
            # inside mj_step: nothing to reuse
            return self._robosuite_step(action)
        substeps = int(round(self.env.control_timestep / self.env.model_timestep))
        integrated = 0  # substeps integrated so far in this control step
        self._positions_of = None

        def forward() -> None:
            key = _state_key(data)
            if key != self._positions_of:
                if self.fast and 0 < integrated < substeps:
                    # between two integrations of one control step only the controller reads the state
                    _positions_and_velocities(model, data)
                else:
                    mujoco.mj_forward(model, data)
                self._positions_of = key
            elif not self.fast:
                mujoco.mj_forwardSkip(model, data, mujoco.mjtStage.mjSTAGE_VEL, 0)

        def step(with_udd: bool = True) -> None:
            nonlocal integrated
            # mj_step's sequence; the checks may reset a diverged state, which then gets a full pass
            mujoco.mj_checkPos(model, data)
            mujoco.mj_checkVel(model, data)
            if _state_key(data) == self._positions_of:
                mujoco.mj_forwardSkip(model, data, mujoco.mjtStage.mjSTAGE_VEL, 0)
            else:
                mujoco.mj_forward(model, data)
            mujoco.mj_checkAcc(model, data)
            integrate(model, data)
            self._positions_of = None
            integrated += 1

        sim.forward, sim.step = forward, step
        osc = self._substep_control()
        if osc is not None:
            robosuite_pre_action = self.env._pre_action

            def pre_action(action, policy_step=False) -> None:
                if policy_step:  # a new goal and robosuite's bookkeeping: robosuite's own code
                    return robosuite_pre_action(action, policy_step)
                forward()  # the controller's update() begins with sim.forward()
                osc.control(action)

            self.env._pre_action = pre_action
        try:
            return self._robosuite_step(action)
        finally:
            del sim.forward, sim.step  # back to the class methods for everything outside a step
            if osc is not None:
                del self.env._pre_action
            self._positions_of = None

    def _substep_control(self) -> OscSubsteps | None:
        """The fast substep controller for the env's current simulator, robot and controller (every
        reset builds a new controller, a hard reset a new simulator and robot), or None when the env's
        control configuration is not the one it reproduces."""
        env = self.env
        if self._osc is None or not self._osc.controls(env):
            self._osc = OscSubsteps(env, compiled=self.fast) if OscSubsteps.supports(env) else None
        return self._osc
