"""LangGap as Gymnasium environments (see docs/gymnasium.md).

Importing this package registers `LangGap/Task-v0` (one task, `LangGapTaskEnv`) and
`LangGap/SameScene-v0` (a scene's sibling tasks as one vector env, `SameSceneVectorEnv`, through
`gym.make_vec`). Without importing it first, name the module in the id:
`gym.make("langgap.gym:LangGap/Task-v0", task=...)` (Gymnasium 1.x imports it; it has no plugin entry points).
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from langgap.gym.task_env import LangGapTaskEnv, policy_observation

TASK_ENV_ID = "LangGap/Task-v0"
SAME_SCENE_ENV_ID = "LangGap/SameScene-v0"


def register_envs() -> None:
    """Register LangGap's environment ids with Gymnasium (idempotent; done on import)."""
    if TASK_ENV_ID not in registry:
        register(id=TASK_ENV_ID, entry_point="langgap.gym.task_env:LangGapTaskEnv")
    if SAME_SCENE_ENV_ID not in registry:
        register(id=SAME_SCENE_ENV_ID, vector_entry_point="langgap.gym.same_scene:SameSceneVectorEnv")


register_envs()

__all__ = ["SAME_SCENE_ENV_ID", "TASK_ENV_ID", "LangGapTaskEnv", "policy_observation", "register_envs"]
