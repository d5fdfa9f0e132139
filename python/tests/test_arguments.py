"""Arguments of the right type whose values the engine cannot take raise the package's
own errors, whose messages name the argument and show the value cut down: ints beyond
64 bits, strs with a lone surrogate (which UTF-8 cannot encode), floats that are not
finite. Arguments of the wrong type stay `TypeError`s."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

import coherent
from coherent import _coherent
from conftest import DEMO

# The robot dog of the demo task, and an action of it that the rules refuse.
DOG = 13
GRAB = "[grab] <mug>(7)"


@pytest.fixture()
def env() -> coherent.Env:
    return coherent.Env(coherent.load_tasks(DEMO)[0])


@pytest.fixture(scope="module")
def line(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """One line of a results file, as `coherent.report` takes it."""
    out = tmp_path_factory.mktemp("line") / "results.jsonl"
    coherent.bench(coherent.load_tasks(DEMO), ["optimal"], out=out)
    [first] = _coherent.read_results(out)
    return first


def test_argument_error_is_a_coherent_value_error() -> None:
    assert issubclass(coherent.ArgumentError, coherent.CoherentError)
    assert issubclass(coherent.ArgumentError, ValueError)


@pytest.mark.parametrize("robot", [2**63, -(2**63) - 1, 2**70])
@pytest.mark.parametrize("method", ["observe", "actions", "why_not", "step"])
def test_a_robot_id_beyond_64_bits_is_no_robot(env: coherent.Env, method: str, robot: int) -> None:
    args = (robot, GRAB) if method in ("why_not", "step") else (robot,)
    with pytest.raises(coherent.UnknownRobotError) as info:
        getattr(env, method)(*args)
    assert str(info.value) == (
        f"robot={robot}: no node id is that large; the robots of task demo-apartment/0 are "
        "6 (robot arm), 11 (quadrotor), 13 (robot dog)"
    )


@pytest.mark.parametrize("method", ["why_not", "step"])
def test_an_action_with_a_lone_surrogate_does_not_parse(env: coherent.Env, method: str) -> None:
    action = GRAB + "\ud800"
    before = env.graph()
    with pytest.raises(coherent.ActionParseError) as info:
        getattr(env, method)(DOG, action)
    assert str(info.value) == (
        r"cannot parse action '[grab] <mug>(7)\ud800': '\ud800' at index 15 is a lone surrogate, not a character"
    )
    assert info.value.action == action
    assert info.value.reason == r"'\ud800' at index 15 is a lone surrogate, not a character"
    assert env.graph() == before
    # The same action without it is refused by the rules, not raised.
    assert env.step(DOG, GRAB)[0] is False


def test_a_long_value_is_cut_down_in_the_message(env: coherent.Env) -> None:
    action = "\ud800" + "x" * 10_000
    with pytest.raises(coherent.ActionParseError) as info:
        env.step(DOG, action)
    # The repr's first 40 characters and its last 16.
    shown = str(info.value).split(": ")[0]
    assert shown == "cannot parse action '\\ud800" + "x" * 33 + "..." + "x" * 15 + "'"


def test_arguments_of_the_wrong_type_stay_type_errors(env: coherent.Env) -> None:
    with pytest.raises(TypeError, match="argument 'robot'"):
        env.actions("13")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'robot'"):
        env.step(13.0, GRAB)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'action'"):
        env.step(DOG, b"[grab] <mug>(7)")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'action'"):
        env.why_not(DOG, None)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("wall_ms", math.inf, r"$['wall_ms']=inf: not a finite number"),
        ("wall_ms", -math.inf, r"$['wall_ms']=-inf: not a finite number"),
        ("steps", 2**64, r"$['steps']=18446744073709551616: an int beyond the 64 bits of JSON numbers"),
        ("scene", "env\udc80", r"$['scene']='env\udc80': '\udc80' at index 3 is a lone surrogate, not a character"),
        ("backend", {"kind\ud800": 1}, r"$['backend']['kind\ud800']='kind\ud800': '\ud800' at index 4 is a lone surrogate, not a character"),
    ],
)
def test_results_lines_json_cannot_hold(line: dict[str, Any], field: str, value: Any, message: str) -> None:
    bad = {**line, field: value}
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.report([line, bad])
    assert str(info.value) == message


def test_a_results_line_key_of_the_wrong_type(line: dict[str, Any]) -> None:
    with pytest.raises(TypeError, match=r"\$\[1\]: a key that is not a string"):
        coherent.report([{**line, 1: "x"}])  # type: ignore[dict-item]


@pytest.mark.parametrize("by", ["table", ""])
def test_plot_table_by(by: str) -> None:
    plot = pytest.importorskip("coherent.plot")
    with pytest.raises(coherent.ArgumentError) as info:
        plot.table([], by=by)  # type: ignore[arg-type]
    assert str(info.value) == f'by={by!r}: expected "type" or "scene"'


def test_gym_reset_seed(env: coherent.Env) -> None:
    gym = pytest.importorskip("coherent.gym")
    genv = gym.CoherentEnv(env.task)
    with pytest.raises(coherent.ArgumentError, match=r"^seed=-1: expected an int from 0$"):
        genv.reset(seed=-1)
    with pytest.raises(TypeError):
        genv.reset(seed=1.5)  # type: ignore[arg-type]
    genv.reset(seed=2**70)


def test_gym_step_arguments(env: coherent.Env) -> None:
    gym = pytest.importorskip("coherent.gym")
    genv = gym.CoherentEnv(env.task)
    genv.reset()
    with pytest.raises(coherent.UnknownRobotError, match="robot=18446744073709551616: no node id"):
        genv.step((2**64, GRAB))
    with pytest.raises(coherent.ActionParseError):
        genv.step((DOG, GRAB + "\udfff"))
    # A float is no robot id: not rounded, and NaN is no ValueError.
    for robot in (13.0, math.nan):
        with pytest.raises(TypeError):
            genv.step((robot, GRAB))
    assert genv.steps == 0
