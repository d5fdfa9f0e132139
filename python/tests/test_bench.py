"""coherent.select, bench, results and report: the benchmark into DataFrames, resumable
as `coherent bench`, and the paper's tables from the same Rust code as the CLI's."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pandas as pd
import pytest

import coherent
from conftest import DEMO


@pytest.fixture(scope="module")
def few(env0_tasks: list[coherent.Task]) -> list[coherent.Task]:
    tasks, missing = coherent.select(env0_tasks, [("env0", 2), ("env0", 4), ("env0", 9)])
    assert missing == []
    return tasks


def test_select_paper40(env0_path: Path) -> None:
    tasks, _ = coherent.read_tasks(env0_path.parent)
    chosen, missing = coherent.select(tasks, "paper40")
    # The paper's subset has 8 tasks in each of env0..env4; the released files stop at env3.
    assert len(chosen) == 32
    assert [(t.scene, t.task_id) for t in chosen[:3]] == [("env0", 2), ("env0", 4), ("env0", 9)]
    assert missing == [("env4", i) for i in (0, 1, 7, 10, 12, 17, 18, 19)]
    everything, none_missing = coherent.select(tasks, "all")
    assert len(everything) == len(tasks) and none_missing == []


def test_select_from_a_file(env0_tasks: list[coherent.Task], tmp_path: Path) -> None:
    listed = tmp_path / "subset.txt"
    listed.write_text("# two of env0\nenv0 3\nenv0 1\nenv9 0\n")
    chosen, missing = coherent.select(env0_tasks, listed)
    assert [t.task_id for t in chosen] == [3, 1]
    assert missing == [("env9", 0)]
    listed.write_text("env0 three\n")
    with pytest.raises(coherent.CoherentError, match="line 1: task id"):
        coherent.select(env0_tasks, str(listed))
    with pytest.raises(TypeError, match="subset"):
        coherent.select(env0_tasks, 40)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="two tasks with scene"):
        coherent.select([env0_tasks[0], env0_tasks[0]], "all")


def test_bench_into_a_dataframe(few: list[coherent.Task], tmp_path: Path) -> None:
    out = tmp_path / "results.jsonl"
    frame = coherent.bench(few, ["pefa", "cmrs", "optimal"], out=out)
    assert isinstance(frame, pd.DataFrame)
    assert len(frame) == 9
    assert frame.attrs["outcome"] == {
        "total": 9,
        "skipped": 0,
        "written": 9,
        "finished": 9,
        "unfinished": 0,
        "method_errors": 0,
        "not_started": 0,
        "interrupted": False,
        "skipped_tasks": [],
        "repaired_bytes": 0,
        "orphaned": [],
        "out": str(out),
    }
    assert frame["success"].all()
    assert (frame["steps"] == frame["gt_steps"]).all()
    assert set(frame["backend_kind"]) == {"builtin"}
    assert set(frame["task_type"]) <= {"mono", "dual", "trio"}
    assert set(frame.columns) >= {"method", "scene", "task_id", "seed", "status", "llm_calls", "transcript"}
    for transcript in frame["transcript"]:
        assert coherent.load_episode(transcript).success
    # The file is the frame.
    assert coherent.results(out).equals(frame)


def test_bench_resumes(few: list[coherent.Task], tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    coherent.bench(few[:1], ["pefa"], out=out)
    frame = coherent.bench(few, ["pefa"], out=out)
    assert frame.attrs["outcome"]["skipped"] == 1 and frame.attrs["outcome"]["written"] == 2
    assert len(frame) == 3


def test_bench_from_a_path_skips_malformed_tasks(env0_path: Path, tmp_path: Path) -> None:
    tasks = json.loads(env0_path.read_text())[:2]
    broken = json.loads(json.dumps(tasks[1]))
    broken["task_id"] = 7
    broken["init_graph"]["edges"][0]["to_id"] = 424242
    path = tmp_path / "env0.json"
    path.write_text(json.dumps([*tasks, broken]))
    frame = coherent.bench(path, ["optimal"], out=tmp_path / "r.jsonl")
    assert sorted(frame["task_id"]) == [0, 1]
    (malformed,) = frame.attrs["malformed"]
    assert "424242" in malformed


def test_bench_simulated_seeds(few: list[coherent.Task], tmp_path: Path) -> None:
    frame = coherent.bench(few, ["pefa"], backend="simulated", sim_errors="all=0.2", seeds=2, out=tmp_path / "r.jsonl")
    assert sorted(frame["seed"].unique()) == [0, 1]
    assert set(frame["backend_kind"]) == {"simulated"}
    assert frame["episode_seed"].nunique() == 6


def test_bench_in_physics_runs_every_action_in_rapier_too(tmp_path: Path) -> None:
    demo = coherent.load_tasks(DEMO)[0]
    frame = coherent.bench([demo], ["optimal", "pefa"], physics=True, out=tmp_path / "r.jsonl")
    assert list(frame["success"]) == [True, True]
    assert list(frame["steps"]) == [22, 22]
    for path in frame["transcript"]:
        episode = coherent.load_episode(path)
        assert episode.header["physics"] is True
        assert episode.header["robots"] == {"kind": "local"}


def test_bench_refuses_unusable_methods_seeds_backends_and_task_lists(few: list[coherent.Task], tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    with pytest.raises(ValueError, match="unknown method"):
        coherent.bench(few, ["pefa", "nope"], out=out)
    with pytest.raises(ValueError, match="at least one method"):
        coherent.bench(few, [], out=out)
    with pytest.raises(ValueError, match="seeds"):
        coherent.bench(few, ["pefa"], seeds=0, out=out)
    with pytest.raises(ValueError, match="backend"):
        coherent.bench(few, ["pefa"], backend="openai", out=out)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match='sim_errors needs backend="simulated"'):
        coherent.bench(few, ["pefa"], sim_errors="all=0.1", out=out)
    with pytest.raises(ValueError, match="no tasks"):
        coherent.bench([], ["pefa"], out=out)
    with pytest.raises(coherent.TaskFormatError):
        coherent.bench(tmp_path / "missing.json", ["pefa"], out=out)
    assert not out.exists()


def test_results_names_a_missing_file_and_a_line_missing_a_field(tmp_path: Path) -> None:
    with pytest.raises(coherent.CoherentError, match="missing.jsonl"):
        coherent.results(tmp_path / "missing.jsonl")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"method": "pefa"}\n')
    with pytest.raises(coherent.CoherentError, match=r"line 1: .*\$\.scene: missing"):
        coherent.results(bad)


@pytest.fixture(scope="module")
def seeded(env0_tasks: list[coherent.Task], tmp_path_factory: pytest.TempPathFactory) -> Path:
    tasks, _ = coherent.select(env0_tasks, "paper40")
    out = tmp_path_factory.mktemp("seeded") / "results.jsonl"
    coherent.bench(tasks, ["pefa", "cmrs"], backend="simulated", sim_errors="all=0.1", seeds=3, out=out)
    return out


def test_report_tables_have_the_papers_rows_columns_and_task_counts(seeded: Path) -> None:
    report = coherent.report(seeded)
    t1 = report.table1
    assert list(t1.index) == ["pefa", "cmrs", "ground truth"]
    assert list(dict.fromkeys(t1.columns.get_level_values("column"))) == ["mono", "dual", "trio", "Avg"]
    assert list(dict.fromkeys(t1.columns.get_level_values("stat"))) == ["SR", "SR ci95", "AS", "AS ci95"]
    assert t1.attrs["tasks"]["Avg"] == 8
    assert sum(t1.attrs["tasks"][c] for c in ("mono", "dual", "trio")) == 8
    assert 0 <= t1.loc["pefa", ("Avg", "SR")] <= 1
    assert t1.loc["pefa", ("Avg", "SR ci95")] >= 0
    assert pd.isna(t1.loc["ground truth", ("Avg", "SR")])
    assert list(dict.fromkeys(report.table2.columns.get_level_values("column"))) == ["env0", "Avg"]
    assert report.seeds == [0, 1, 2]
    assert report.unfinished == 0 and report.untyped_tasks == 0
    assert report.backends == ["simulated: optimal-planner with errors hallucinate=0.1,wrong_robot=0.1,malformed=0.1,suboptimal=0.1"]
    assert list(report.costs.index) == ["pefa", "cmrs"]
    assert report.costs.loc["cmrs", "calls_per_step"] == 1.0


def test_report_agrees_with_the_cli(seeded: Path, coherent_exe: str) -> None:
    report = coherent.report(seeded)
    for fmt, text in (("markdown", report.markdown()), ("csv", report.csv())):
        cli = subprocess.run(
            [coherent_exe, "bench", "--report", str(seeded), "--format", fmt], capture_output=True, text=True, check=True
        )
        assert cli.stdout == text
    assert report._repr_markdown_() == report.markdown()
    # The numbers of the frames are the CLI's JSON report's.
    cli = subprocess.run(
        [coherent_exe, "bench", "--report", str(seeded), "--format", "json"], capture_output=True, text=True, check=True
    )
    table = json.loads(cli.stdout)["table1"]
    for row in table["rows"]:
        for column, cell in zip(table["columns"], row["cells"]):
            assert report.table1.loc[row["method"], (column, "SR")] == pytest.approx(cell["sr"]["mean"])
            assert report.table1.loc[row["method"], (column, "AS ci95")] == pytest.approx(cell["as"]["ci95"])


def test_report_from_a_frame_a_path_or_lines(seeded: Path) -> None:
    frame = coherent.results(seeded)
    by_path, by_frame = coherent.report(seeded), coherent.report(frame)
    by_lines = coherent.report(coherent._coherent.read_results(seeded))
    assert by_path.markdown() == by_frame.markdown() == by_lines.markdown()
    pd.testing.assert_frame_equal(by_path.table1, by_frame.table1)
    # A frame filtered by pandas reports on what is left.
    only_pefa = coherent.report(frame[frame["method"] == "pefa"])
    assert list(only_pefa.table1.index) == ["pefa", "ground truth"]


def test_report_rejects_bad_lines(seeded: Path) -> None:
    frame = coherent.results(seeded).drop(columns=["status"])
    with pytest.raises(ValueError, match="results line 0: missing field `status`"):
        coherent.report(frame)
    with pytest.raises(ValueError, match="format"):
        coherent._coherent.report_text([], "html")  # type: ignore[arg-type]


def test_report_of_nothing() -> None:
    report = coherent.report([])
    assert list(report.table1.index) == ["ground truth"]
    assert report.costs.empty


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to oneself is POSIX")
def test_bench_is_interruptible_and_resumes(env0_tasks: list[coherent.Task], tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    tasks, _ = coherent.select(env0_tasks, "paper40")
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.4, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            coherent.bench(tasks, ["pefa"], backend="simulated", sim_errors="all=0.3", seeds=20, concurrency=1, out=out)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    done = coherent.results(out)
    assert 0 < len(done) < 160
    # The same settings resume (a task of the run, its 20 seeds).
    frame = coherent.bench(tasks[:1], ["pefa"], backend="simulated", sim_errors="all=0.3", seeds=20, out=out)
    assert frame.attrs["outcome"]["written"] + frame.attrs["outcome"]["skipped"] == 20


def test_bench_replays_an_earlier_run(few: list[coherent.Task], tmp_path: Path) -> None:
    recorded = coherent.bench(
        few, ["pefa", "dmrs-2d"], backend="simulated", sim_errors="all=0.2", seeds=2, out=tmp_path / "a.jsonl"
    )
    replayed = coherent.bench(few, ["pefa", "dmrs-2d"], backend="replay", replay_from=tmp_path / "a.jsonl", seeds=2, out=tmp_path / "b.jsonl")
    assert set(replayed["backend_kind"]) == {"replay"}
    assert replayed["error"].isna().all()
    columns = ["method", "task_id", "seed", "episode_seed", "status", "steps", "llm_calls"]
    key = ["method", "task_id", "seed"]
    pd.testing.assert_frame_equal(
        recorded[columns].sort_values(key).reset_index(drop=True),
        replayed[columns].sort_values(key).reset_index(drop=True),
    )
    # An episode the earlier run does not have is skipped, and said so.
    more = coherent.bench(few, ["cmrs"], backend="replay", replay_from=tmp_path / "a.jsonl", out=tmp_path / "c.jsonl")
    assert len(more) == 0
    assert len(more.attrs["outcome"]["skipped_tasks"]) == 3
    assert "cmrs seed 0 has no finished episode" in more.attrs["outcome"]["skipped_tasks"][0]
    with pytest.raises(ValueError, match="replay_from="):
        coherent.bench(few, ["pefa"], backend="replay", out=tmp_path / "d.jsonl")
    with pytest.raises(ValueError, match='replay_from needs backend="replay"'):
        coherent.bench(few, ["pefa"], replay_from=tmp_path / "a.jsonl", out=tmp_path / "d.jsonl")
    with pytest.raises(coherent.CoherentError, match="missing.jsonl"):
        coherent.bench(few, ["pefa"], backend="replay", replay_from=tmp_path / "missing.jsonl", out=tmp_path / "d.jsonl")
