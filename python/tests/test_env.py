"""Env: observations, action lists, steps, the goal test, reset, and a real episode."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import coherent
from conftest import TASK0_PLAN

NODE_KEYS = {"id", "category", "class_name", "prefab_name", "properties", "states"}
EDGE_KEYS = {"from_id", "to_id", "relation_type"}


def test_an_env_names_its_robots_and_task_and_starts_short_of_the_goal(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    assert env.robots == [22, 23, 24, 50]
    assert env.task.task_id == 0
    assert not env.goal_satisfied()
    assert repr(env) == "Env(scene='env0', task_id=0, robots=[22, 23, 24, 50], physics=False, goal_satisfied=False)"


def test_an_observation_holds_the_room_and_only_nodes_and_edges_the_robot_sees(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    obs = env.observe(22)
    assert set(obs) == {"room", "nodes", "edges"}
    assert isinstance(obs["room"], int)
    ids = {n["id"] for n in obs["nodes"]}
    assert 22 in ids and obs["room"] in ids
    assert all(set(n) == NODE_KEYS for n in obs["nodes"])
    assert all(set(e) == EDGE_KEYS for e in obs["edges"])
    # Observations only relate what the robot sees.
    assert all(e["from_id"] in ids and e["to_id"] in ids for e in obs["edges"])
    room = next(n for n in obs["nodes"] if n["id"] == obs["room"])
    assert room["category"] == "Rooms"


def test_a_landed_quadrotor_may_only_take_off(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    assert env.actions(22) == ["[takeoff_from] <childroom floor>(3)"]
    assert all(isinstance(a, str) for a in env.actions(23))


def _edge_set(edges: list[Any]) -> set[tuple[int, str, int]]:
    return {(e["from_id"], e["relation_type"], e["to_id"]) for e in edges}


def test_graph_is_the_whole_state(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    graph = env.graph()
    assert set(graph) == {"nodes", "edges"}
    original = task0.to_original()["init_graph"]
    assert {n["id"] for n in graph["nodes"]} == {n["id"] for n in original["nodes"]}
    assert _edge_set(graph["edges"]) == _edge_set(original["edges"])


def test_unparsable_action_is_not_executed(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    before = env.graph()
    ok, reason, done = env.step(22, "fly to the kitchen")
    assert (ok, done) == (False, False)
    assert reason is not None and "cannot parse" in reason
    assert env.graph() == before


def test_infeasible_action_says_why(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    ok, reason, done = env.step(22, "[land_on] <high kitchen table>(35)")
    assert not ok and not done
    assert isinstance(reason, str) and reason
    ok, reason, _ = env.step(24, "[grab] <apple>(999)")
    assert not ok
    assert reason is not None and "999" in reason


@pytest.mark.parametrize("method", ["observe", "actions", "step"])
def test_unknown_robot(task0: coherent.Task, method: str) -> None:
    env = coherent.Env(task0)
    args = (35, "[grab] <apple>(3)") if method == "step" else (35,)
    with pytest.raises(coherent.UnknownRobotError, match="35 is not a robot") as info:
        getattr(env, method)(*args)
    assert "22 (quadrotor)" in str(info.value)
    assert isinstance(info.value, coherent.CoherentError)


def test_unknown_robot_out_of_range(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    with pytest.raises(coherent.UnknownRobotError):
        env.actions(-1)
    # Beyond the 64 bits of node ids: no robot either (it was an OverflowError).
    with pytest.raises(coherent.UnknownRobotError, match=r"robot=1180591620717411303424: no node id is that large"):
        env.actions(2**70)


def test_episode_replays_the_optimal_plan(task0: coherent.Task) -> None:
    result = coherent.plan(task0)
    steps = [(s["robot"], s["action"]) for s in result["plan"]]
    assert steps == TASK0_PLAN
    env = coherent.Env(task0)
    for i, (robot, action) in enumerate(steps):
        assert action in env.actions(robot)
        ok, reason, done = env.step(robot, action)
        assert ok, f"step {i} {action!r}: {reason}"
        assert reason is None
        assert done == (i == len(steps) - 1)
    assert env.goal_satisfied()
    quadrotor = next(n for n in env.graph()["nodes"] if n["id"] == 22)
    assert "LAND" in quadrotor["states"]


def test_reset_brings_back_the_initial_graph_after_the_goal_is_reached(task1: coherent.Task) -> None:
    env = coherent.Env(task1)
    start = env.graph()
    for step in coherent.plan(task1)["plan"]:
        assert env.step(step["robot"], step["action"])[0]
    assert env.goal_satisfied()
    assert env.graph() != start
    env.reset()
    assert env.graph() == start
    assert not env.goal_satisfied()


def test_envs_of_one_task_are_independent(task0: coherent.Task) -> None:
    a, b = coherent.Env(task0), coherent.Env(task0)
    assert a.step(*TASK0_PLAN[0])[0]
    assert a.graph() != b.graph()
    assert b.actions(22) == ["[takeoff_from] <childroom floor>(3)"]


def test_physical_env_carries_the_optimal_plan_out_in_rapier() -> None:
    demo = Path(__file__).resolve().parents[2] / "examples" / "tasks" / "demo.json"
    task = coherent.load_tasks(demo)[0]
    env = coherent.Env(task, physics=True)
    assert env.physics and "physics=True" in repr(env)
    ok, reason, _ = env.step(13, "[grab] <mug>(7)")
    assert not ok and reason  # the rules still refuse first, with their reason
    done = False
    for step in coherent.plan(task)["plan"]:
        ok, reason, done = env.step(step["robot"], step["action"])
        assert ok, reason
    assert done and env.goal_satisfied()
    env.reset()
    assert not env.goal_satisfied()
    assert issubclass(coherent.PhysicsError, coherent.CoherentError)


def test_why_not_checks_without_acting(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    before = env.graph()
    assert env.why_not(22, TASK0_PLAN[0][1]) is None
    reason = env.why_not(22, "[grab] <apple>(3)")
    assert reason is not None and "cannot [grab]" in reason
    # The same reason a refused step gives.
    assert env.step(22, "[grab] <apple>(3)") == (False, reason, False)
    assert env.graph() == before


def test_why_not_a_bad_action_string(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    reason = env.why_not(22, "fly to the kitchen")
    assert reason is not None and reason.startswith("cannot parse")
    with pytest.raises(coherent.ActionParseError) as info:
        coherent.parse_action("fly to the kitchen")
    assert info.value.action == "fly to the kitchen"


def test_why_not_unknown_robot(task0: coherent.Task) -> None:
    env = coherent.Env(task0)
    with pytest.raises(coherent.UnknownRobotError, match="35 is not a robot"):
        env.why_not(35, "[grab] <apple>(3)")
