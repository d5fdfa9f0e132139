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

The task's events (or those of ``events=``, docs/dynamic.md) happen as in an episode:
each step is a step of the episode, and after it the events due before the next are
carried out. ``info["news"]`` says what the team was told of them before the coming
step, ``info["robots"]`` is the team now: a robot that went down, or has not joined yet,
is offered no action (``info["actions"][robot]`` is empty), and an action given to it
does nothing (``ok`` False, ``reason`` says why) but still takes the step. A
failing-actions event makes an action fail (``ok`` False), its draws seeded by the
``seed`` of :meth:`CoherentEnv.reset` (0 until one is given).
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


def draws_seed(seed: int) -> int:
    """The seed of :class:`coherent.Env`'s failure draws for a Gymnasium or PettingZoo
    ``seed`` from 0: the same below 2**64, taken modulo 2**64 above (Gymnasium takes any
    int; the draws are seeded by 64 bits)."""
    return operator.index(seed) % 2**64


class CoherentEnv(gymnasium.Env[str, tuple[int, str]]):
    """A task's world as a Gymnasium environment; see the module's documentation."""

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(
        self, task: Task, *, physics: bool = False, max_steps: int | None = None, events: Any = None
    ) -> None:
        self.env = Env(task, physics=physics, events=events)
        # Every robot of the task, those that join later too: the team now is in the info.
        self.robots = self.env.task.robots
        self.max_steps = budget(task, max_steps=max_steps)
        self.observation_space = spaces.Text(max_length=MAX_OBSERVATION, min_length=0, charset=CHARSET)
        self.action_space = spaces.Tuple(
            (RobotSpace(self.robots), spaces.Text(max_length=MAX_ACTION, min_length=0, charset=CHARSET))
        )
        self.steps = 0

    def _observation(self) -> str:
        return json.dumps(self.env.graph(), separators=(",", ":"))

    def _info(self, ok: bool | None = None, reason: str | None = None) -> dict[str, Any]:
        team = self.env.robots
        return {
            "ok": ok,
            "reason": reason,
            "steps": self.steps,
            "actions": {robot: self.env.actions(robot) if robot in team else [] for robot in self.robots},
            "robots": team,
            "news": self.env.news,
        }

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[str, dict[str, Any]]:
        """Back to the task's initial state, its events from the start. The world is
        deterministic but for a failing-actions event's draws: ``seed`` seeds those (as
        ``coherent.Env.reset`` does, for this episode and the next ones) and the spaces'
        sampling."""
        if seed is not None and operator.index(seed) < 0:
            raise ArgumentError(f"seed={seed!r}: expected an int from 0")
        super().reset(seed=seed)
        if seed is not None:
            self.action_space.seed(seed)
        self.env.reset(seed=None if seed is None else draws_seed(seed))
        self.steps = 0
        return self._observation(), self._info()

    def step(self, action: tuple[int, str]) -> tuple[str, float, bool, bool, dict[str, Any]]:
        """Tries ``(robot, action text)``; raises :class:`coherent.UnknownRobotError` for
        a robot that is not one of the task's. A robot of the task out of the team now
        does nothing, and the step is taken."""
        robot, text = action
        # An int or a numpy integer; a float is refused (TypeError), not rounded.
        robot = operator.index(robot)
        if robot in self.robots and robot not in self.env.robots:
            _, _, done = self.env.step([])
            ok, reason = False, f"robot {robot} is not in the team now (it went down, or has not joined yet); nothing done"
        else:
            ok, reason, done = self.env.step(robot, text)
        self.steps += 1
        truncated = not done and self.steps >= self.max_steps
        return self._observation(), float(done and ok), done, truncated, self._info(ok, reason)
