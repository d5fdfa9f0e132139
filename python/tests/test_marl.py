"""`coherent.marl`: the robots as the agents of a PettingZoo `ParallelEnv`, every step a
joint step. PettingZoo's own API test on the demo and on released tasks; the makespan
plan played through it; budget, shaping, masks and bad actions."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

import coherent
from coherent.marl import NOOP, CoherentParallelEnv
from conftest import DEMO, ENV_DIR


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def _released(scene: str, task_id: int) -> coherent.Task:
    # read_tasks: env3 holds a malformed task, which load_tasks would refuse the file for.
    tasks, _ = coherent.read_tasks(ENV_DIR / f"{scene}.json")
    return next(t for t in tasks if t.task_id == task_id)


def _index(env: CoherentParallelEnv, infos: dict, agent: str, action: str) -> int:
    """The index that names `action` for `agent` now."""
    return 1 + infos[agent]["actions"].index(action)


def test_the_demo_passes_pettingzoos_parallel_api_test(demo: coherent.Task) -> None:
    parallel_api_test(CoherentParallelEnv(demo), num_cycles=200)


@pytest.mark.parametrize(("scene", "task_id"), [("env0", 2), ("env1", 16), ("env2", 13), ("env3", 1)])
def test_released_tasks_pass_pettingzoos_parallel_api_test(env0_path: Path, scene: str, task_id: int) -> None:
    task = _released(scene, task_id)
    parallel_api_test(CoherentParallelEnv(task, shaping=True), num_cycles=100)


def test_the_makespan_plan_reaches_the_goal_in_its_makespan(demo: coherent.Task) -> None:
    planned = coherent.plan(demo, parallel=True)
    env = CoherentParallelEnv(demo)
    names = demo.robot_names
    assert env.possible_agents == [names[r] for r in demo.robots]
    assert env.max_steps == 2 * planned["makespan"]
    observations, infos = env.reset(seed=1)
    assert env.agents == env.possible_agents
    for i, step in enumerate(planned["parallel_plan"]):
        actions = {names[s["robot"]]: _index(env, infos, names[s["robot"]], s["action"]) for s in step}
        observations, rewards, terminations, truncations, infos = env.step(actions)
        last = i == len(planned["parallel_plan"]) - 1
        assert set(rewards) == set(env.possible_agents)
        assert rewards == dict.fromkeys(env.possible_agents, 1.0 if last else 0.0)
        assert terminations == dict.fromkeys(env.possible_agents, last)
        assert not any(truncations.values())
        for agent in env.possible_agents:
            assert infos[agent]["ok"] is (True if agent in actions else None), infos[agent]
            assert infos[agent]["steps"] == i + 1
    assert env.agents == [] and env.steps == planned["makespan"]
    with pytest.raises(coherent.ArgumentError, match="the episode is over: reset"):
        env.step({env.possible_agents[0]: NOOP})


def test_observations_are_each_robots_view_and_masks_mark_its_actions(demo: coherent.Task) -> None:
    env = CoherentParallelEnv(demo)
    observations, infos = env.reset()
    plain = coherent.Env(demo)
    for agent, robot in env.robot.items():
        assert env.observation_space(agent).contains(observations[agent])
        assert json.loads(observations[agent]) == plain.observe(robot)
        offered = plain.actions(robot)
        assert infos[agent]["actions"] == offered
        mask = infos[agent]["action_mask"]
        assert mask.dtype == np.int8 and len(mask) == env.action_space(agent).n == 1 + demo.most_actions(robot)
        assert mask.tolist() == [1] * (1 + len(offered)) + [0] * (len(mask) - 1 - len(offered))
        assert infos[agent]["ok"] is None and infos[agent]["reason"] is None
    assert json.loads(env.state()) == plain.graph()


def test_doing_nothing_is_truncated_at_twice_the_makespan(demo: coherent.Task) -> None:
    env = CoherentParallelEnv(demo)
    env.reset()
    for _ in range(env.max_steps):
        assert env.agents
        _, rewards, terminations, truncations, _ = env.step(dict.fromkeys(env.agents, NOOP))
        assert set(rewards.values()) == {0.0} and not any(terminations.values())
    assert all(truncations.values()) and env.agents == []
    short = CoherentParallelEnv(demo, max_steps=1)
    short.reset()
    assert all(short.step({})[3].values())


def test_shaping_pays_the_progress_toward_the_goal(demo: coherent.Task) -> None:
    planned = coherent.plan(demo, parallel=True)["parallel_plan"]
    names = demo.robot_names
    totals = {}
    for shaping in (False, True):
        env = CoherentParallelEnv(demo, shaping=shaping)
        _, infos = env.reset()
        start = sum(env.env.goal_holds()) / len(demo.goal)
        total = 0.0
        for step in planned:
            actions = {names[s["robot"]]: _index(env, infos, names[s["robot"]], s["action"]) for s in step}
            _, rewards, _, _, infos = env.step(actions)
            total += rewards[env.possible_agents[0]]
        totals[shaping] = (total, start)
    assert totals[False][0] == 1.0
    total, start = totals[True]
    # The potential goes from the fraction of goal predicates at the start to 1.
    assert total == pytest.approx(1.0 + (1.0 - start))


def test_an_index_beyond_the_list_does_nothing_and_says_so(demo: coherent.Task) -> None:
    env = CoherentParallelEnv(demo)
    _, infos = env.reset()
    arm = demo.robot_names[6]
    beyond = len(infos[arm]["actions"]) + 1
    observations, _, _, _, infos = env.step({arm: beyond})
    assert infos[arm]["ok"] is False
    assert infos[arm]["reason"] == f"action {beyond} is none of the {beyond - 1} actions offered; nothing done"
    assert json.loads(env.state()) == coherent.Env(demo).graph()


def test_unknown_agents_and_bad_arguments_raise(demo: coherent.Task) -> None:
    env = CoherentParallelEnv(demo)
    env.reset()
    with pytest.raises(coherent.ArgumentError, match=r"agents \['drone_1'\] are not acting now"):
        env.step({"drone_1": NOOP})
    for bad in (-1, True):
        with pytest.raises(coherent.ArgumentError, match="expected an int from 0"):
            CoherentParallelEnv(demo, max_steps=bad)
        with pytest.raises(coherent.ArgumentError, match="expected an int from 0"):
            env.reset(seed=bad)
    with pytest.raises(TypeError):
        env.step({env.agents[0]: 1.5})
