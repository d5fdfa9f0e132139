"""plan, validate and parse_action."""

from __future__ import annotations

import inspect
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import coherent
from conftest import TASK0_PLAN

PLAN_KEYS = {
    "scene", "task_id", "gt_steps", "optimal_steps", "solvable", "reason",
    "task_type", "plan", "states_expanded", "elapsed_ms",
}  # fmt: skip


def test_plan_gives_the_shortest_plan_with_the_documented_keys(task0: coherent.Task) -> None:
    result = coherent.plan(task0)
    assert set(result) == PLAN_KEYS
    assert result["scene"] == "env0" and result["task_id"] == 0
    assert result["solvable"] is True and result["reason"] is None
    assert result["optimal_steps"] == result["gt_steps"] == 5
    assert result["task_type"] == "mono"
    assert [(s["robot"], s["action"]) for s in result["plan"]] == TASK0_PLAN
    assert result["states_expanded"] > 0
    assert isinstance(result["elapsed_ms"], float)


def test_plan_equals_the_cli_json(env0_path: Path, task1: coherent.Task) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "coherent._cli", "plan", str(env0_path), "--task", "1", "--json"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    from_cli = json.loads(out.stdout)
    from_py = dict(coherent.plan(task1))
    from_cli.pop("elapsed_ms")
    from_py.pop("elapsed_ms")
    assert from_py == from_cli


def test_plan_stops_at_the_state_limit(task0: coherent.Task) -> None:
    result = coherent.plan(task0, max_states=3)
    assert result["solvable"] is False
    assert result["optimal_steps"] is None and result["plan"] == []
    assert result["reason"] is not None and "limit of 3 states" in result["reason"]
    assert coherent.plan(task0, 3)["reason"] == result["reason"]  # positional too


PARALLEL_KEYS = {
    "makespan", "makespan_proven", "makespan_lower", "makespan_stop", "parallel_plan",
    "makespan_states_expanded", "makespan_ms",
}  # fmt: skip


def test_plan_parallel_gives_the_fewest_joint_steps_as_the_cli(
    env0_path: Path, env0_tasks: list[coherent.Task]
) -> None:
    # env0 task 9: 9 steps in turn, 8 when the arm grabs the plate as the quadrotor
    # takes off.
    task9 = next(t for t in env0_tasks if t.task_id == 9)
    result = coherent.plan(task9, parallel=True)
    assert set(result) == PLAN_KEYS | PARALLEL_KEYS
    assert result["optimal_steps"] == 9
    assert (result["makespan"], result["makespan_proven"], result["makespan_lower"]) == (8, True, 8)
    assert result["makespan_stop"] is None
    steps = result["parallel_plan"]
    assert steps is not None and len(steps) == 8
    assert [(a["robot"], a["action"]) for a in steps[0]] == [
        (22, "[takeoff_from] <livingroom floor>(5)"),
        (24, "[grab] <plate>(51)"),
    ]
    assert sorted(a["action"] for step in steps for a in step) == sorted(a["action"] for a in result["plan"])
    out = subprocess.run(
        [sys.executable, "-m", "coherent._cli", "plan", str(env0_path), "--task", "9", "--parallel", "--json"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    untimed = [
        {k: v for k, v in line.items() if k not in ("elapsed_ms", "makespan_ms")}
        for line in (json.loads(out.stdout), dict(result))
    ]
    assert untimed[0] == untimed[1]
    assert set(coherent.plan(task9)) == PLAN_KEYS  # nothing parallel unless asked


PHYSICS_KEYS = {"physics_ok", "physics_error", "sim_seconds", "physics_wall_ms"}


def test_plan_parallel_physics_runs_both_plans_in_rapier_as_the_cli(
    env0_path: Path, env0_tasks: list[coherent.Task]
) -> None:
    # env0 task 9 again: its 8 joint steps carried out in Rapier, the quadrotor taking
    # off while the arm grabs the plate, next to its 9 steps in turn.
    task9 = next(t for t in env0_tasks if t.task_id == 9)
    result = coherent.plan(task9, parallel=True, physics=True)
    joint_keys = {f"makespan_{k}" for k in PHYSICS_KEYS}
    assert set(result) == PLAN_KEYS | PARALLEL_KEYS | PHYSICS_KEYS | joint_keys
    assert result["physics_ok"] is True and result["makespan_physics_ok"] is True
    assert result["physics_error"] is None and result["makespan_physics_error"] is None
    assert 1.0 < result["makespan_sim_seconds"] < result["sim_seconds"]
    assert set(coherent.plan(task9, physics=True)) == PLAN_KEYS | PHYSICS_KEYS
    out = subprocess.run(
        [sys.executable, "-m", "coherent._cli", "plan", str(env0_path), "--task", "9", "--parallel", "--physics", "--json"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    timed = {"elapsed_ms", "makespan_ms", "physics_wall_ms", "makespan_physics_wall_ms"}
    untimed = [
        {k: v for k, v in line.items() if k not in timed} for line in (json.loads(out.stdout), dict(result))
    ]
    assert untimed[0] == untimed[1]


def test_plan_parallel_at_a_limit_keeps_the_scheduled_plan_and_a_lower_bound(
    env0_tasks: list[coherent.Task],
) -> None:
    task9 = next(t for t in env0_tasks if t.task_id == 9)
    result = coherent.plan(task9, max_states=500, parallel=True)
    assert result["optimal_steps"] == 9
    assert (result["makespan"], result["makespan_proven"], result["makespan_stop"]) == (8, False, "states")
    assert 1 <= result["makespan_lower"] < 8


def test_plan_rejects_negative_limit(task0: coherent.Task) -> None:
    with pytest.raises(coherent.ArgumentError, match=r"^max_states=-1: out of range: 0 to 18446744073709551615$"):
        coherent.plan(task0, max_states=-1)


def test_plan_needs_a_task() -> None:
    with pytest.raises(TypeError):
        coherent.plan("env0.json")  # type: ignore[arg-type]


def test_validate_clean_task(task0: coherent.Task) -> None:
    assert coherent.validate(task0) == []


def test_validate_reports_problems(task0: coherent.Task) -> None:
    findings = coherent.validate(task0, max_states=3)
    assert len(findings) == 1
    assert findings[0].startswith(
        "the goal could not be decided within the search limits: search stopped at the limit of 3 states"
    )


def test_parse_action() -> None:
    assert coherent.parse_action("[grab] <apple>(3)") == {
        "verb": "grab",
        "object": {"name": "apple", "id": 3},
        "target": None,
    }
    assert coherent.parse_action("  [putinto] <apple>(3) into <fridge>(7) ") == {
        "verb": "putinto",
        "object": {"name": "apple", "id": 3},
        "target": {"name": "fridge", "id": 7},
    }
    assert coherent.parse_action("[land_on] <high kitchen table>(35)")["object"] == {
        "name": "high kitchen table",
        "id": 35,
    }


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("", "empty action"),
        ("grab apple", "starts with [verb]"),
        ("[fly] <apple>(3)", 'unknown verb "fly"'),
        ("[grab] <apple>(x)", 'id "x" is not an integer'),
        ("[puton] <apple>(3)", '"puton" needs|needs " on <name>(id)"'),
        ("[grab] <apple>(3) now", "unexpected text"),
    ],
)
def test_parse_action_errors(text: str, reason: str) -> None:
    with pytest.raises(coherent.ActionParseError) as info:
        coherent.parse_action(text)
    assert any(r in info.value.reason for r in reason.split("|")), info.value.reason
    assert info.value.action == text
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, coherent.CoherentError)


def _interrupt_soon(delay: float) -> threading.Timer:
    timer = threading.Timer(delay, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.fixture()
def exhaustive_task(tmp_path: Path) -> coherent.Task:
    """Our benchmark's s1-apartment with only the robot dog left, asked to move five
    things, one of them the mug on the kitchen island, which is out of its reach. Nothing
    rules the goal out statically, so the planner must search every state of the dog
    and those five things (about 900,000, seconds) to find it unreachable."""
    task = json.loads(next(t for t in coherent.benchmark.tasks() if t.scene == "s1-apartment").to_json())
    names = {n["class_name"]: n["id"] for n in task["graph"]["nodes"]}
    gone = {names["robot arm"], names["quadrotor"], names["basket"]}
    task["graph"]["nodes"] = [n for n in task["graph"]["nodes"] if n["id"] not in gone]
    task["graph"]["edges"] = [
        e for e in task["graph"]["edges"] if e["from_id"] not in gone and e["to_id"] not in gone
    ]
    task["geometry"]["robots"] = [r for r in task["geometry"]["robots"] if r["id"] not in gone]
    task["robots"] = [r for r in task["robots"] if r["id"] not in gone]
    moves = [
        ("apple", "bed"),
        ("milk", "sink counter"),
        ("pan", "dining table"),
        ("towel", "coffee table"),
        ("mug", "nightstand"),
    ]
    task["goal"] = [
        {"relation": "ON", "subject": names[a], "target": names[b], "count": 1} for a, b in moves
    ]
    path = tmp_path / "s1-dog-only.json"
    path.write_text(json.dumps(task), encoding="utf-8")
    return coherent.load_tasks(path)[0]


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to oneself is POSIX")
def test_plan_is_interruptible(exhaustive_task: coherent.Task) -> None:
    # Ctrl-C reaches Python within 50 ms and cancels the search itself, which stops
    # within about a thousand states: the call returns at once, the CPU is free again.
    # A runner started in the background (`cmd &`) inherits SIGINT ignored, and Python
    # then keeps it ignored: put Python's own handler in place for this test.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = _interrupt_soon(0.3)
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            coherent.plan(exhaustive_task)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert time.monotonic() - start < 2
    # The worker thread is gone: no more CPU time accrues to this process.
    cpu = time.process_time()
    time.sleep(0.3)
    assert time.process_time() - cpu < 0.1


def test_default_limit_is_the_cli_default(capfd: pytest.CaptureFixture[str]) -> None:
    assert coherent.cli_main(["coherent", "plan", "--help"]) == 0
    usage = capfd.readouterr().out
    assert f"[default: {coherent.DEFAULT_MAX_STATES}]" in usage
    # The native functions take the same constant (shown as `...`); coherent.bench too.
    for function in (coherent.plan, coherent.validate, coherent.run):
        assert inspect.signature(function).parameters["max_states"].default is Ellipsis
    assert inspect.signature(coherent.bench).parameters["max_states"].default == coherent.DEFAULT_MAX_STATES
