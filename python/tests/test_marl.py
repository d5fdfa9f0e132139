"""`coherent.marl`: the robots as the agents of a PettingZoo `ParallelEnv`, every step a
joint step. PettingZoo's own API test on the demo and on released tasks, and on the demo
with events; the makespan plan played through it; budget, shaping, masks and bad
actions; an agent that goes down terminated, one that joins entering, the news in the
infos."""

from __future__ import annotations

import json
import warnings
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


#: The quadrotor down before step 3, the dog joining before step 4, and failing actions.
EVENTS = [
    {"step": 3, "kind": "robot_down", "robot": 11},
    {"step": 4, "kind": "robot_up", "robot": 13},
    {"step": 2, "kind": "action_fails", "probability": 0.3},
]


def test_a_task_with_events_passes_pettingzoos_parallel_api_test(demo: coherent.Task) -> None:
    """Agents that leave and one that enters, as PettingZoo's test expects them to: the
    dicts of every step hold the agents acting and those that joined, none revived."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        parallel_api_test(CoherentParallelEnv(demo, events=EVENTS), num_cycles=200)
    said = [str(w.message) for w in caught]
    assert not [w for w in said if "given" in w or "revived" in w], said


def test_an_agent_down_terminates_and_one_that_joins_enters(demo: coherent.Task) -> None:
    names = demo.robot_names
    arm, drone, dog = names[6], names[11], names[13]
    env = CoherentParallelEnv(demo, events=EVENTS[:2])
    assert env.possible_agents == [arm, drone, dog]
    observations, infos = env.reset(seed=0)
    assert env.agents == [arm, drone] and set(observations) == set(infos) == {arm, drone}
    assert infos[arm]["news"] == []
    # Step 1, then step 2: after it, the quadrotor goes down.
    env.step({})
    observations, rewards, terminations, truncations, infos = env.step({drone: 1})
    assert set(observations) == set(rewards) == set(terminations) == set(truncations) == {arm, drone}
    assert terminations == {arm: False, drone: True}
    told = ["<quadrotor>(11) broke down: it stays where it is for good, and can do nothing more."]
    assert infos[arm]["news"] == infos[drone]["news"] == told
    assert infos[drone]["actions"] == [] and infos[drone]["action_mask"].tolist()[:2] == [1, 0]
    assert env.agents == [arm]
    with pytest.raises(coherent.ArgumentError, match="are not acting now"):
        env.step({drone: NOOP})
    # Step 3: after it, the dog joins, in the dicts of that step and in the agents.
    observations, rewards, terminations, truncations, infos = env.step({arm: NOOP})
    assert set(observations) == set(terminations) == {arm, dog}
    assert terminations == {arm: False, dog: False}
    assert infos[dog]["news"] == ["<robot dog>(13) joined the team in <kitchen>(0)."]
    assert infos[dog]["actions"] == coherent.Env(demo).actions(13)
    assert json.loads(observations[dog])["nodes"]
    assert env.agents == [arm, dog] and env.steps == 3 == env.env.steps
    # reset: the events from the start again.
    env.reset()
    assert env.agents == [arm, drone] and env.env.robots == [6, 11]


def test_failing_actions_follow_the_seed_of_reset(demo: coherent.Task) -> None:
    """Failing actions in joint steps: an agent's action that fails says so, and the same
    seed gives the same failures."""
    events = [{"step": 1, "kind": "action_fails", "probability": 0.5}]

    def outcomes(seed: int) -> list[tuple[bool | None, str | None]]:
        env = CoherentParallelEnv(demo, events=events)
        _, infos = env.reset(seed=seed)
        seen = []
        for _ in range(10):
            _, _, _, _, infos = env.step(dict.fromkeys(env.agents, 1))
            seen += [(infos[a]["ok"], infos[a]["reason"]) for a in env.possible_agents]
        return seen

    first = outcomes(4)
    assert first == outcomes(4)
    failed = [reason for ok, reason in first if ok is False]
    assert failed and set(failed) == {
        "the action failed (events[0]: each action fails with probability 0.5); nothing changed"
    }
    assert any(ok for ok, _ in first)
    assert outcomes(5) != first
