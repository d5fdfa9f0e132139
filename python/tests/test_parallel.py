"""Robots acting at once, from Python: `coherent.run(..., execution="parallel")` and its
episode (makespan, actions, a row per robot's part), `coherent.bench` with both
executions and the report's makespan table, methods written in Python answering a decision per robot, the tree searches
refusing, and the real small model running a parallel PEFA episode whose executors are
asked at once."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

import coherent
from conftest import DEMO, ENV_DIR

# The demo's robots: the arm on the kitchen counter, the quadrotor, the dog.
ARM, QUADROTOR, DOG = 6, 11, 13


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def read_transcript(path: str | Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def test_a_parallel_episode_takes_joint_steps_and_says_so(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, execution="parallel", out=tmp_path)
    assert episode.execution == "parallel" and episode.success
    assert (episode.steps, episode.makespan, episode.actions) == (13, 13, 22)
    assert episode.max_steps == 26, "2 x the optimal makespan"
    assert episode.sim_seconds is None
    assert episode.header["execution"] == "parallel"
    first = episode.transcript[0]
    assert [p["robot"] for p in first["parts"]] == [ARM, QUADROTOR, DOG]
    frame = episode.to_dataframe()
    assert len(frame) == 22, "a row per robot's part"
    assert list(frame["step"].unique()) == list(range(1, 14))
    assert set(frame["outcome"]) == {"executed"}
    assert frame["llm_calls"].sum() == episode.llm_calls
    again = coherent.replay(episode.path, out=tmp_path / "again")
    assert again.steps == 13 and again.execution == "parallel"

    sequential = coherent.run(demo, out=tmp_path)
    assert (sequential.execution, sequential.makespan, sequential.actions) == ("sequential", 22, 22)
    assert "execution" not in sequential.header, "a sequential header is as before"


def test_the_tree_searches_and_unknown_executions_are_refused(demo: coherent.Task, tmp_path: Path) -> None:
    for method in ("mcts", "llm-mcts"):
        with pytest.raises(coherent.ArgumentError, match=f"{method} is sequential only"):
            coherent.run(demo, method, execution="parallel", out=tmp_path)
    with pytest.raises(coherent.ArgumentError, match="expected \"sequential\" or \"parallel\""):
        coherent.run(demo, execution="both", out=tmp_path)
    with pytest.raises(coherent.ArgumentError, match="sequential only"):
        coherent.bench([demo], ["mcts"], execution=["sequential", "parallel"], out=tmp_path / "r.jsonl")
    with pytest.raises(coherent.ArgumentError, match="execution=\\[\\]: an empty list"):
        coherent.bench([demo], ["pefa"], execution=[], out=tmp_path / "r.jsonl")


def test_bench_runs_both_executions_and_the_report_compares_them(demo: coherent.Task, tmp_path: Path) -> None:
    tasks, _ = coherent.read_tasks(ENV_DIR / "env0.json")
    chosen = [demo, *tasks[:4]]
    frame = coherent.bench(
        chosen,
        ["pefa", "cmrs", "optimal"],
        execution=["sequential", "parallel"],
        backend="simulated",
        sim_errors="all=0.1",
        seeds=2,
        out=tmp_path / "r.jsonl",
    )
    assert len(frame) == 5 * 3 * 2 * 2
    assert set(frame["execution"]) == {"sequential", "parallel"}
    parallel = frame[frame["execution"] == "parallel"]
    assert parallel["optimal_makespan"].notna().all()
    solved = parallel[parallel["success"]]
    assert (solved["makespan"] == solved["steps"]).all()
    assert (solved["makespan"] >= solved["optimal_makespan"]).all()
    optimal = parallel[parallel["method"] == "optimal"]
    assert (optimal["makespan"] == optimal["optimal_makespan"]).all()
    report = coherent.report(frame)
    assert "pefa (parallel)" in report.table1.index
    speed = report.makespan
    assert ("optimal", "parallel", "Avg") in speed.index
    row = speed.loc[("optimal", "parallel", "Avg")]
    assert row["sr"] == 1.0 and row["speedup"] >= 1.0
    assert row["makespan"] == pytest.approx(row["optimal_makespan"])
    assert "### Makespan" in report.markdown()
    assert "makespan,pefa (parallel),Avg," in report.csv()
    # Both executions are one run: its settings record them, and a run of other
    # executions does not resume the file.
    assert all(list(e) == ["sequential", "parallel"] for e in frame["settings_executions"])
    with pytest.raises(coherent.ArgumentError, match="execution: sequential,parallel in the file, parallel now"):
        coherent.bench(chosen, ["pefa"], execution="parallel", backend="simulated",
                       sim_errors="all=0.1", seeds=2, out=tmp_path / "r.jsonl")


class TwoAtATime:
    """Gives the two first robots with an action the first of their lists, together."""

    name = "two-at-a-time"

    seen: set[str] = set()

    def __init__(self, task: coherent.Task) -> None:
        self.task = task

    def act(self, view: coherent.View) -> list[coherent.Decision]:
        TwoAtATime.seen.add(view.execution)
        acting = [r for r in view.robots if view.actions[r]][:2]
        return [coherent.Decision(r, view.actions[r][0], note="first", calls=1, prompt_tokens=10) for r in acting]


class SameRobotTwice:
    name = "same-robot-twice"

    def __init__(self, task: coherent.Task) -> None:
        pass

    def act(self, view: coherent.View) -> list[tuple[int, str]]:
        actions = view.actions[DOG]
        return [(DOG, actions[0]), (DOG, actions[-1])]


def test_a_method_written_in_python_answers_a_decision_per_robot(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, TwoAtATime, execution="parallel", max_steps=3, out=tmp_path)
    assert TwoAtATime.seen == {"parallel"}
    rounds = episode.transcript
    assert len(rounds) == 3
    assert len(rounds[0]["parts"]) == 2
    assert all(p["external"]["note"] == "first" for r in rounds for p in r["parts"])
    assert episode.llm_calls == sum(len(r["parts"]) for r in rounds), "the calls each decision reports"
    assert episode.prompt_tokens == 10 * episode.llm_calls
    again = coherent.replay(episode.path, out=tmp_path / "again")
    assert [r["parts"] for r in again.transcript] == [r["parts"] for r in rounds]

    refused = coherent.run(demo, SameRobotTwice, execution="parallel", max_steps=1, out=tmp_path)
    part = refused.transcript[0]["parts"][0]
    assert part["outcome"]["reason"] == "interference"
    assert refused.actions == 0

    with pytest.raises(coherent.MethodError, match="a sequential episode takes one a step"):
        coherent.run(demo, TwoAtATime, max_steps=1, out=tmp_path)


def test_the_small_model_runs_parallel_pefa_with_its_executors_asked_at_once(
    local_model: str, tmp_path: Path
) -> None:
    # env1 task 16: four robots, so that several have subtasks at once.
    task = next(t for t in coherent.load_tasks(ENV_DIR / "env1.json") if t.task_id == 16)
    # The server answers one request at a time, so a round's executors wait in its queue
    # behind each other: on a loaded machine the last may wait minutes.
    llm = coherent.LLM(base_url=f"{local_model}/v1", model="smollm2-135m", read_timeout=900.0, timeout=900.0)
    # The paper's layout: with it this 135M model gives two robots subtasks within three
    # rounds (with ours its reasoning runs on until cut, and it names one).
    episode = coherent.run(task, llm=llm, execution="parallel", max_steps=3, prompts="paper-layout", out=tmp_path)
    assert episode.status in ("success", "failure")
    rounds = episode.transcript
    assert len(rounds) == 3
    busy = [r for r in rounds if sum(c["role"] == "executor" for c in r["calls"]) >= 2]
    assert busy, "some round asked two executors or more"
    for r in busy:
        executors = [c for c in r["calls"] if c["role"] == "executor"]
        assert {c["robot"] for c in executors} == {p["robot"] for p in r["parts"] if p["decision"] or p["outcome"]}
        # The server answers one request at a time: asked at once, the later answers
        # waited for the earlier ones, so their latencies add up to more than the round.
        latency = sum(c["answer"]["latency_ms"] for c in r["calls"] if c["answer"])
        assert latency > r["wall_ms"], (latency, r["wall_ms"])
    again = coherent.replay(episode.path, out=tmp_path / "again")
    assert again.steps == episode.steps
