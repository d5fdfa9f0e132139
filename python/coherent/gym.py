"""A Gymnasium environment over :class:`coherent.Env`, for planners that plug into RL
tooling (``pip install '.[gym]'``)::

    from coherent.gym import CoherentEnv

    env = CoherentEnv(task)
    obs, info = env.reset(seed=0)
    robot = env.robots[0]
    obs, reward, terminated, truncated, info = env.step((robot, info["actions"][robot][0]))

An action is ``(robot id, action text)``; the actions a robot may use now are in
``info["actions"]``. The observation is the whole scene graph as JSON text (``nodes`` and
``edges`` with the original format's field names). The reward is 1 on the step that
reaches the goal and 0 otherwise; an infeasible or unparsable action changes nothing
and ``info["reason"]`` says why. The episode is truncated after ``max_steps`` steps
(by default the budget every episode gets, ``coherent.budget``: twice the task's ground
truth, the paper's, or twice the optimum when the task has none).
"""

from __future__ import annotations

import json
import operator
import string
from typing import Any

from ._coherent import ArgumentError, Env, Task, budget
from ._extras import needs

with needs("coherent.gym", "gym"):
    import gymnasium
    import numpy as np
    from gymnasium import spaces

#: Characters of the observation and of action texts (JSON is written ASCII-only).
CHARSET = string.printable
#: Longest observation text the observation space admits.
MAX_OBSERVATION = 1 << 22
#: Longest action text the action space admits.
MAX_ACTION = 256


class RobotSpace(spaces.Space[int]):
    """The robots of a task, by node id."""

    def __init__(self, robots: list[int], seed: int | np.random.Generator | None = None) -> None:
        self.robots = tuple(robots)
        super().__init__(shape=(), dtype=np.int64, seed=seed)

    def sample(self, mask: Any = None, probability: Any = None) -> int:
        return int(self.np_random.choice(self.robots))

    def contains(self, x: Any) -> bool:
        return isinstance(x, (int, np.integer)) and int(x) in self.robots

    def __repr__(self) -> str:
        return f"RobotSpace({list(self.robots)})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, RobotSpace) and other.robots == self.robots

    def __hash__(self) -> int:
        return hash(self.robots)


class CoherentEnv(gymnasium.Env[str, tuple[int, str]]):
    """A task's world as a Gymnasium environment; see the module's documentation."""

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(self, task: Task, *, physics: bool = False, max_steps: int | None = None) -> None:
        self.env = Env(task, physics=physics)
        self.robots = self.env.robots
        self.max_steps = budget(task, max_steps=max_steps)
        self.observation_space = spaces.Text(max_length=MAX_OBSERVATION, min_length=0, charset=CHARSET)
        self.action_space = spaces.Tuple(
            (RobotSpace(self.robots), spaces.Text(max_length=MAX_ACTION, min_length=0, charset=CHARSET))
        )
        self.steps = 0

    def _observation(self) -> str:
        return json.dumps(self.env.graph(), separators=(",", ":"))

    def _info(self, ok: bool | None = None, reason: str | None = None) -> dict[str, Any]:
        return {
            "ok": ok,
            "reason": reason,
            "steps": self.steps,
            "actions": {robot: self.env.actions(robot) for robot in self.robots},
        }

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[str, dict[str, Any]]:
        """Back to the task's initial state; the world is deterministic, ``seed`` only
        seeds the spaces' sampling."""
        if seed is not None and operator.index(seed) < 0:
            raise ArgumentError(f"seed={seed!r}: expected an int from 0")
        super().reset(seed=seed)
        if seed is not None:
            self.action_space.seed(seed)
        self.env.reset()
        self.steps = 0
        return self._observation(), self._info()

    def step(self, action: tuple[int, str]) -> tuple[str, float, bool, bool, dict[str, Any]]:
        """Tries ``(robot, action text)``; raises :class:`coherent.UnknownRobotError` for
        a robot that is not one of the task's."""
        robot, text = action
        # An int or a numpy integer; a float is refused (TypeError), not rounded.
        ok, reason, done = self.env.step(operator.index(robot), text)
        self.steps += 1
        truncated = not done and self.steps >= self.max_steps
        return self._observation(), float(done and ok), done, truncated, self._info(ok, reason)
