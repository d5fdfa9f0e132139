"""`Env.step(actions)`: one joint step, several robots acting at once, as a dict or a list
of pairs; per-robot outcomes; a refused step carries out nothing."""

from __future__ import annotations

import re

import pytest

import coherent
from conftest import DEMO

ARM, QUADROTOR, DOG = 6, 11, 13
GRAB = "[grab] <mug>(7)"
TO_FRIDGE = "[movetowards] <fridge>(8)"
TO_DOOR = "[movetowards] <door>(4)"


@pytest.fixture()
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def test_a_joint_step_moves_the_world_as_its_actions_in_turn(demo: coherent.Task) -> None:
    joint = coherent.Env(demo)
    oks, reasons, done = joint.step({ARM: GRAB, DOG: TO_FRIDGE})
    assert (oks, reasons, done) == ([True, True], [None, None], False)
    in_turn = coherent.Env(demo)
    assert in_turn.step(DOG, TO_FRIDGE)[0] and in_turn.step(ARM, GRAB)[0]
    assert joint.graph() == in_turn.graph()


def test_a_list_of_pairs_is_the_same_step_as_a_dict(demo: coherent.Task) -> None:
    by_dict, by_list = coherent.Env(demo), coherent.Env(demo)
    assert by_dict.step({DOG: TO_FRIDGE, ARM: GRAB}) == by_list.step([(DOG, TO_FRIDGE), (ARM, GRAB)])
    assert by_dict.graph() == by_list.graph()
    # One pair is a step of one robot; no pair, a step in which nobody acts.
    assert by_list.step([(QUADROTOR, "[takeoff_from] <coffee table>(10)")])[0] == [False]
    assert by_list.step([]) == ([], [], False)


def test_a_robot_given_two_actions_refuses_the_whole_step(demo: coherent.Task) -> None:
    env = coherent.Env(demo)
    before = env.graph()
    oks, reasons, done = env.step([(DOG, TO_DOOR), (ARM, GRAB), (DOG, TO_FRIDGE)])
    assert oks == [False, False, False] and not done
    said = (
        f"<robot dog>(13)'s {TO_DOOR} and <robot dog>(13)'s {TO_FRIDGE} interfere over the robot "
        "<robot dog>(13): it is given two actions in one step"
    )
    assert reasons[0] == reasons[2] == said
    # The arm's action is fine, but nothing of a refused step is carried out.
    assert reasons[1] == f"not carried out: the joint step was refused ({said})"
    assert env.graph() == before


def test_an_action_not_offered_refuses_the_step_with_its_own_reason(demo: coherent.Task) -> None:
    env = coherent.Env(demo)
    why = env.why_not(DOG, GRAB)
    assert why is not None
    oks, reasons, _ = env.step({ARM: GRAB, DOG: GRAB})
    assert oks == [False, False]
    assert reasons[1] == why
    assert reasons[0] == f"not carried out: the joint step was refused ({why})"
    assert env.actions(ARM) == coherent.Env(demo).actions(ARM)


def test_the_goal_reached_in_a_joint_step_is_done(demo: coherent.Task) -> None:
    env = coherent.Env(demo)
    plan = coherent.plan(demo)["plan"]
    for i, step in enumerate(plan):
        oks, _, done = env.step([(step["robot"], step["action"])])
        assert oks == [True] and done is (i == len(plan) - 1)
    assert env.goal_satisfied() and all(env.goal_holds())


def test_goal_holds_follows_each_predicate(demo: coherent.Task) -> None:
    env = coherent.Env(demo)
    assert len(env.goal_holds()) == len(demo.goal)
    assert not all(env.goal_holds())


SHAPE = "step(robot, action) tries one action, step(actions) a joint step: actions is a dict"


@pytest.mark.parametrize(
    ("actions", "error", "says"),
    [
        ({99: GRAB}, coherent.UnknownRobotError, "99"),
        ([(ARM,)], TypeError, SHAPE),
        ("[grab] <mug>(7)", TypeError, SHAPE),
        ({ARM: 7}, TypeError, "argument 'actions': 'int' object cannot be cast as 'str'"),
    ],
)
def test_a_joint_step_of_the_wrong_shape_raises(
    demo: coherent.Task, actions: object, error: type[Exception], says: str
) -> None:
    env = coherent.Env(demo)
    with pytest.raises(error, match=re.escape(says)):
        env.step(actions)  # type: ignore[call-overload]
    assert env.graph() == coherent.Env(demo).graph()


def test_robot_names_and_most_actions(demo: coherent.Task) -> None:
    assert demo.robot_names == {ARM: "robot_arm_6", QUADROTOR: "quadrotor_11", DOG: "robot_dog_13"}
    env = coherent.Env(demo)
    for robot in demo.robots:
        assert 0 < len(env.actions(robot)) <= demo.most_actions(robot)
    with pytest.raises(coherent.UnknownRobotError):
        demo.most_actions(7)
