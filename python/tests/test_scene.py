"""scene_layout, robot_paths and render_svg: the scene from above, as `coherent render`."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

import coherent
from conftest import DEMO


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def test_layout_of_a_generated_scene(task0: coherent.Task) -> None:
    layout = coherent.scene_layout(task0)
    assert set(layout) >= {"rooms", "doors", "items", "robots", "specs", "wall_height"}
    rooms = {n["id"] for n in task0.to_native()["graph"]["nodes"] if n["category"] == "Rooms"}
    assert {r["id"] for r in layout["rooms"]} == rooms
    assert {r["id"] for r in layout["robots"]} <= set(task0.robots)
    for room in layout["rooms"]:
        assert room["min"][0] < room["max"][0] and room["min"][1] < room["max"][1]


def test_robot_paths_of_the_plan_and_of_an_episode(demo: coherent.Task, tmp_path: Path) -> None:
    planned = coherent.robot_paths(demo)
    mobile = {r for r, kind in demo.robot_types.items() if kind != "robot arm"}
    assert set(planned) == mobile
    for track in planned.values():
        assert len(track) > 1 and all(len(p) == 3 for p in track)
    # (x, y, z) with y up: the quadrotor flies.
    flown = [y for r, track in planned.items() if demo.robot_types[r] == "quadrotor" for _, y, _ in track]
    assert max(flown) > 0.5
    episode = coherent.run(demo, out=tmp_path)
    # The built-in backend follows the optimal plan: the same actions, the same paths.
    assert coherent.robot_paths(episode) == planned


def test_render_svg_is_the_cli_picture(demo: coherent.Task, coherent_exe: str, tmp_path: Path) -> None:
    out = tmp_path / "demo.svg"
    subprocess.run([coherent_exe, "render", str(DEMO), "--plan", "--out", str(out)], check=True, capture_output=True)
    assert coherent.render_svg(demo) == out.read_text()
    bare = coherent.render_svg(demo, paths=False)
    assert bare.startswith("<svg") and len(bare) < len(out.read_text())
    episode = coherent.run(demo, out=tmp_path)
    subprocess.run(
        [coherent_exe, "render", "--transcript", str(episode.path), "--out", str(out)], check=True, capture_output=True
    )
    assert coherent.render_svg(episode) == out.read_text()


def test_scene_errors(task0: coherent.Task) -> None:
    with pytest.raises(TypeError, match="Task or an Episode"):
        coherent.robot_paths("demo.json")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="Task or an Episode"):
        coherent.render_svg(42)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        coherent.scene_layout(None)  # type: ignore[arg-type]
