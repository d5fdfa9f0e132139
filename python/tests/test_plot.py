"""coherent.plot: each figure draws what it says, from real results and episodes."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("matplotlib")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.container import BarContainer  # noqa: E402

import coherent  # noqa: E402
from coherent import analysis, plot  # noqa: E402
from conftest import DEMO, REPO  # noqa: E402


@pytest.fixture(scope="module")
def results(env0_tasks: list[coherent.Task], tmp_path_factory: pytest.TempPathFactory) -> coherent.Report:
    tasks, _ = coherent.select(env0_tasks, "paper40")
    out = tmp_path_factory.mktemp("plot") / "r.jsonl"
    frame = coherent.bench(tasks, ["pefa", "cmrs", "mcts"], backend="simulated", sim_errors="all=0.1", seeds=2, out=out)
    return coherent.report(frame)


@pytest.fixture(scope="module")
def episode(tmp_path_factory: pytest.TempPathFactory) -> coherent.Episode:
    demo = coherent.load_tasks(DEMO)[0]
    return coherent.run(demo, sim_errors="all=0.2", seed=1, out=tmp_path_factory.mktemp("runs"))


@pytest.fixture(autouse=True)
def close_figures() -> None:
    yield
    plt.close("all")


@pytest.mark.parametrize(("by", "columns"), [("type", ["Mono", "Dual", "Trio", "Average"]), ("scene", ["env0", "Average"])])
def test_table_draws_a_bar_with_error_bars_per_method_and_column(results: coherent.Report, tmp_path: Path, by: str, columns: list[str]) -> None:
    fig = plot.table(results, by=by)  # type: ignore[arg-type]
    sr, avg = fig.axes
    assert [t.get_text().split("\n")[0] for t in sr.get_xticklabels()] == columns
    assert sr.get_ylabel() == "success rate (SR)" and avg.get_ylabel() == "average steps (AS)"
    # One bar per method and column; error bars with two seeds.
    assert len(sr.patches) == 3 * len(columns)
    bars = [c for c in sr.containers if isinstance(c, BarContainer)]
    assert len(bars) == 3 and all(b.errorbar is not None for b in bars)
    assert ("Table I" if by == "type" else "Table II") in fig.texts[0].get_text()
    assert "2 seeds" in fig.texts[0].get_text()
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names == ["ground truth", "pefa", "cmrs", "mcts"]
    fig.savefig(tmp_path / "table.png")
    assert (tmp_path / "table.png").stat().st_size > 10_000


def test_table_from_a_frame_and_its_errors(results: coherent.Report) -> None:
    frame = coherent.results(results.lines[0]["transcript"].split(".transcripts")[0] + ".jsonl")
    fig = plot.table(frame, by="scene", title="mine")
    assert fig.texts[0].get_text().startswith("mine")
    with pytest.raises(ValueError, match="by="):
        plot.table(results, by="robot")  # type: ignore[arg-type]


def test_timeline_marks_each_step_and_failed_ones_and_the_success(episode: coherent.Episode) -> None:
    ax = plot.timeline(episode)
    frame = episode.to_dataframe()
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels[:3] == ["robot arm (6)", "quadrotor (11)", "robot dog (13)"]
    markers = [line for line in ax.get_lines() if line.get_marker() in ("o", "x", "*")]
    assert len(markers) == len(frame)
    failed = [line for line in markers if line.get_marker() == "x"]
    assert len(failed) == (frame["outcome"] != "executed").sum() > 0
    assert [line.get_marker() for line in markers].count("*") == int(episode.success)
    assert f"demo-apartment task 0, pefa: {episode.status} in {episode.steps} steps (GT 22)" == ax.get_title()


def test_timeline_marks_each_event_before_its_step(episode: coherent.Episode, tmp_path: Path) -> None:
    demo = coherent.load_tasks(DEMO)[0]
    events = coherent.run(demo, events=REPO / "examples" / "events" / "demo.json", out=tmp_path)
    ax = plot.timeline(events)
    at = {r["step"]: [h["kind"] + (" ends" if h.get("ended") else "") for h in r["events"]] for r in events.transcript if r.get("events")}
    assert sorted(at.values()) == [["blocked"], ["blocked ends"], ["robot_down"]]
    marks = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("event")]
    assert sorted(line.get_xdata()[0] for line in marks) == sorted(step - 0.5 for step in at)
    assert {", ".join(names) for names in at.values()} <= {t.get_text() for t in ax.texts}
    assert "event" in [t.get_text() for t in ax.get_legend().get_texts()]
    # Without events, none.
    ax = plot.timeline(episode)
    assert not [line for line in ax.get_lines() if line.get_gid()] and not ax.texts
    assert "event" not in [t.get_text() for t in ax.get_legend().get_texts()]


def test_recovery_draws_a_bar_per_method_and_kind_in_a_panel_per_column(events_results: Path, tmp_path: Path) -> None:
    fig = plot.recovery(events_results)
    table = analysis.events_table(events_results)
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_ylabel() for ax in axes] == ["success rate", "steps over the reference", "rounds", "wasted actions"]
    kinds = sorted(set(table.index.get_level_values("kind")))
    for ax, column in zip(axes, ["sr", "over_reference", "recovery_rounds", "wasted"]):
        assert [t.get_text().split("\n")[0] for t in ax.get_xticklabels()] == kinds
        # A bar per row with a number; none where there is nothing to average.
        assert sorted(p.get_height() for p in ax.patches) == pytest.approx(sorted(table[column].dropna()))
    assert [t.get_text() for t in axes[0].get_xticklabels()][0] == "action_fails\n(n=3)"
    names = [t.get_text() for t in fig.legends[0].get_texts()]
    assert names == ["pefa", "pefa (parallel)", "cmrs", "cmrs (parallel)", "optimal", "optimal (parallel)"]
    assert fig.get_suptitle().startswith("Events: success and recovery")
    fig.savefig(tmp_path / "recovery.png")
    assert (tmp_path / "recovery.png").stat().st_size > 10_000


def test_recovery_from_a_report_and_its_errors(events_results: Path, results: coherent.Report) -> None:
    fig = plot.recovery(coherent.report(events_results), stats=["recovery_calls"], title="mine")
    (ax,) = fig.axes
    assert ax.get_ylabel() == "model calls" and fig.get_suptitle().startswith("mine")
    with pytest.raises(ValueError, match="no results line with a reference"):
        plot.recovery(results)
    with pytest.raises(ValueError, match=r"stats=\['speed'\]: expected some of sr, over_reference"):
        plot.recovery(events_results, stats=["speed"])


def test_tokens_of_a_backend_without_tokens(episode: coherent.Episode) -> None:
    ax = plot.tokens(episode)
    assert len(ax.patches) == 2 * episode.steps
    assert any("reports no tokens" in t.get_text() for t in ax.texts)
    assert f"{episode.llm_calls} calls" in ax.get_title()


def test_tokens_of_a_model(model_episode: coherent.Episode) -> None:
    ax = plot.tokens(model_episode)
    prompt, completion = ax.patches
    assert prompt.get_height() == model_episode.prompt_tokens > 0
    assert completion.get_height() == model_episode.completion_tokens > 0
    assert not ax.texts
    assert "smollm2-135m" in ax.get_title()


def test_scene_map_draws_each_robots_path_and_names_the_rooms(episode: coherent.Episode) -> None:
    (ax,) = plot.scene(episode)
    names = [t.get_text() for t in ax.get_legend().get_texts()]
    assert names[:3] == ["robot arm (6)", "quadrotor (11)", "robot dog (13)"]
    assert "path (hollow: where it ends)" in names
    tracks = coherent.robot_paths(episode)
    drawn = {line.get_gid() for line in ax.get_lines() if (line.get_gid() or "").startswith("path")}
    assert drawn == {f"path {robot}" for robot, track in tracks.items() if track}
    room_names = {t.get_text() for t in ax.texts}
    assert {"kitchen", "living room"} <= room_names
    assert "paths of the episode" in ax.get_title()


def test_scene_map_without_paths(env0_tasks: list[coherent.Task]) -> None:
    fig, ax = plt.subplots()
    assert plot.scene(env0_tasks[0], ax=ax, paths=False) == [ax]
    assert not [line for line in ax.get_lines() if line.get_gid()]
    with pytest.raises(ValueError, match=r"env0: ax must be one Axes per storey \(1\), not 2"):
        plot.scene(env0_tasks[0], ax=plt.subplots(1, 2)[1], paths=False)


def test_scene_map_of_two_storeys() -> None:
    # s5-house task 13: the robot dog walks down the stairs, then to the living room.
    task = next(t for t in coherent.benchmark.tasks(subset="40") if (t.scene, t.task_id) == ("s5-house", 13))
    ground, upstairs = plot.scene(task)
    assert (ground.get_title(), upstairs.get_title()) == ("level 0.00 m", "level 3.00 m")
    fig = ground.figure
    assert fig.get_suptitle().startswith("s5-house task 13 - paths of the optimal plan")
    assert "robot dog (58)" in [t.get_text() for t in fig.legends[0].get_texts()]
    layout = coherent.scene_layout(task)
    names = {n["id"]: n["class_name"] for n in task.to_native()["graph"]["nodes"]}
    for ax, level in ((ground, 0.0), (upstairs, 3.0)):
        texts = {t.get_text() for t in ax.texts}
        assert {names[r["id"]] for r in layout["rooms"] if r["level"] == level} <= texts
    assert "stairs up to 3.00 m" in {t.get_text() for t in ground.texts}
    assert "stairs down to 0.00 m" in {t.get_text() for t in upstairs.texts}

    def drawn(ax: Axes, robot: int) -> list[tuple[float, float]]:
        return [(x, z) for line in ax.get_lines() if line.get_gid() == f"path {robot}" for x, z in line.get_xydata()]

    def in_room_of(level: float, x: float, z: float) -> bool:
        return any(
            r["level"] == level and r["min"][0] <= x <= r["max"][0] and r["min"][1] <= z <= r["max"][1]
            for r in layout["rooms"]
        )

    tracks = coherent.robot_paths(task)
    for robot, track in tracks.items():
        below, above = drawn(ground, robot), drawn(upstairs, robot)
        # Every point once, on the panel of its storey.
        assert sorted(below + above) == sorted((x, z) for x, _, z in track)
        assert all((x, z) in below for x, y, z in track if y < 0.5)
        assert all((x, z) in above for x, y, z in track if y > 2.95 and in_room_of(3.0, x, z))
    dog = next(r for r, kind in task.robot_types.items() if kind == "robot dog")
    assert drawn(ground, dog) and drawn(upstairs, dog)
    with pytest.raises(ValueError, match=r"s5-house: ax must be one Axes per storey \(2\), not 1"):
        plot.scene(task, ax=ground, paths=False)
