"""Methods written in Python: a class whose `act(view)` answers each step runs through
`coherent.run` and `coherent.bench` like a built-in method (its rows beside `optimal`'s
in the same DataFrame and report), each fault of a step is handled as documented, an
async `act` runs concurrently, the transcripts are complete and replay without the
class, and the `coherent` command loads such a method from a module or a `.py` file."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

import coherent
from conftest import DEMO, ENV_DIR, REPO, TASK0_PLAN


class FollowPlan:
    """Follows `coherent.plan(task)` step by step."""

    name = "follow-plan"

    def __init__(self, task: coherent.Task) -> None:
        self.plan = [(s["robot"], s["action"]) for s in coherent.plan(task)["plan"]]

    def act(self, view: coherent.View) -> tuple[int, str]:
        return self.plan[view.step - 1]


def read_transcript(path: str | Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


@pytest.fixture(scope="module")
def solvable() -> list[coherent.Task]:
    tasks, _ = coherent.read_tasks(ENV_DIR)
    chosen = [t for t in tasks if coherent.plan(t)["solvable"]]
    assert len(chosen) == 80
    return chosen


def test_a_method_that_follows_the_plan_is_a_method_like_optimal(
    solvable: list[coherent.Task], tmp_path: Path
) -> None:
    frame = coherent.bench(solvable, ["optimal", FollowPlan], concurrency=4, out=tmp_path / "r.jsonl")
    assert len(frame) == 160
    assert set(frame["method"]) == {"optimal", "follow-plan"}
    assert frame["success"].all()
    assert (frame["steps"] == frame["optimal_steps"]).all()
    ours = frame[frame["method"] == "follow-plan"]
    assert set(ours["status"]) == {"success"}
    assert set(ours["backend_kind"]) == {"none"} and not ours["uses_model"].any()
    report = coherent.report(frame)
    assert list(report.table1.index) == ["optimal", "follow-plan", "ground truth"]
    for column in ("mono", "dual", "trio", "Avg"):
        assert report.table1.loc["follow-plan", (column, "SR")] == 1.0
        assert report.table1.loc["follow-plan", (column, "AS")] == report.table1.loc["optimal", (column, "AS")]
    assert "| follow-plan | 1.000 /" in report.markdown()


class Scripted:
    """Answers from `script` (one entry per step: a decision, a tuple, or an exception
    to raise) and keeps what it was shown."""

    name = "scripted"
    script: list[Any] = []
    views: list[coherent.View] = []

    def __init__(self, task: coherent.Task) -> None:
        self.task = task
        self.steps = list(type(self).script)

    def act(self, view: coherent.View) -> Any:
        type(self).views.append(view)
        answer = self.steps.pop(0)
        if isinstance(answer, BaseException):
            raise answer
        return answer


def scripted(*script: Any) -> type[Scripted]:
    return type("Script", (Scripted,), {"script": list(script), "views": []})


def test_the_view(task0: coherent.Task, tmp_path: Path) -> None:
    method = scripted(TASK0_PLAN[0], TASK0_PLAN[1])
    episode = coherent.run(task0, method=method, max_steps=2, out=tmp_path)
    assert episode.method == "scripted" and episode.steps == 2
    first, second = method.views
    assert first.task is task0 and second.task is task0
    assert (first.step, second.step, first.max_steps) == (1, 2, 2)
    env = coherent.Env(task0)
    assert first.robots == env.robots and first.robot_types == task0.robot_types
    assert first.actions == {r: env.actions(r) for r in env.robots}
    assert first.observation(22) == env.observe(22)
    assert "<quadrotor>(22)" in first.observation_text(22)
    team = first.observation_text()
    assert all(f"({r})" in team for r in env.robots)
    with pytest.raises(ValueError, match="robot 999 is not in the team"):
        first.observation(999)
    assert first.history == []
    assert second.history == [(22, "[takeoff_from] <childroom floor>(3)", True, None)]
    env.step(*TASK0_PLAN[0])
    assert second.actions == {r: env.actions(r) for r in env.robots}
    assert "View(scene='env0', task_id=0, step=1" in repr(first)


def test_each_fault_is_a_step(task0: coherent.Task, tmp_path: Path) -> None:
    outside = (22, "[grab] <high kitchen table>(35)")
    method = scripted(
        outside,
        coherent.Decision(999, "[takeoff_from] <childroom floor>(3)", note="who?"),
        coherent.Decision(None, None, note="thinking", prompt_tokens=7, completion_tokens=3, calls=1),
        *TASK0_PLAN,
    )
    episode = coherent.run(task0, method=method, out=tmp_path)
    assert episode.success and episode.steps == 3 + len(TASK0_PLAN)
    assert (episode.llm_calls, episode.prompt_tokens, episode.completion_tokens) == (1, 7, 3)
    rounds = episode.transcript
    # An action outside the list is run as written: the feasibility check says why not.
    assert outside[1] not in method.views[0].actions[22]
    assert rounds[0]["outcome"]["kind"] == "infeasible" and rounds[0]["outcome"]["reason"] != "error"
    assert rounds[0]["external"] == {
        "robot": 22,
        "action": outside[1],
        "note": "",
        "prompt_tokens": 0,
        "completion_tokens": 0,
        "calls": 0,
    }
    # A robot that is not in the team is a failed step that says so.
    assert rounds[1]["outcome"]["reason"] == "unknown_robot"
    assert "999 is not a robot of task env0/0" in rounds[1]["outcome"]["message"]
    assert rounds[1]["external"]["note"] == "who?"
    # No robot: no action, and the step counts.
    assert rounds[2]["outcome"] == {"kind": "declined"}
    history = method.views[3].history
    assert [(r, ok) for r, _, ok, _ in history] == [(22, False), (999, False), (None, False)]
    assert history[0][3] == rounds[0]["outcome"]["message"]
    frame = episode.to_dataframe()
    assert list(frame["outcome"][:3]) == ["infeasible", "infeasible", "declined"]
    assert frame["robot"].iloc[0] == 22 and frame["prompt_tokens"].iloc[2] == 7
    # The recording replays without the class.
    replayed = coherent.replay(episode.path, out=tmp_path / "again")
    assert (replayed.success, replayed.steps, replayed.prompt_tokens) == (True, episode.steps, 7)


def test_an_exception_ends_that_episode_only(
    env0_tasks: list[coherent.Task], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    class Fails(FollowPlan):
        name = "fails"

        def act(self, view: coherent.View) -> tuple[int, str]:
            if view.task.task_id == 1 and view.step == 2:
                raise ValueError("boom at step 2")
            return super().act(view)

    tasks = env0_tasks[:3]
    frame = coherent.bench(tasks, ["optimal", Fails], out=tmp_path / "r.jsonl")
    assert len(frame) == 6
    failed = frame[frame["status"] == "error"]
    assert list(failed["task_id"]) == [1] and list(failed["method"]) == ["fails"]
    (line,) = failed.to_dict("records")
    assert line["steps"] == 2 and not line["success"]
    assert "Traceback (most recent call last)" in line["error"]
    assert line["error"].endswith("ValueError: boom at step 2")
    assert frame[frame["status"] != "error"]["success"].all()
    records = read_transcript(line["transcript"])
    assert [r["type"] for r in records] == ["header", "round", "round", "summary"]
    assert records[0]["external"] is True
    assert records[2]["outcome"]["kind"] == "method_error"
    assert records[2]["outcome"]["message"] == line["error"]
    assert records[3]["status"] == "error"
    report = coherent.report(frame)
    assert (report.unfinished, report.errors) == (1, 1)
    # The report lists it by method with the exception and where it was raised, and
    # gives no advice to run the same (failing) code again.
    (failure,) = report.failures
    assert failure["method"] == "fails" and failure["episodes"] == 1
    assert failure["first_error"].startswith("ValueError: boom at step 2 (test_methods.py, line ")
    assert failure["first_error"].endswith(", in act)") and failure["transcript"] == line["transcript"]
    markdown = report.markdown()
    assert "1 episode(s) failed with an error (the method's own," in markdown
    assert "Episodes that failed with an error" in markdown and "run the same command" not in markdown
    # The same call runs the error episode again, and only it; the progress says why it failed.
    again = coherent.bench(tasks, ["optimal", Fails], out=tmp_path / "r.jsonl", progress=True)
    told = capsys.readouterr().err
    assert "6 episodes: 5 already finished in the results file, 1 to run" in told
    assert "fails env0 task 1 seed 0: error: ValueError: boom at step 2 (test_methods.py, line " in told
    # The traceback of this run's episode: its own transcript, beside the first one's.
    assert f"; traceback in {Path(line['transcript']).parent}/env0-task1-fails-" in told
    assert again.attrs["outcome"]["skipped"] == 5 and again.attrs["outcome"]["written"] == 1
    # coherent.run raises, with the method's exception as the cause and the episode.
    with pytest.raises(coherent.MethodError, match="ValueError: boom at step 2") as info:
        coherent.run(tasks[1], method=Fails, out=tmp_path / "run")
    assert isinstance(info.value.__cause__, ValueError)
    assert info.value.episode.status == "error" and info.value.episode.steps == 2


def test_what_cannot_be_a_method(task0: coherent.Task, tmp_path: Path) -> None:
    class NoAct:
        def __init__(self, task: coherent.Task) -> None:
            pass

    with pytest.raises(coherent.MethodError, match="has no act"):
        coherent.run(task0, method=NoAct, out=tmp_path)

    class Bad:
        def __init__(self, task: coherent.Task) -> None:
            pass

        def act(self, view: coherent.View) -> Any:
            return "22: [takeoff_from] <childroom floor>(3)"

    with pytest.raises(coherent.MethodError, match="expected a coherent.Decision or a"):
        coherent.run(task0, method=Bad, out=tmp_path)

    class Raises:
        def __init__(self, task: coherent.Task) -> None:
            raise KeyError("no model")

    with pytest.raises(coherent.MethodError, match="KeyError: 'no model'") as info:
        coherent.run(task0, method=Raises, out=tmp_path)
    assert isinstance(info.value.__cause__, KeyError)
    with pytest.raises(ValueError, match="a built-in method's"):
        coherent.run(task0, method=type("Pefa", (FollowPlan,), {"name": "pefa"}), out=tmp_path)
    with pytest.raises(ValueError, match="use letters, digits"):
        coherent.run(task0, method=type("X", (FollowPlan,), {"name": "my method"}), out=tmp_path)
    with pytest.raises(TypeError, match="expected a method's name, or a class"):
        coherent.run(task0, method=42, out=tmp_path)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="a decision for a robot needs an action"):
        coherent.Decision(22, None)
    with pytest.raises(ValueError, match="two methods are named"):
        coherent.bench([task0], [FollowPlan, type("Other", (FollowPlan,), {})], out=tmp_path / "r.jsonl")
    # A function is a method too, named after it.
    def plan_follower(task: coherent.Task) -> FollowPlan:
        return FollowPlan(task)

    assert coherent.run(task0, method=plan_follower, out=tmp_path).method == "plan_follower"


class SlowAsync(FollowPlan):
    """Waits 0.2 s per step, in a coroutine, counting the coroutines at once."""

    name = "slow-async"
    lock = threading.Lock()
    running = 0
    most = 0

    async def act(self, view: coherent.View) -> coherent.Decision:  # type: ignore[override]
        cls = type(self)
        with cls.lock:
            cls.running += 1
            cls.most = max(cls.most, cls.running)
        await asyncio.sleep(0.2)
        with cls.lock:
            cls.running -= 1
        robot, action = self.plan[view.step - 1]
        return coherent.Decision(robot, action, note="after a nap")


def test_async_act_runs_concurrently(env0_tasks: list[coherent.Task], tmp_path: Path) -> None:
    tasks = env0_tasks[:4]
    steps = sum(coherent.plan(t)["optimal_steps"] for t in tasks)
    start = time.monotonic()
    frame = coherent.bench(tasks, ["pefa", SlowAsync], concurrency=4, out=tmp_path / "r.jsonl")
    elapsed = time.monotonic() - start
    assert frame["success"].all()
    assert SlowAsync.most >= 3, SlowAsync.most
    # One after another it would take steps x 0.2 s.
    assert elapsed < 0.6 * steps * 0.2, (elapsed, steps)
    for path in frame[frame["method"] == "slow-async"]["transcript"]:
        records = read_transcript(path)
        assert records[-1]["type"] == "summary" and records[-1]["status"] == "success"
        assert all(r["external"]["note"] == "after a nap" for r in records[1:-1])


def test_the_command_loads_a_method_from_a_file_or_a_module(
    coherent_exe: str, env0_path: Path, tmp_path: Path
) -> None:
    (tmp_path / "mine.py").write_text(
        "import coherent\n\n"
        "class Follow:\n"
        "    def __init__(self, task):\n"
        "        self.plan = [(s['robot'], s['action']) for s in coherent.plan(task)['plan']]\n"
        "    def act(self, view):\n"
        "        return self.plan[view.step - 1]\n"
    )
    run = subprocess.run(
        [coherent_exe, "run", str(env0_path), "--task", "0", "--method", "mine.py:Follow", "--out", "runs", "--json"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["steps"] == 5
    assert "Follow is a method written in Python" in run.stderr
    bench = subprocess.run(
        [coherent_exe, "bench", "--tasks", str(env0_path), "--subset", "paper40", "--methods", "optimal,mine:Follow",
         "--out", "r.jsonl"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert bench.returncode == 0, bench.stderr
    frame = coherent.results(tmp_path / "r.jsonl")
    assert sorted(set(frame["method"])) == ["Follow", "optimal"] and frame["success"].all()
    missing = subprocess.run(
        [coherent_exe, "run", str(DEMO), "--method", "no_such_module:X"], capture_output=True, text=True, cwd=tmp_path
    )
    assert missing.returncode == 2
    assert "no_such_module:X: ModuleNotFoundError: No module named 'no_such_module'" in missing.stderr
    # From Python, "MODULE:CLASS" is a method too.
    episode = coherent.run(
        coherent.load_tasks(env0_path)[0], method=str(tmp_path / "mine.py") + ":Follow", out=tmp_path / "py"
    )
    assert episode.success and episode.method == "Follow"


def test_the_greedy_example(env0_tasks: list[coherent.Task], tmp_path: Path) -> None:
    sys.path.insert(0, str(REPO / "examples" / "methods"))
    try:
        from greedy import Greedy
    finally:
        sys.path.pop(0)
    frame = coherent.bench(env0_tasks, ["optimal", Greedy], out=tmp_path / "r.jsonl")
    greedy = frame[frame["method"] == "greedy"]
    assert len(greedy) == 21 and set(greedy["status"]) <= {"success", "failure"}
    # It solves the tasks one robot does in a few steps (env0 tasks 1 and 3, say).
    assert set(greedy[greedy["success"]]["task_id"]) >= {1, 3}


KEY = "sk-methods-test-SECRET-5151"


@pytest.fixture(scope="module")
def small_llm(local_model: str) -> coherent.LLM:
    return coherent.LLM(base_url=f"{local_model}/v1", model="smollm2-135m", api_key=KEY)


def test_llm_chat_goes_through_the_rust_client(small_llm: coherent.LLM) -> None:
    reply = small_llm.chat([{"role": "user", "content": "Say hello."}], max_tokens=8)
    assert isinstance(reply, coherent.Reply) and str(reply) == reply.text
    assert reply.prompt_tokens > 0 and reply.completion_tokens > 0
    assert reply.latency_ms > 0 and reply.attempts == 1 and reply.format == "text"
    assert reply.finish in ("stop", "length") and reply.refusal is None
    schema = {
        "type": "object",
        "properties": {"answer": {"type": "string", "enum": ["yes", "no"]}},
        "required": ["answer"],
        "additionalProperties": False,
    }
    structured = small_llm.chat("Is the sky blue? Answer in JSON.", schema=schema, max_tokens=20)
    assert structured.format == "json_schema"
    assert json.loads(structured.text)["answer"] in ("yes", "no")

    async def both() -> list[coherent.Reply]:
        return await asyncio.gather(small_llm.achat("Say A.", max_tokens=4), small_llm.achat("Say B.", max_tokens=4))

    assert all(r.completion_tokens > 0 for r in asyncio.run(both()))
    unreachable = coherent.LLM(base_url="http://127.0.0.1:9/v1", model="m", api_key=KEY, max_retries=1)
    with pytest.raises(coherent.BackendError, match="connection failed.*after 2 attempts") as info:
        unreachable.chat("hi")
    assert KEY not in str(info.value)
    with pytest.raises(TypeError, match="messages"):
        small_llm.chat(42)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="role"):
        small_llm.chat("hi", role="critic")  # type: ignore[arg-type]


def test_the_central_example_with_a_real_model(
    small_llm: coherent.LLM, env0_tasks: list[coherent.Task], tmp_path: Path
) -> None:
    sys.path.insert(0, str(REPO / "examples" / "methods"))
    try:
        from central import CentralPlanner
    finally:
        sys.path.pop(0)

    class Small(CentralPlanner):
        llm = small_llm

    # env0 task 2: bread into the plate, milk box into the microwave (GT 5); two steps.
    task = env0_tasks[2]
    out = tmp_path / "r.jsonl"
    # A price for the model (USD per million tokens): the line's cost is its tokens at it.
    prices = {"smollm2-135m": {"input": 1.0, "cached_input": 0.5, "output": 2.0}}
    frame = coherent.bench([task], [Small], max_steps=2, out=out, prices=prices)
    (line,) = frame.to_dict("records")
    assert (line["method"], line["steps"], line["max_steps"]) == ("central", 2, 2)
    cached = line["cached_tokens"]  # the server's prompt cache: priced at cached_input
    fresh = line["prompt_tokens"] - cached
    expected = (fresh * 1.0 + cached * 0.5 + line["completion_tokens"] * 2.0) / 1e6
    assert line["cost_usd"] > 0 and line["cost_usd"] == pytest.approx(expected)
    assert line["status"] in ("success", "failure")
    assert line["llm_calls"] == 2 and line["prompt_tokens"] > 0 and line["completion_tokens"] > 0
    assert line["uses_model"] and line["backend_kind"] == "openai"
    assert line["backend_model"] == "smollm2-135m" and line["backend_base_url"] == small_llm.base_url
    records = read_transcript(line["transcript"])
    assert records[0]["external"] is True and records[0]["backend"]["kind"] == "none"
    for r in records[1:-1]:
        (call,) = r["calls"]
        assert call["client"] == {"kind": "openai", "model": "smollm2-135m", "base_url": small_llm.base_url}
        assert call["role"] == "assigner" and call["messages"][0]["role"] == "system"
        assert "Actions (robot: action)" in call["messages"][1]["content"]
        assert call["answer"]["latency_ms"] > 0 and call["answer"]["usage"]["prompt_tokens"] > 0
        assert r["external"]["note"]
    assert KEY not in out.read_text() + Path(line["transcript"]).read_text()
    # The recording replays with no model and no Python method behind it.
    replayed = coherent.bench(
        [task], [Small], backend="replay", replay_from=out, max_steps=2, out=tmp_path / "again.jsonl"
    )
    (again,) = replayed.to_dict("records")
    assert again["error"] is None, again["error"]
    assert (again["steps"], again["prompt_tokens"], again["backend_kind"]) == (2, line["prompt_tokens"], "replay")


def test_calls_of_an_async_method_are_filed_under_its_step(
    small_llm: coherent.LLM, task0: coherent.Task, tmp_path: Path
) -> None:
    class AskTwice:
        name = "ask-twice"

        def __init__(self, task: coherent.Task) -> None:
            pass

        async def act(self, view: coherent.View) -> coherent.Decision:
            first, second = await asyncio.gather(
                small_llm.achat("Say yes.", max_tokens=4),
                small_llm.achat("Say no.", max_tokens=4, role="executor", robot=view.robots[0]),
            )
            return coherent.Decision(None, None, note=first.text + " / " + second.text)

    episode = coherent.run(task0, method=AskTwice, max_steps=2, out=tmp_path)
    assert episode.steps == 2 and episode.llm_calls == 4 and episode.prompt_tokens > 0
    for r in episode.transcript:
        roles = sorted((c["role"], c["robot"]) for c in r["calls"])
        assert roles == [("assigner", None), ("executor", task0.robots[0])]
    # Outside a method's act, a call is nobody's step.
    small_llm.chat("Say nothing.", max_tokens=2)
    assert coherent.load_episode(episode.path).llm_calls == 4
