"""`lerobot`: a LeRobot policy checkpoint run in process (π0, π0.5, π0-FAST, SmolVLA, ACT, Diffusion, ...).

`--policy-arg path=DIR` names a checkpoint's `pretrained_model/` directory (or the checkpoint directory
holding one): `config.json`, `model.safetensors` and LeRobot's saved pre/post processors. The policy is
loaded the way `lerobot-eval` loads it (`make_policy` with LeRobot's LIBERO env features, so a
checkpoint saved with `use_peft=True` loads its base policy and adapter), and `adapter=DIR` applies a
PEFT/LoRA adapter directory on top of `path`. Each step the policy gets what LeRobot's LIBERO
pipeline gives it: upright images under `observation.images.image` / `image2`, the 8-D
`observation.state` and the instruction as `task`, through the checkpoint's own preprocessor; its
`select_action` keeps the checkpoint's action chunking (`n_action_steps`). Images are rendered at the
checkpoint's input size (the training data's) unless `image_size` says otherwise; `threads` caps
torch's CPU threads (0: torch's default). Each episode
reseeds torch and NumPy from the context's seed and init index, so sampling policies are reproducible.

Needs the LeRobot environment `.venv-lerobot` (`./setup.sh` makes it unless given `--core`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from langgap.lerobot_libero import ACTION_KEY, CAMERA_KEYS, IMAGE_PREFIX, STATE_KEY, image_tensor
from langgap.policies.base import PolicySpec, TaskContext, current_instruction
from langgap.policies.lerobot_checkpoint import CheckpointError, check_arguments, pretrained_dir
from langgap.sim.env import ACTION_DIM, Observation


def episode_seed(context: TaskContext) -> int:
    """One 32-bit seed per (seed, init index), as `random` derives its stream."""
    return int(np.random.SeedSequence([context.seed, context.init_index]).generate_state(1)[0])


class LeRobotPolicy:
    """A LeRobot `PreTrainedPolicy` behind LangGap's policy protocol (see the module docstring)."""

    check_arguments = staticmethod(check_arguments)  # before a run starts (`policy_kwargs`)

    def __init__(self, path: str, device: str = "cpu", adapter: str = "", image_size: int = 0, threads: int = 0):
        import torch
        from lerobot.configs.policies import PreTrainedConfig
        from lerobot.envs.configs import LiberoEnv
        from lerobot.policies.factory import make_policy, make_pre_post_processors

        if threads > 0:
            # Several workers on few cores: torch's default (all cores each) makes its threads spin against
            # each other; measured on 2 busy cores, one Diffusion chunk took 2.4-3.3 s with 2 threads, 37 ms with 1.
            torch.set_num_threads(threads)
        self.path = pretrained_dir(path)
        self.device = device
        self.adapter = adapter
        try:
            config = PreTrainedConfig.from_pretrained(self.path)
        except Exception as exc:  # draccus and json raise many kinds of errors for a bad config.json
            raise CheckpointError(f"cannot read {self.path / 'config.json'}: {exc}") from None
        config.pretrained_path = self.path
        config.device = device
        self.lerobot_config = config
        self.cameras = self._cameras(config)
        size = image_size or self._checkpoint_image_size(config)
        self._check_state_and_action(config)
        # LeRobot's LIBERO features (`--env.type=langgap` declares the same): keys, shapes, image size.
        env_features = LiberoEnv(observation_height=size, observation_width=size)
        try:
            model = make_policy(config, env_cfg=env_features)
            if adapter:
                from peft import PeftModel

                model = PeftModel.from_pretrained(model, str(Path(adapter).expanduser()))
        except (OSError, ValueError, KeyError) as exc:
            raise CheckpointError(f"cannot load LeRobot policy from {self.path}: {exc}") from None
        model.eval()
        self.model = model
        overrides = {"device_processor": {"device": device}, "rename_observations_processor": {"rename_map": {}}}
        self.preprocessor, self.postprocessor = make_pre_post_processors(
            policy_cfg=config, pretrained_path=str(self.path), preprocessor_overrides=overrides
        )
        self._torch = torch
        self._instruction = ""
        self._context: TaskContext | None = None
        self.spec = PolicySpec(cameras=self.cameras, image_size=size, chunk=1, replan=1)

    @staticmethod
    def _cameras(config) -> tuple[str, ...]:
        wanted = set(config.image_features)
        known = {IMAGE_PREFIX + key: camera for camera, key in CAMERA_KEYS.items()}
        unknown = sorted(wanted - set(known))
        if unknown:
            raise CheckpointError(f"checkpoint wants camera(s) {unknown}; LIBERO provides {', '.join(sorted(known))}")
        return tuple(camera for key, camera in known.items() if key in wanted)

    @staticmethod
    def _checkpoint_image_size(config) -> int:
        shapes = {tuple(feature.shape[-2:]) for feature in config.image_features.values()}
        square = [h for h, w in shapes if h == w]
        # Non-square or mixed inputs: LIBERO's training resolution; the policy's processor resizes.
        return square[0] if len(shapes) == 1 and square else 256

    @staticmethod
    def _check_state_and_action(config) -> None:
        state = config.input_features.get(STATE_KEY)
        if state is not None and tuple(state.shape) != (8,):
            raise CheckpointError(f"checkpoint wants a {tuple(state.shape)} state; LIBERO's is 8-D")
        action = config.output_features.get(ACTION_KEY)
        if action is None or tuple(action.shape) != (ACTION_DIM,):
            shape = None if action is None else tuple(action.shape)
            raise CheckpointError(f"checkpoint outputs action shape {shape}; LIBERO needs ({ACTION_DIM},)")

    def config(self) -> dict:
        """What is recorded with results: the checkpoint, its policy type and chunking, device and adapter."""
        return {
            "path": str(self.path),
            "type": self.lerobot_config.type,
            "device": self.device,
            "adapter": self.adapter or None,
            "n_action_steps": getattr(self.lerobot_config, "n_action_steps", None),
        }

    def reset(self, context: TaskContext) -> None:
        """Clear the policy's queues and reseed torch and NumPy for this episode."""
        from lerobot.utils.random_utils import set_seed

        set_seed(episode_seed(context))
        self.model.reset()
        self.preprocessor.reset()
        self.postprocessor.reset()
        self._context = context
        self._instruction = context.instruction

    def model_inputs(self, observation: Observation) -> dict:
        """The batch LeRobot's LIBERO pipeline hands the policy's preprocessor (after `LiberoProcessorStep`)."""
        batch = {IMAGE_PREFIX + CAMERA_KEYS[c]: image_tensor(observation.images[c]) for c in self.cameras}
        batch[STATE_KEY] = self._torch.from_numpy(np.asarray(observation.state, dtype=np.float32)).unsqueeze(0)
        batch["task"] = [self._instruction]
        return batch

    def act(self, observation: Observation) -> np.ndarray:
        """One action from the policy's `select_action` (which plays out its chunk before replanning; when
        the instruction changes, the chunk planned under the old one is dropped, as the rollout drops its own)."""
        instruction = current_instruction(observation, self._context)
        if instruction != self._instruction:
            self.model.reset()
            self._instruction = instruction
        batch = self.preprocessor(self.model_inputs(observation))
        with self._torch.inference_mode():
            action = self.model.select_action(batch)
        action = self.postprocessor(action)
        return action.to("cpu").numpy().reshape(-1, ACTION_DIM)[0].astype(np.float64)
