"""LeRobot plugin: importing it registers `--env.type=langgap` (see `langgap.lerobot_env`)."""

from langgap.lerobot_env import LangGapEnv

__all__ = ["LangGapEnv"]
