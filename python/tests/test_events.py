"""Events from Python (docs/dynamic.md): `coherent.run(events=...)` with a list or a file,
the episode against its reference, a method written in Python told what happened in its
view's `news`, bad events raised as `TaskFormatError` naming `events=`, the JSON path
and the value, before anything runs, a real small model told of an event end to end;
`coherent.Env` stepped by hand meeting each kind as the episode does (the optimal
method's actions carried out in it: the same news, outcomes and end, in sequential and
joint steps, by the rules and in physics), the team as it is now, failing actions drawn
by the seed, and refused where they cannot be carried out;
and the reference in `coherent.analysis`: the results frame's columns, and the events
table worked out in pandas equal to the Rust report's, number for number."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import coherent
from coherent import analysis
from conftest import DEMO, REPO

MOVED = [{"step": 3, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]
TOLD = "Someone outside the team moved <apple>(9) onto <sofa>(14)."
DEMO_EVENTS = REPO / "examples" / "events" / "demo.json"


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def test_a_run_with_events_ends_in_the_reference_steps(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, "pefa", events=MOVED, out=tmp_path)
    summary = episode.summary
    assert summary["status"] == "success"
    assert summary["reference"]["steps"] == summary["steps"] == episode.steps
    assert summary["reference"]["kinds"] == ["object_moved"]
    # The same events from a file.
    path = tmp_path / "events.json"
    path.write_text(json.dumps({"events": MOVED}))
    again = coherent.run(demo, "pefa", events=path, out=tmp_path)
    assert again.summary["reference"] == summary["reference"]


class Told:
    """Takes the first action of the first robot that has one, and keeps what it was told
    at each step (in `Told.news`, for the test to read)."""

    name = "told"
    news: list[list[str]] = []

    def __init__(self, task: coherent.Task) -> None:
        Told.news = []

    def act(self, view: coherent.View) -> tuple[int, str]:
        Told.news.append(view.news)
        robot = next(r for r in view.robots if view.actions[r])
        return robot, view.actions[robot][0]


def test_a_python_method_is_told_in_its_view(demo: coherent.Task, tmp_path: Path) -> None:
    coherent.run(demo, Told, events=MOVED, max_steps=4, out=tmp_path)
    assert Told.news == [[], [], [TOLD], []]


@pytest.mark.parametrize(
    ("events", "path", "words"),
    [
        ([{"step": 3, "kind": "robot_down", "robot": 7}], "$[0].robot", "not a robot"),
        ([{"step": 45, "kind": "robot_down", "robot": 13}], "$[0].step", "past the episode's step budget"),
        ({"events": [{"step": 2, "kind": "blocked", "door": 9}]}, "$.events[0].door", "is not a door"),
    ],
)
def test_bad_events_raise_before_anything_runs(
    demo: coherent.Task, tmp_path: Path, events: object, path: str, words: str
) -> None:
    with pytest.raises(coherent.TaskFormatError, match=words) as raised:
        coherent.run(demo, "pefa", events=events, out=tmp_path / "runs")
    assert raised.value.file == "events="
    assert raised.value.json_path == path
    assert not (tmp_path / "runs").exists()


def test_a_small_model_hears_of_an_event_end_to_end(
    demo: coherent.Task, local_model: str, tmp_path: Path
) -> None:
    """SmolLM2-135M behind llama.cpp's server runs PEFA on the demo task with the apple
    moved before step 2: the episode runs through, the optimum is proven at the start
    and at the event, and both prompts of the round after it say what happened first (its
    success is not asked)."""
    llm = coherent.LLM(base_url=f"{local_model}/v1", model="smollm2-135m")
    events = [{"step": 2, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]
    episode = coherent.run(demo, "pefa", llm=llm, events=events, max_steps=2, out=tmp_path)
    assert episode.steps == 2
    reference = episode.summary["reference"]
    assert reference["start"] == {"steps": 22}
    first, second = episode.transcript
    assert first.get("events") is None
    (happened,) = second["events"]
    assert happened["told"] == "Someone outside the team moved <apple>(9) onto <sofa>(14)."
    assert happened["optimum"]["steps"] >= 1
    assert second["calls"], "the model was asked"
    for call in second["calls"]:
        user = call["messages"][-1]["content"]
        assert "What just happened, that the team did not do:\n- " + happened["told"] in user


#: One event of each kind on the demo task, as crates/coherent-agents/tests/events.rs has
#: them, and the demo's own list.
KINDS: dict[str, list[dict[str, Any]]] = {
    "robot_down": [
        {"when": {"relation": "INSIDE", "subject": 7, "target": 12}, "kind": "robot_down", "robot": 6}
    ],
    "robot_up": [{"step": 6, "kind": "robot_up", "robot": 13, "room": 0}],
    "object_moved": [{"when": {"held": 7}, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}],
    "goal_changed": [
        {
            "step": 5,
            "kind": "goal_changed",
            "remove": [{"relation": "ON", "subject": 9, "target": 10}],
            "add": [{"relation": "ON", "subject": 9, "target": 14}],
            "instruction": "The mug to the coffee table, the apple to the sofa.",
        }
    ],
    "blocked": [{"step": 2, "kind": "blocked", "door": 4, "steps": 3}],
    "action_fails": [{"step": 2, "kind": "action_fails", "probability": 0.5}],
    "demo": json.loads(DEMO_EVENTS.read_text())["events"],
}


def _told(round_: dict[str, Any]) -> list[str]:
    """What the team was told before a round of a transcript."""
    return [e["told"] for e in round_.get("events") or [] if e["told"]]


def _acted(decision: dict[str, Any] | None) -> tuple[int, str] | None:
    """The robot and action a decision carries out, if any."""
    if decision and decision.get("can_do") and decision.get("action") and decision.get("robot") is not None:
        return decision["robot"], decision["action"]
    return None


def _play_in_env(env: coherent.Env, episode: coherent.Episode, parallel: bool) -> None:
    """Carries out an episode's actions in `env`, round by round: before each, `env` was
    told what the round was, and each action comes out as it did in the episode (ran, or
    the same reason: a failing action's draw included)."""
    for round_ in episode.transcript:
        assert env.steps == round_["step"] - 1
        assert env.news == _told(round_), f"step {round_['step']}"
        if parallel:
            parts = [(p, _acted(p.get("decision"))) for p in round_.get("parts") or []]
            acting = [(p, act) for p, act in parts if act]
            oks, reasons, done = env.step([act for _, act in acting])
            for (part, _), ok, reason in zip(acting, oks, reasons, strict=True):
                assert ok == (part["outcome"]["kind"] == "executed")
                assert reason == part["outcome"].get("message")
        elif act := _acted(round_.get("decision")):
            ok, reason, done = env.step(*act)
            assert ok == (round_["outcome"]["kind"] == "executed")
            assert reason == round_["outcome"].get("message")
        else:
            _, _, done = env.step([])
        assert done == round_["done"]
    assert env.steps == episode.steps


@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("execution", ["sequential", "parallel"])
def test_env_meets_the_events_as_an_episode_does(
    demo: coherent.Task, tmp_path: Path, kind: str, execution: str
) -> None:
    """The optimal method's episode with the events, its actions carried out in `Env`
    stepped by hand with the same events and seed: the same news before the same steps,
    the same outcomes (the failing actions' draws, the robots out of the team), the goal
    reached at the same step."""
    events = KINDS[kind]
    episode = coherent.run(demo, "optimal", events=events, seed=3, execution=execution, max_steps=80, out=tmp_path)
    assert episode.summary["status"] == "success"
    env = coherent.Env(demo, events=events, seed=3)
    _play_in_env(env, episode, execution == "parallel")
    assert env.goal_satisfied()
    # reset: the events from the start again, and the same episode.
    env.reset()
    _play_in_env(env, episode, execution == "parallel")


def test_a_robot_down_leaves_the_team_and_one_that_joins_enters_it(demo: coherent.Task) -> None:
    """Along the demo's optimal plan, the arm goes down once the mug is in the basket: it
    leaves `Env.robots` before the next step, and an action given to it raises."""
    env = coherent.Env(demo, events=KINDS["robot_down"])
    assert env.robots == [6, 11, 13]
    for step in coherent.plan(demo)["plan"]:
        assert env.step(step["robot"], step["action"])[0]
        if env.news:
            break
    assert env.robots == [11, 13]
    assert env.news == ["<robot arm>(6) broke down: it stays where it is for good, and can do nothing more."]
    assert env.task.robots == [6, 11, 13], "the task's robots are all there"
    with pytest.raises(coherent.UnknownRobotError, match="its robots are 11 .*, 13 "):
        env.step(6, "[grab] <apple>(9)")
    with pytest.raises(coherent.UnknownRobotError):
        env.actions(6)
    taken = env.steps
    with pytest.raises(coherent.UnknownRobotError):
        env.step([(11, "[land_on] <kitchen counter>(5)"), (6, "[grab] <apple>(9)")])
    assert env.steps == taken, "a step refused before it is taken takes none"
    assert env.news, "and the news stay those of the coming step"
    # A robot that joins later is out of the team until then.
    env = coherent.Env(demo, events=KINDS["robot_up"])
    assert env.robots == [6, 11]
    for _ in range(5):
        assert env.step([]) == ([], [], False)
    assert env.steps == 5
    assert env.robots == [6, 11, 13]
    assert env.news == ["<robot dog>(13) joined the team in <kitchen>(0)."]
    assert "[movetowards] <door>(4)" in env.actions(13)


def test_a_failing_action_says_so_and_the_draws_follow_the_seed(demo: coherent.Task) -> None:
    """Each step, robot 13 opens or closes the door: which tries fail is the seed's, the
    same for the same seed; a failed one changes nothing."""
    events = [{"step": 1, "kind": "action_fails", "probability": 0.5, "robot": 13}]

    def tries(env: coherent.Env) -> list[bool]:
        env.step(13, "[movetowards] <door>(4)")
        oks = []
        while len(oks) < 12:
            action = "[open] <door>(4)" if env.why_not(13, "[open] <door>(4)") is None else "[close] <door>(4)"
            ok, reason, _ = env.step(13, action)
            if not ok:
                assert reason == (
                    "the action failed (events[0]: each action fails with probability 0.5); nothing changed"
                )
                assert env.why_not(13, action) is None, "nothing changed"
            oks.append(ok)
        return oks

    first = tries(coherent.Env(demo, events=events, seed=7))
    assert first == tries(coherent.Env(demo, events=events, seed=7))
    assert not all(first) and any(first)
    other = coherent.Env(demo, events=events, seed=7)
    other.reset(seed=8)
    assert other.seed == 8
    assert tries(other) != first
    # The others' actions never fail.
    env = coherent.Env(demo, events=events, seed=7)
    assert all(env.step(6, env.actions(6)[0])[0] for _ in range(12))


def test_a_goal_changed_is_the_envs_goal_and_instruction(demo: coherent.Task) -> None:
    env = coherent.Env(demo, events=KINDS["goal_changed"])
    before = env.goal
    for _ in range(4):
        env.step([])
    assert env.goal != before
    assert "on_<apple>(9)_<sofa>(14)" in env.goal
    assert env.instruction == "The mug to the coffee table, the apple to the sofa."
    assert env.news == ["The task has changed. The new task: The mug to the coffee table, the apple to the sofa."]
    assert env.task.instruction == demo.instruction, "the task as given"


def test_an_env_with_events_refuses_what_cannot_carry_them_out(demo: coherent.Task, tmp_path: Path) -> None:
    """Neither physics nor robots over ROS 2 carry a robot joining in a room of the
    event's; the task's own events run too."""
    with pytest.raises(coherent.TaskFormatError, match="robots over ROS 2 are not carried anywhere") as raised:
        coherent.Env(demo, robots="ros2", events=KINDS["robot_up"], server_wait=0.1)
    assert raised.value.json_path == "$[0].room"
    with pytest.raises(coherent.TaskFormatError, match="physics does not carry a robot anywhere") as raised:
        coherent.Env(demo, physics=True, events=KINDS["robot_up"])
    assert raised.value.json_path == "$[0].room"
    data = json.loads(DEMO.read_text())
    data["events"] = MOVED
    path = tmp_path / "demo-moved.json"
    path.write_text(json.dumps(data))
    (task,) = coherent.load_tasks(path)
    env = coherent.Env(task)
    env.step([])
    env.step([])
    assert env.news == [TOLD]


def test_physics_carries_the_events_out(demo: coherent.Task, tmp_path: Path) -> None:
    """The demo's events in Rapier: the optimal episode's actions carried out step by step,
    physics agreeing with the rules after each event."""
    events = KINDS["demo"]
    episode = coherent.run(demo, "optimal", events=events, seed=3, out=tmp_path)
    env = coherent.Env(demo, physics=True, events=events, seed=3)
    _play_in_env(env, episode, False)
    assert env.goal_satisfied()


def test_the_results_frame_spreads_the_reference(events_results: Path, demo: coherent.Task, tmp_path: Path) -> None:
    frame = coherent.results(events_results)
    lines = coherent._coherent.read_results(events_results)
    assert len(frame) == len(lines) == 108
    for (_, row), line in zip(frame.iterrows(), lines):
        reference = line["reference"]
        recoveries = reference["recoveries"]
        assert row["reference"] == reference
        assert row["event_kinds"] == "+".join(reference["kinds"])
        assert _na_or(row["reference_steps"]) == reference.get("steps")
        steps = reference.get("steps")
        assert _na_or(row["over_reference"]) == (None if steps is None else line["steps"] - steps)
        assert _na_or(row["unreachable"]) == reference.get("unreachable")
        assert row["recoveries"] == len(recoveries)
        assert row["recovered"] == sum(r.get("rounds") is not None for r in recoveries)
        assert row["recovery_rounds"] == sum(r.get("rounds") or 0 for r in recoveries)
        assert row["recovery_wasted"] == sum(r["wasted"] for r in recoveries)
        assert row["recovery_calls"] == sum(r["calls"] for r in recoveries)
    assert set(frame["event_kinds"]) == {"robot_down", "robot_up", "object_moved", "goal_changed", "blocked", "action_fails"}
    assert all(str(frame[c].dtype) == "Int64" for c in analysis._REFERENCE_INTS)
    # Every sequential robot_down episode conceded a goal out of reach for good.
    down = frame[(frame["event_kinds"] == "robot_down") & (frame["execution"] == "sequential")]
    assert (down["status"] == "conceded").all() and down["unreachable"].notna().all()
    assert down["reference_steps"].isna().all()
    # A file without events: the frame it was before events existed, not one column more.
    plain = tmp_path / "plain.jsonl"
    coherent.bench([demo], ["optimal"], out=plain)
    (line,) = coherent._coherent.read_results(plain)
    spread = [f"backend_{n}" for n in analysis._BACKEND_FIELDS] + [f"settings_{n}" for n in analysis._SETTINGS_FIELDS]
    expected = [k for k in line if k not in ("backend", "settings")] + spread
    assert list(coherent.results(plain).columns) == expected
    # Lines with and without: NA where there is none.
    both = tmp_path / "both.jsonl"
    both.write_text(plain.read_text() + events_results.read_text())
    mixed = coherent.results(both)
    assert mixed.loc[0, list(analysis._REFERENCE_COLUMNS)].isna().all() and pd.isna(mixed.loc[0, "reference"])
    columns = list(analysis._REFERENCE_COLUMNS)
    pd.testing.assert_frame_equal(mixed[columns].iloc[1:].reset_index(drop=True), frame[columns])
    # A frame with them reports as its file does (the columns are read from `reference`).
    assert coherent.report(frame).markdown() == coherent.report(events_results).markdown()


def _na_or(value: Any) -> Any:
    return None if pd.isna(value) else value


def _markdown_row(key: tuple[str, str, str], row: dict[str, Any]) -> str:
    """A row of the Rust report's events table in Markdown (`harness/dynamic.rs`)."""
    method, execution, kind = key

    def opt(x: float) -> str:
        return "-" if pd.isna(x) else f"{x:.2f}"

    name = method if execution == "sequential" else f"{method} (parallel)"
    cells = [
        name, kind, str(row["episodes"]), f"{row['sr']:.3f}", str(row["conceded"]), opt(row["over_reference"]),
        f"{row['recovered']}/{row['recoveries']}", opt(row["recovery_rounds"]), opt(row["wasted"]), opt(row["recovery_calls"]),
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |"


def test_the_events_table_is_the_reports(events_results: Path, coherent_exe: str) -> None:
    """Worked out in pandas, the table is the one the Rust report computes (its frame
    and its text), row for row and number for number."""
    table = analysis.events_table(events_results)
    report = coherent.report(events_results)
    pd.testing.assert_frame_equal(table, report.events, check_exact=True)
    methods = ["pefa", "cmrs", "optimal"]
    kinds = sorted({"robot_down", "robot_up", "object_moved", "goal_changed", "blocked", "action_fails"})
    assert list(table.index) == [(m, e, k) for m in methods for e in ("sequential", "parallel") for k in kinds]
    assert list(table.columns) == list(analysis._EVENT_COLUMNS)
    assert (table["episodes"] == 3).all()
    # A lock is two changes, the lock and the door opening again.
    assert (table.xs("blocked", level="kind")["recoveries"] == 6).all()
    assert table.loc[("optimal", "sequential", "robot_down"), "conceded"] == 3
    assert table.xs("sequential", level="execution").loc["optimal", "over_reference"].dropna().eq(0).all()
    assert table["recovery_rounds"].notna().any() and table["over_reference"].isna().any()
    cli = subprocess.run([coherent_exe, "bench", "--report", str(events_results)], capture_output=True, text=True, check=True)
    part = cli.stdout.split("### Events: success and recovery")[1]
    rows = [line for line in part.splitlines() if line.startswith("| ") and not line.startswith("| Method")]
    assert rows == [_markdown_row(key, row) for key, row in zip(table.index, table.to_dict("records"))]


def test_the_events_table_of_a_frame_filtered_grouped_or_of_several_runs(events_results: Path, tmp_path: Path) -> None:
    frame = coherent.results(events_results)
    whole = analysis.events_table(frame)
    by_seed = analysis.events_table(frame, by=["seed"])
    assert by_seed.index.names == ["method", "execution", "kind", "seed"]
    assert len(by_seed) == 3 * len(whole)
    counts = ["episodes", "conceded", "recovered", "recoveries"]
    pd.testing.assert_frame_equal(by_seed[counts].groupby(level=[0, 1, 2], sort=False).sum(), whole[counts])
    only = analysis.events_table(frame[frame["method"] == "cmrs"])
    pd.testing.assert_frame_equal(only, whole.loc[["cmrs"]])
    # Another run's lines in the same frame: the report refuses them, the table takes them.
    other = tmp_path / "other.jsonl"
    coherent.bench(events_results.parent / "variants", ["optimal"], out=other)
    both = pd.concat([frame, coherent.results(other)], ignore_index=True)
    with pytest.raises(coherent.ArgumentError, match="report one run at a time"):
        coherent.report(both)
    table = analysis.events_table(both, by=["settings_backend"])
    assert table.loc[("optimal", "sequential", "object_moved", "builtin"), "episodes"] == 1
    pd.testing.assert_frame_equal(table.xs("simulated", level="settings_backend"), whole)
    # Results without events have an empty table, with its columns.
    empty = analysis.events_table(coherent.results(other).drop(columns=["reference", *analysis._REFERENCE_COLUMNS]))
    assert empty.empty and list(empty.columns) == list(analysis._EVENT_COLUMNS)
    assert list(empty.index.names) == ["method", "execution", "kind"]
