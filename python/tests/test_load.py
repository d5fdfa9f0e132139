"""load_tasks, Task, and the TaskFormatError raised for bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import coherent


def test_load_original_file_str_and_pathlike(env0_path: Path) -> None:
    by_path = coherent.load_tasks(env0_path)
    by_str = coherent.load_tasks(str(env0_path))
    assert len(by_path) == len(by_str) == 21
    assert [t.task_id for t in by_path] == list(range(21))
    assert all(isinstance(t, coherent.Task) for t in by_path)


def test_a_task_shows_the_files_scene_id_name_instruction_goal_and_robots(task0: coherent.Task) -> None:
    assert task0.scene == "env0"
    assert task0.task_id == 0
    assert task0.name == "MultiAgent_0"
    assert task0.instruction == "The <quadrotor>(22) lands on the <high kitchen table>(35)."
    assert task0.gt == 5
    assert task0.robots == [22, 23, 24, 50]
    assert task0.robot_types == {22: "quadrotor", 23: "robot dog", 24: "robot arm", 50: "robot arm"}
    assert task0.goal == ["on_<quadrotor>(22)_<high kitchen table>(35)"]


def test_task_is_read_only(task0: coherent.Task) -> None:
    with pytest.raises(AttributeError):
        task0.task_id = 3  # type: ignore[misc]


def test_a_tasks_repr_names_scene_id_and_robots(task0: coherent.Task) -> None:
    text = repr(task0)
    assert text.startswith("Task(scene='env0', task_id=0, name='MultiAgent_0'")
    assert "robots=[22, 23, 24, 50]" in text


def test_to_original_gives_back_the_file(env0_path: Path, task0: coherent.Task) -> None:
    original = json.loads(env0_path.read_text())[0]
    exported = task0.to_original()
    assert exported.keys() == original.keys()
    assert exported["task_goal"] == original["task_goal"]
    assert exported["init_graph"]["edges"] == original["init_graph"]["edges"]
    assert len(exported["init_graph"]["nodes"]) == len(original["init_graph"]["nodes"])


def test_to_native_round_trips(tmp_path: Path, task0: coherent.Task) -> None:
    native = task0.to_native()
    assert native["scene"] == "env0"
    assert native["task_id"] == 0
    assert native["goal"] == [{"relation": "ON", "subject": 22, "target": 35, "count": 1}]
    path = tmp_path / "task-000.json"
    path.write_text(json.dumps(native))
    (again,) = coherent.load_tasks(path)
    assert again.to_native() == native
    assert again.goal == task0.goal
    assert again.robot_types == task0.robot_types


def test_load_folder_recursively(tmp_path: Path, env0_path: Path, task1: coherent.Task) -> None:
    shutil.copy(env0_path, tmp_path / "env0.json")
    (tmp_path / "native").mkdir()
    (tmp_path / "native" / "task-001.json").write_text(json.dumps(task1.to_native()))
    (tmp_path / "notes.txt").write_text("not a task")
    tasks = coherent.load_tasks(tmp_path)
    assert len(tasks) == 22
    assert [(t.scene, t.task_id) for t in tasks].count(("env0", 1)) == 2


def test_bad_path_names_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "no-such-env.json"
    with pytest.raises(coherent.TaskFormatError, match="no-such-env.json") as info:
        coherent.load_tasks(missing)
    assert info.value.file == str(missing)
    assert info.value.json_path is None
    assert isinstance(info.value, coherent.CoherentError)
    assert isinstance(info.value, ValueError)


def test_a_folder_without_task_files_is_a_task_format_error(tmp_path: Path) -> None:
    with pytest.raises(coherent.TaskFormatError, match="no .json task files"):
        coherent.load_tasks(tmp_path)


def test_malformed_task_names_file_json_path_and_value(tmp_path: Path, env0_path: Path) -> None:
    tasks = json.loads(env0_path.read_text())[:2]
    tasks[0]["init_graph"]["edges"][0]["to_id"] = 424242
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(tasks))
    with pytest.raises(coherent.TaskFormatError) as info:
        coherent.load_tasks(path)
    message = str(info.value)
    assert str(path) in message
    assert "$[0].init_graph.edges[0].to_id" in message
    assert "424242" in message
    assert info.value.file == str(path)
    assert info.value.json_path == "$[0].init_graph.edges[0].to_id"


def test_wrong_type_names_json_path(tmp_path: Path, env0_path: Path) -> None:
    tasks = json.loads(env0_path.read_text())[:1]
    tasks[0]["init_graph"]["nodes"][2]["id"] = "seven"
    path = tmp_path / "typed.json"
    path.write_text(json.dumps(tasks))
    with pytest.raises(coherent.TaskFormatError, match=r"\$\[0\]\.init_graph\.nodes\[2\]\.id") as info:
        coherent.load_tasks(path)
    assert "seven" in str(info.value)


def test_cut_json_is_a_task_format_error_at_the_root_naming_the_line(tmp_path: Path) -> None:
    path = tmp_path / "cut.json"
    path.write_text('[{"task_id": 0,')
    with pytest.raises(coherent.TaskFormatError, match="invalid JSON at line 1") as info:
        coherent.load_tasks(path)
    assert info.value.json_path == "$"


def test_a_number_is_no_path() -> None:
    with pytest.raises(TypeError):
        coherent.load_tasks(42)  # type: ignore[arg-type]


def test_read_tasks_keeps_going_past_a_malformed_task(env0_path: Path) -> None:
    # The released folder: env3's task at index 18 uses node id 24 twice.
    tasks, errors = coherent.read_tasks(env0_path.parent)
    assert len(tasks) == 81
    assert len(errors) == 1
    (error,) = errors
    assert isinstance(error, coherent.TaskFormatError)
    assert error.file.endswith("env3.json")
    assert error.json_path == "$[18].init_graph.nodes[25].id"
    assert "duplicate node id 24" in str(error)
    with pytest.raises(coherent.TaskFormatError, match=r"\$\[18\]\.init_graph\.nodes\[25\]\.id"):
        coherent.load_tasks(env0_path.parent)


def test_read_tasks_raises_for_an_unreadable_path(tmp_path: Path) -> None:
    with pytest.raises(coherent.TaskFormatError, match="missing.json"):
        coherent.read_tasks(tmp_path / "missing.json")


def test_task_type_by_the_planner(env0_tasks: list[coherent.Task]) -> None:
    types = {t.task_id: t.type for t in env0_tasks}
    assert types[0] == coherent.plan(env0_tasks[0])["task_type"]
    assert set(types.values()) <= {"mono", "dual", "trio"}
    assert env0_tasks[2].type == "mono"


def test_to_json_is_the_native_file(tmp_path: Path, task0: coherent.Task) -> None:
    assert json.loads(task0.to_json()) == task0.to_native()
    pretty = task0.to_json(indent=True)
    assert pretty.startswith("{\n") and json.loads(pretty) == task0.to_native()
    path = tmp_path / "task.json"
    path.write_text(pretty)
    assert coherent.load_tasks(path)[0].to_json() == task0.to_json()
