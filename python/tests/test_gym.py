"""coherent.gym.CoherentEnv: the Gymnasium interface over Env, with events too (the news
in the info, a robot out of the team offered nothing)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import coherent  # noqa: E402
from coherent.gym import CoherentEnv, RobotSpace  # noqa: E402
from conftest import DEMO, TASK0_PLAN  # noqa: E402

#: The demo's events (the arm down once the mug is in the basket, a door locked for two
#: steps), a robot that joins later and failing actions.
EVENTS = [
    {"when": {"relation": "INSIDE", "subject": 7, "target": 12}, "kind": "robot_down", "robot": 6},
    {"step": 9, "kind": "blocked", "door": 4, "steps": 2},
    {"step": 3, "kind": "robot_up", "robot": 13},
    {"step": 2, "kind": "action_fails", "probability": 0.2},
]


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


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def test_a_task_with_events_passes_gymnasiums_checker(demo: coherent.Task) -> None:
    check_env(CoherentEnv(demo, events=EVENTS), skip_render_check=True)


def test_events_in_the_info_and_a_robot_out_of_the_team_offered_nothing(demo: coherent.Task, tmp_path: Path) -> None:
    """The optimal method's episode with the events, its actions played through the
    Gymnasium env: the same news before each step, the same outcomes; a robot that has not
    joined yet or went down is offered nothing, and an action given to it does nothing
    but takes the step."""
    episode = coherent.run(demo, "optimal", events=EVENTS, seed=5, max_steps=80, out=tmp_path)
    assert episode.summary["status"] == "success"
    env = CoherentEnv(demo, events=EVENTS, max_steps=80)
    assert env.robots == [6, 11, 13]
    _, info = env.reset(seed=5)
    assert info["robots"] == [6, 11] and info["actions"][13] == [] and info["news"] == []
    went_down = False
    for round_ in episode.transcript:
        told = [e["told"] for e in round_.get("events") or [] if e["told"]]
        assert info["news"] == told
        if 6 not in info["robots"] and not went_down:
            went_down = True
            assert info["actions"][6] == []
        decision = round_.get("decision")
        if not (decision and decision.get("can_do") and decision.get("action")):
            # Nothing to do (a door locked): words that are no action let the step go by.
            _, reward, terminated, truncated, info = env.step((11, "wait"))
            assert info["ok"] is False and info["reason"]
            continue
        _, reward, terminated, truncated, info = env.step((decision["robot"], decision["action"]))
        assert info["ok"] == (round_["outcome"]["kind"] == "executed")
        assert info["reason"] == round_["outcome"].get("message")
        assert terminated == round_["done"] and not truncated
    assert went_down and terminated and reward == 1.0
    assert info["steps"] == episode.steps == env.env.steps
    # An action given to the robot down does nothing, and the step is taken.
    _, _, _, _, info = env.step((6, "[grab] <apple>(9)"))
    assert info["ok"] is False and info["reason"].startswith("robot 6 is not in the team now")
    assert info["steps"] == env.env.steps == episode.steps + 1
