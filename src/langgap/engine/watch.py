"""The scene goals watched over one episode: which became true and when, and whether an ordered goal's
parts came in the wrong order. One implementation for every way an episode is driven (the harness's
`run_episode`, the Gymnasium env)."""

from __future__ import annotations

from collections.abc import Mapping

from langgap.goals import Goal, GoalProgress, is_ordered, unordered
from langgap.sim.env import TaskEnv


class SceneWatch:
    """Watches `goals` (name -> goal) on `env` from the state the policy first sees (after settling).

    A goal already true at the start is listed in `at_start`, never as reached; every other goal keeps
    its own history from step 0 (ordered goals), and `reached` maps it to the first step it held.
    Call `observe()` after every `env.step`. `wrong_order` judges the env's task goal (`OrderWatch`).
    """

    def __init__(self, env: TaskEnv, goals: Mapping[str, Goal]):
        self._env = env
        self.goals = dict(goals)
        self.at_start = self.holding()
        # Names of one goal share its progress, so each distinct goal is evaluated once a step: LIBERO-goal's ten
        # scenes share one layout, and a `full` goal scene watches each of its goals under ten names.
        names: dict[Goal, list[str]] = {}
        for name, goal in self.goals.items():
            if name not in self.at_start:
                names.setdefault(goal, []).append(name)
        self._pending = [(GoalProgress(goal), shared) for goal, shared in names.items()]
        self._order = OrderWatch(env, env.task.goal)
        self.reached: dict[str, int] = {}
        for progress, _ in self._pending:
            progress.observe(0, env.predicate_holds)

    def observe(self) -> None:
        """Record the state after the env's latest step."""
        step, truth = self._env.steps, self._env.predicate_holds
        for progress, shared in self._pending:
            if progress.observe(step, truth):
                for name in shared:
                    self.reached.setdefault(name, step)
        self._order.observe()

    def holding(self) -> list[str]:
        """The watched goals that hold in the current state, order ignored."""
        return [name for name, goal in self.goals.items() if self._env.goal_holds(goal)]

    def wrong_order(self, success: bool) -> bool:
        """Whether an ordered task goal's parts all held at some step without the goal being met."""
        return self._order.wrong(success)


class OrderWatch:
    """Whether an ordered `goal`'s parts all held at some step on `env`, order ignored (from step 0; call
    `observe()` after every `env.step`): a goal not met although they did came in the wrong order."""

    def __init__(self, env: TaskEnv, goal: Goal):
        self._env = env
        self._unordered = GoalProgress(unordered(goal)) if is_ordered(goal) else None
        self.observe()

    def observe(self) -> None:
        if self._unordered is not None:
            self._unordered.observe(self._env.steps, self._env.predicate_holds)

    def wrong(self, success: bool) -> bool:
        """Whether the goal was not met although all its parts held at some step."""
        return not success and self._unordered is not None and self._unordered.first_held is not None
