"""The scripted oracle: a generic planner that solves LangGap tasks from their goal and privileged state."""

from langgap.policies.oracle.planner import OracleError
from langgap.policies.oracle.policy import BlindPolicy, OraclePolicy

__all__ = ["BlindPolicy", "OracleError", "OraclePolicy"]
