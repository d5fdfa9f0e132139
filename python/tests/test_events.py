"""Events from Python (docs/dynamic.md): `coherent.run(events=...)` with a list or a file,
the episode against its reference, a method written in Python told what happened in its
view's `news`, bad events raised as `TaskFormatError` naming `events=`, the JSON path
and the value, before anything runs, and a real small model told of an event end to
end."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import coherent
from conftest import DEMO

MOVED = [{"step": 3, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]
TOLD = "Someone outside the team moved <apple>(9) onto <sofa>(14)."


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


def test_stepping_by_hand_refuses_a_task_with_events(tmp_path: Path) -> None:
    """`Env` (and Gymnasium and PettingZoo on it) would never make the events happen:
    a task with events is refused, not run without them."""
    data = json.loads(DEMO.read_text())
    data["events"] = MOVED
    path = tmp_path / "demo-moved.json"
    path.write_text(json.dumps(data))
    (task,) = coherent.load_tasks(path)
    with pytest.raises(coherent.ArgumentError, match="Env does not run events yet"):
        coherent.Env(task)
