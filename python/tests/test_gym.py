"""coherent.gym.CoherentEnv: the Gymnasium interface over Env."""

from __future__ import annotations

import json

import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import coherent  # noqa: E402
from coherent.gym import CoherentEnv, RobotSpace  # noqa: E402
from conftest import TASK0_PLAN  # noqa: E402


def test_passes_gymnasiums_checker(task0: coherent.Task) -> None:
    check_env(CoherentEnv(task0), skip_render_check=True)


def test_reset_observation_and_info(task0: coherent.Task) -> None:
    env = CoherentEnv(task0)
    obs, info = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    assert json.loads(obs) == coherent.Env(task0).graph()
    assert info["actions"][22] == ["[takeoff_from] <childroom floor>(3)"]
    assert set(info["actions"]) == set(task0.robots)
    assert info["steps"] == 0 and info["ok"] is None


def test_the_optimal_plan_earns_the_reward(task0: coherent.Task) -> None:
    env = CoherentEnv(task0)
    env.reset()
    rewards = []
    for i, action in enumerate(TASK0_PLAN):
        assert env.action_space.contains(action)
        _, reward, terminated, truncated, info = env.step(action)
        rewards.append(reward)
        assert info["ok"] and info["reason"] is None
        assert terminated == (i == len(TASK0_PLAN) - 1) and not truncated
    assert rewards == [0.0, 0.0, 0.0, 0.0, 1.0]
    obs, _ = env.reset()
    assert json.loads(obs) == coherent.Env(task0).graph()


def test_a_refused_action_and_truncation(task0: coherent.Task) -> None:
    env = CoherentEnv(task0, max_steps=2)
    env.reset()
    before = env.env.graph()
    _, reward, terminated, truncated, info = env.step((22, "fly to the kitchen"))
    assert (reward, terminated, truncated, info["ok"]) == (0.0, False, False, False)
    assert info["reason"].startswith("cannot parse")
    assert env.env.graph() == before
    _, _, terminated, truncated, info = env.step((24, "[grab] <apple>(999)"))
    assert not terminated and truncated and "999" in info["reason"]


def test_default_budget_is_twice_the_ground_truth(task0: coherent.Task) -> None:
    assert CoherentEnv(task0).max_steps == 2 * task0.gt


def test_unknown_robot(task0: coherent.Task) -> None:
    env = CoherentEnv(task0)
    env.reset()
    with pytest.raises(coherent.UnknownRobotError):
        env.step((35, "[grab] <apple>(3)"))


def test_robot_space_samples_and_contains_only_the_tasks_robots(task0: coherent.Task) -> None:
    space = RobotSpace(task0.robots, seed=3)
    assert {space.sample() for _ in range(50)} == set(task0.robots)
    assert space.contains(22) and not space.contains(35) and not space.contains("22")
    assert space == RobotSpace(task0.robots) and space != RobotSpace([22])
    assert repr(space) == "RobotSpace([22, 23, 24, 50])"
