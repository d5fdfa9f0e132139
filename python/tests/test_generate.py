"""coherent.generate (docs/generate.md, "From Python"): the same tasks as `coherent
generate` with the same knobs, the same folder byte for byte, each knob in Python's
types, and errors that name the knob as Python spells it."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

import coherent


def files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_the_same_folder_as_the_command_and_the_same_tasks_back(tmp_path: Path, coherent_exe: str) -> None:
    cli, py = tmp_path / "cli", tmp_path / "py"
    subprocess.run(
        [coherent_exe, "generate", "--out", str(cli), "--tasks", "4", "--seed", "5", "--robots", "2-3", "--jobs", "1"],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    made = coherent.generate(4, seed=5, robots="2-3", jobs=2, out=py)
    written = files(py)
    assert written == files(cli), "the folders differ"
    assert "coherent generate --tasks 4 --seed 5" in written["README.md"].decode()

    lines = [json.loads(line) for line in (py / "manifest.jsonl").read_text().splitlines()]
    assert [entry for _, entry in made] == lines
    for task, entry in made:
        (from_file,) = coherent.load_tasks(py / entry["file"])
        assert task.to_json() == from_file.to_json()
        assert task.gt == entry["optimal_steps"] == coherent.plan(task)["optimal_steps"]
        assert 2 <= entry["team_size"] <= 3

    # Without a folder: the same tasks, nothing written.
    again = coherent.generate(4, seed=5, robots="2-3")
    assert [e for _, e in again] == lines
    assert [t.to_json() for t, _ in again] == [t.to_json() for t, _ in made]


def test_knobs_in_pythons_types_are_the_commands_text() -> None:
    as_text = coherent.generate(
        2, seed=3, team="quadrotor=1,legged=1-2", type="dual", split="1,0,0", rooms="3", predicates=2, scenes=1
    )
    as_python = coherent.generate(
        2, seed=3, team={"quadrotor": 1, "legged": "1-2"}, type=["dual"], split=(1, 0, 0), rooms=3, predicates="2", scenes=1
    )
    assert [e for _, e in as_text] == [e for _, e in as_python]
    for _, entry in as_text:
        assert entry["type"] == "dual" and entry["predicates"] == 2 and entry["split"] == "train"
        assert entry["team"]["quadrotor"] == 1 and 1 <= entry["team"]["legged"] <= 2 and entry["team"]["arm"] == 0


@pytest.mark.parametrize(
    ("knobs", "named"),
    [
        ({"rooms": "1-40"}, "rooms: "),
        ({"team": "quadrotor=1", "type": "trio"}, "type: "),
        ({"team": "submarine=1"}, "team: "),
        ({"max_draws": 1, "steps": "40"}, "steps: "),
        ({"upstairs": 2.0}, "upstairs: "),
        ({"split": "0,0,0"}, "split: "),
        ({"tasks": 0}, "tasks: "),
        ({"tasks": -1}, "tasks="),
        ({"upstairs": float("nan")}, "upstairs="),
    ],
)
def test_a_knob_that_cannot_be_used_is_named(knobs: dict, named: str, tmp_path: Path) -> None:
    out = tmp_path / "set"
    with pytest.raises(coherent.ArgumentError) as e:
        coherent.generate(**{"tasks": 1, "jobs": 1, "out": out, **knobs})
    assert str(e.value).startswith(named), str(e.value)
    assert "--" not in str(e.value), "every knob in the message named as Python's argument"


def test_a_request_the_draws_cannot_meet_names_the_arguments_to_change(tmp_path: Path) -> None:
    with pytest.raises(coherent.ArgumentError) as e:
        coherent.generate(2, seed=0, steps="200", max_draws=8, jobs=1, out=tmp_path / "set")
    assert str(e.value).startswith("steps: after 8 draws (max_draws 8)"), str(e.value)


@pytest.mark.parametrize(
    ("knobs", "message"),
    [
        ({"rooms": [2, 3]}, "rooms: expected an int or a str, not list"),
        ({"team": 3}, "team: expected a str or a dict, not int"),
        ({"seed": "1"}, "seed: expected an int, not str"),
        ({"tasks": True}, "tasks: expected an int, not bool"),
        ({"type": {"mono"}}, "type: expected a str, a list or a tuple, not set"),
    ],
)
def test_a_knob_of_the_wrong_type_is_a_type_error_naming_it(knobs: dict, message: str) -> None:
    with pytest.raises(TypeError, match=f"^{message}$"):
        coherent.generate(**{"tasks": 1, **knobs})
