"""A PettingZoo parallel environment over :class:`coherent.Env`, for multi-agent
reinforcement learning (``pip install ".[marl]"`` from a checkout)::

    from coherent.marl import CoherentParallelEnv

    env = CoherentParallelEnv(task)
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: env.action_space(a).sample(infos[a]["action_mask"]) for a in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

The agents are the task's robots, by name (``Task.robot_names``: ``"robot_dog_13"``).
Every step is a joint step: each agent acts at most once, all at the same time, by the
rules of docs/semantics.md ("Parallel steps"). An agent's action is an index: 0 does
nothing, ``i`` does the ``i``-th action of the list its info gave with the last
observation (``infos[agent]["actions"][i - 1]``); ``infos[agent]["action_mask"]`` marks
the indices that mean an action now. An index beyond the list does nothing either, and
the agent's ``reason`` says so. A joint step the rules refuse (two actions that
interfere) carries out nothing, and each agent's ``reason`` says why.

An agent observes what its robot sees (:meth:`coherent.Env.observe`) as JSON text;
:meth:`CoherentParallelEnv.state` is the whole scene graph, for a centralised critic.
The reward is the team's, the same for every agent: 1 on the step that reaches the goal,
0 otherwise. With ``shaping=True`` each step also gets the change in the fraction of goal
predicates that hold, a potential-based shaping (Ng, Harada and Russell, ICML 1999),
which leaves the optimal policies as they are. Every agent terminates when the goal is
reached, and is truncated after ``max_steps`` joint steps, by default twice the task's
makespan (the fewest joint steps), the budget of every parallel episode
(``coherent.budget(task, execution="parallel")``).

The task's events (or those of ``events=``, docs/dynamic.md) happen as in a parallel
episode: each call of :meth:`CoherentParallelEnv.step` is a joint step, and after it the
events due before the next are carried out; each agent's info has what the team was told
of them (``infos[agent]["news"]``). An agent whose robot goes down terminates: its
``terminations`` entry is True on the step after which it went down, and it leaves
``env.agents``. A robot that joins later is one of ``possible_agents`` from the start,
and enters ``env.agents`` (and the dicts that step returns) on the step after which it
joined, as PettingZoo's parallel API allows. A failing-actions event makes an agent's
action fail (its ``ok`` False, ``reason`` says so), the draws seeded by the ``seed`` of
:meth:`CoherentParallelEnv.reset` (0 until one is given).
"""

from __future__ import annotations

import json
import operator
from typing import Any

from ._coherent import ArgumentError, Env, Task, budget
from ._extras import needs

with needs("coherent.marl", "marl"):
    import numpy as np
    from gymnasium import spaces
    from pettingzoo import ParallelEnv

# The observations' characters and length, as the Gymnasium environment's.
from .gym import CHARSET, MAX_OBSERVATION, draws_seed

#: The action index that does nothing.
NOOP = 0


class CoherentParallelEnv(ParallelEnv[str, str, int]):
    """A task's world as a PettingZoo ``ParallelEnv``; see the module's documentation."""

    metadata: dict[str, Any] = {"name": "coherent_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(
        self,
        task: Task,
        *,
        physics: bool = False,
        max_steps: int | None = None,
        shaping: bool = False,
        events: Any = None,
    ) -> None:
        self.env = Env(task, physics=physics, events=events)
        self.shaping = bool(shaping)
        steps = None if max_steps is None else _count("max_steps", max_steps)
        self.max_steps = budget(task, execution="parallel", max_steps=steps)
        names = task.robot_names
        self.possible_agents: list[str] = [names[robot] for robot in task.robots]
        self.agents: list[str] = []
        self.robot: dict[str, int] = {names[robot]: robot for robot in task.robots}
        self._action_spaces = {
            agent: spaces.Discrete(1 + task.most_actions(robot)) for agent, robot in self.robot.items()
        }
        text = spaces.Text(max_length=MAX_OBSERVATION, min_length=0, charset=CHARSET)
        self._observation_spaces = {agent: text for agent in self.possible_agents}
        self.steps = 0
        # What each agent's indices mean: its actions as of the last observation.
        self._offered: dict[str, list[str]] = {}
        # Each agent's last observation: what an agent whose robot went down is left with.
        self._seen: dict[str, str] = {}

    def observation_space(self, agent: str) -> spaces.Space[str]:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space[int]:
        return self._action_spaces[agent]

    def state(self) -> str:
        """The whole scene graph now, as JSON text."""
        return json.dumps(self.env.graph(), separators=(",", ":"))

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, str], dict[str, dict[str, Any]]]:
        """Back to the task's initial state, its events from the start. The world is
        deterministic but for a failing-actions event's draws: ``seed`` seeds those (as
        ``coherent.Env.reset`` does, for this episode and the next ones) and the action
        spaces' sampling; ``options`` is accepted and unused."""
        if seed is not None:
            seed = _count("seed", seed)
            for i, agent in enumerate(self.possible_agents):
                self._action_spaces[agent].seed(seed + i)
        self.env.reset(seed=None if seed is None else draws_seed(seed))
        self.steps = 0
        self._seen = {}
        self.agents = self._team()
        observations = self._observe()
        return observations, {agent: self._info(agent) for agent in self.agents}

    def step(
        self, actions: dict[str, int]
    ) -> tuple[
        dict[str, str], dict[str, float], dict[str, bool], dict[str, bool], dict[str, dict[str, Any]]
    ]:
        """One joint step: each agent of ``actions`` does the action its index names (an
        agent left out does nothing). Raises :class:`coherent.ArgumentError` for an agent
        that is not acting now (none is after the episode's end: call ``reset``)."""
        unknown = [agent for agent in actions if agent not in self.agents]
        if unknown:
            raise ArgumentError(
                f"agents {unknown!r} are not acting now; the agents: {self.agents!r}"
                + ("" if self.agents else " (the episode is over: reset)")
            )
        before = self._progress() if self.shaping else 0.0
        chosen: list[tuple[str, str]] = []
        said: dict[str, tuple[bool | None, str | None]] = dict.fromkeys(self.agents, (None, None))
        for agent, index in actions.items():
            index = operator.index(index)
            offered = self._offered[agent]
            if index == NOOP:
                continue
            if not 0 < index <= len(offered):
                said[agent] = (False, f"action {index} is none of the {len(offered)} actions offered; nothing done")
                continue
            chosen.append((agent, offered[index - 1]))
        # Every call is a joint step of the episode, one in which nobody acts included.
        oks, reasons, done = self.env.step([(self.robot[agent], text) for agent, text in chosen])
        for (agent, _), ok, reason in zip(chosen, oks, reasons, strict=True):
            said[agent] = (ok, reason)
        self.steps += 1
        reward = float(done)
        if self.shaping:
            reward += self._progress() - before
        truncated = not done and self.steps >= self.max_steps
        # The agents that acted, and those whose robots joined the team after the step.
        team = self._team()
        acting = [agent for agent in self.possible_agents if agent in self.agents or agent in team]
        self.agents = acting
        observations = self._observe()
        rewards = dict.fromkeys(acting, reward)
        terminations = {agent: done or agent not in team for agent in acting}
        truncations = dict.fromkeys(acting, truncated)
        infos = {agent: self._info(agent, *said.get(agent, (None, None))) for agent in acting}
        self.agents = [] if done or truncated else [agent for agent in acting if agent in team]
        return observations, rewards, terminations, truncations, infos

    def _team(self) -> list[str]:
        """The agents whose robots are in the team now, in the order of ``possible_agents``."""
        team = set(self.env.robots)
        return [agent for agent in self.possible_agents if self.robot[agent] in team]

    def _observe(self) -> dict[str, str]:
        """Each acting agent's view as JSON text; remembers the actions offered now. An
        agent whose robot went down is offered none, and keeps its last view."""
        observations = {}
        team = set(self.env.robots)
        for agent in self.agents:
            robot = self.robot[agent]
            if robot in team:
                self._offered[agent] = self.env.actions(robot)
                self._seen[agent] = json.dumps(self.env.observe(robot), separators=(",", ":"))
            else:
                self._offered[agent] = []
            observations[agent] = self._seen.get(agent, "{}")
        return observations

    def _info(self, agent: str, ok: bool | None = None, reason: str | None = None) -> dict[str, Any]:
        """What an agent is told besides its observation: its last action's outcome
        (``ok`` None when it did nothing), the actions its indices name now, their mask."""
        offered = self._offered[agent]
        mask = np.zeros(self._action_spaces[agent].n, dtype=np.int8)
        mask[: 1 + len(offered)] = 1
        return {
            "ok": ok,
            "reason": reason,
            "steps": self.steps,
            "actions": offered,
            "action_mask": mask,
            "news": self.env.news,
        }

    def _progress(self) -> float:
        """The fraction of goal predicates that hold: the shaping's potential."""
        holds = self.env.goal_holds()
        return sum(holds) / len(holds) if holds else 1.0


def _count(name: str, value: Any) -> int:
    """An int argument from 0 (a bool is not one)."""
    if isinstance(value, bool) or operator.index(value) < 0:
        raise ArgumentError(f"{name}={value!r}: expected an int from 0")
    return operator.index(value)
