"""Prompt files at run time and cost, from Python: ``prompts=`` (a folder or a dict) and
the ``PromptError`` of a bad template, ``prices=`` and ``cost_usd`` (episodes, the
results DataFrame, the report's cost columns), and ``coherent.plot.pareto``. A stub
OpenAI-compatible server on loopback answers with fixed token counts, so that costs
are known exactly."""

from __future__ import annotations

import asyncio
import json
import math
import subprocess
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import pandas as pd
import pytest

import coherent
from coherent import plot

# What the stub answers every call with, in tokens.
PROMPT, CACHED, COMPLETION = 1000, 400, 50
PRICES = {"stub-model": {"input": 2.0, "cached_input": 0.5, "output": 8.0}}
PER_CALL = (600 * 2.0 + 400 * 0.5 + 50 * 8.0) / 1e6


class _Stub(BaseHTTPRequestHandler):
    """Chat completions: the first robot for the assigner, an empty goal for llm-pddl, the
    first action otherwise."""

    seen: list[dict[str, Any]]

    def do_POST(self) -> None:  # noqa: N802 (the standard library's name)
        request = json.loads(self.rfile.read(int(self.headers["content-length"])))
        self.seen.append(request)
        schema = request["response_format"]["json_schema"]
        props = schema["schema"]["properties"]
        if schema["name"] == "proposal":
            content = {"reasoning": "go", "robot": props["robot"]["enum"][0], "subtask": "the first thing"}
        elif schema["name"] == "goal":
            # llm-pddl's one question: a goal of no facts, read and refused as misread.
            content = {"goal": []}
        else:
            # A dialogue's speaker may have no action of its own yet: an empty list.
            actions = props["action"]["enum"]
            content = {"action": actions[0] if actions else "none", "subtask_complete": False, "note": ""}
        body = json.dumps(
            {
                "choices": [{"message": {"role": "assistant", "content": json.dumps(content)}, "finish_reason": "stop"}],
                "usage": {
                    "prompt_tokens": PROMPT,
                    "completion_tokens": COMPLETION,
                    "prompt_tokens_details": {"cached_tokens": CACHED},
                },
            }
        ).encode()
        self.send_response(200)
        self.send_header("content-type", "application/json")
        self.send_header("content-length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: Any) -> None:
        pass


@pytest.fixture()
def stub() -> Iterator[tuple[coherent.LLM, list[dict[str, Any]]]]:
    seen: list[dict[str, Any]] = []
    handler = type("Handler", (_Stub,), {"seen": seen})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    llm = coherent.LLM(base_url=f"http://127.0.0.1:{server.server_port}/v1", model="stub-model")
    yield llm, seen
    server.shutdown()
    server.server_close()


@pytest.fixture(autouse=True)
def close_figures() -> Iterator[None]:
    yield
    plt.close("all")


def _sent(requests: list[dict[str, Any]]) -> str:
    return json.dumps([r["messages"] for r in requests])


def test_a_dict_of_templates_reaches_the_model_and_the_header(
    task0: coherent.Task, stub: tuple[coherent.LLM, list[dict[str, Any]]], tmp_path: Path
) -> None:
    llm, seen = stub
    mine = "You assign subtasks (MARKER-PY-1). The team:\n{{team}}\nAnswer in JSON."
    episode = coherent.run(
        task0, llm=llm, max_steps=1, out=tmp_path, prompts={"assigner_system.txt": mine}, prices=PRICES
    )
    assert "MARKER-PY-1" in _sent(seen)
    assert "MARKER-PY-1" in episode.transcript[0]["calls"][0]["messages"][0]["content"]
    record = episode.header["prompts"]
    assert list(record["replaced"]) == ["assigner_system.txt"]
    assert len(record["hash"]) == 32
    # Priced: two calls at the table given.
    assert episode.cached_tokens == 2 * CACHED
    assert episode.cost_usd == pytest.approx(2 * PER_CALL, rel=1e-12)
    # The same file name from a folder: the same set, the same hash.
    folder = tmp_path / "prompts"
    folder.mkdir()
    (folder / "assigner_system.txt").write_text(mine)
    (folder / "README.md").write_text("not a template: ignored")
    again = coherent.run(task0, llm=llm, max_steps=1, out=tmp_path, prompts=folder)
    assert again.header["prompts"] == record
    assert again.cost_usd is None, "stub-model has no built-in price"
    # The replay renders the recorded set and prices the recorded tokens.
    replayed = coherent.replay(episode.path, out=tmp_path, prices=PRICES)
    assert [r["calls"] for r in replayed.transcript] == [r["calls"] for r in episode.transcript]
    assert replayed.cost_usd == pytest.approx(episode.cost_usd)
    assert coherent.load_episode(episode.path).cost_usd is None


def test_the_small_models_tokens_priced(model_episode: coherent.Episode, tmp_path: Path) -> None:
    # SmolLM2 behind llama.cpp's server: real token counts, at a price given for it.
    assert model_episode.cost_usd is None, "no built-in price for a local model"
    prices = {"smollm2-135m": {"input": 0.02, "cached_input": 0.01, "output": 0.04}}
    replayed = coherent.replay(model_episode.path, out=tmp_path, prices=prices)
    fresh = model_episode.prompt_tokens - model_episode.cached_tokens
    expected = (fresh * 0.02 + model_episode.cached_tokens * 0.01 + model_episode.completion_tokens * 0.04) / 1e6
    assert replayed.cost_usd == pytest.approx(expected, rel=1e-12)
    assert replayed.cost_usd > 0


def test_an_unknown_placeholder_raises_prompt_error_before_any_call(
    task0: coherent.Task, stub: tuple[coherent.LLM, list[dict[str, Any]]], tmp_path: Path
) -> None:
    llm, seen = stub
    bad = {"executor_user.txt": "Subtask: {{subtask}}\nActions:\n{{actions}} {{no_such_thing}}"}
    with pytest.raises(coherent.PromptError) as raised:
        coherent.run(task0, llm=llm, out=tmp_path, prompts=bad)
    e = raised.value
    assert isinstance(e, coherent.CoherentError) and isinstance(e, ValueError)
    assert (e.file, e.line, e.placeholder) == (str(Path("prompts") / "executor_user.txt"), 3, "no_such_thing")
    assert str(e).endswith(
        "executor_user.txt:3: unknown placeholder {{no_such_thing}}; the placeholders of this "
        "template: subtask, observation, scene, state, actions"
    )
    with pytest.raises(coherent.PromptError, match="no_such_thing"):
        coherent.bench([task0], ["pefa"], backend=llm, out=tmp_path / "r.jsonl", prompts=bad)
    assert not (tmp_path / "r.jsonl").exists()
    with pytest.raises(coherent.PromptError, match="not a template") as typo:
        coherent.run(task0, out=tmp_path, prompts={"asigner_user.txt": "x"})
    assert typo.value.line is None and typo.value.placeholder is None
    with pytest.raises(TypeError, match="prompts"):
        coherent.run(task0, out=tmp_path, prompts=42)  # type: ignore[arg-type]
    assert seen == [], "no model call was made"


class _AsksTheModel:
    """A method written in Python that asks the model once a step through ``coherent.LLM``
    (priced by the built-in table: its model is ``gpt-4o-mini``), then takes the first
    action of the first robot that has one."""

    llm: coherent.LLM

    def __init__(self, task: coherent.Task) -> None:
        pass

    def act(self, view: coherent.View) -> tuple[int, str]:
        schema = {"type": "object", "properties": {"action": {"type": "string", "enum": ["go"]}}}
        self.llm.chat("Which robot?", schema, max_tokens=10)
        return _first_action(view)


class _AsksNothing:
    """A method written in Python that takes the first action and asks no model."""

    def __init__(self, task: coherent.Task) -> None:
        pass

    def act(self, view: coherent.View) -> tuple[int, str]:
        return _first_action(view)


class _ReportsItsOwnCalls:
    """A method written in Python that reports calls of a client of its own, whose model
    no table prices."""

    def __init__(self, task: coherent.Task) -> None:
        pass

    def act(self, view: coherent.View) -> coherent.Decision:
        robot, action = _first_action(view)
        return coherent.Decision(robot, action, prompt_tokens=100, completion_tokens=10, calls=1)


def _first_action(view: coherent.View) -> tuple[int, str]:
    return next((r, a[0]) for r, a in view.actions.items() if a)


@pytest.mark.parametrize("method", [*coherent.METHODS, "asks-the-model", "asks-nothing", "reports-its-own-calls"])
def test_an_episode_costs_what_its_transcript_costs(
    task0: coherent.Task, stub: tuple[coherent.LLM, list[dict[str, Any]]], method: str, tmp_path: Path
) -> None:
    # One rule prices an episode as it runs and its transcript read back: the model it
    # used (the backend's, or the client a method written in Python called through) at
    # the built-in prices, and 0 for one that made no model call.
    llm = coherent.LLM(base_url=stub[0].base_url, model="gpt-4o-mini")
    python_methods = {"asks-the-model": _AsksTheModel, "asks-nothing": _AsksNothing, "reports-its-own-calls": _ReportsItsOwnCalls}
    if method in python_methods:
        cls = type(method.replace("-", "_"), (python_methods[method],), {"llm": llm, "name": method})
        episode = coherent.run(task0, cls, max_steps=2, out=tmp_path)
    else:
        episode = coherent.run(task0, method, llm=llm, max_steps=2, out=tmp_path)
    loaded = coherent.load_episode(episode.path)
    assert episode.cost_usd == loaded.cost_usd, method
    expected = {
        "asks-the-model": "priced",
        "asks-nothing": 0.0,
        "reports-its-own-calls": None,
        "mcts": 0.0,
        "optimal": 0.0,
        "random": 0.0,
    }.get(method, "priced")
    if expected == "priced":
        assert episode.cost_usd is not None and episode.cost_usd > 0, method
    else:
        assert episode.cost_usd == expected, method


def test_bench_prices_lines_and_the_report_has_cost_per_task_and_per_success(
    env0_tasks: list[coherent.Task], stub: tuple[coherent.LLM, list[dict[str, Any]]], tmp_path: Path
) -> None:
    llm, seen = stub
    tasks, _ = coherent.select(env0_tasks, [("env0", 0), ("env0", 2)])
    prices = tmp_path / "prices.toml"
    prices.write_text('["stub-model"]\ninput = 2.0\ncached_input = 0.5\noutput = 8.0\n')
    marker = "MARKER-BENCH: {{instruction}}\n{{robots}}\n{{observation}}\n{{history}}"
    frame = coherent.bench(
        tasks,
        ["pefa", "optimal"],
        backend=llm,
        out=tmp_path / "r.jsonl",
        prices=prices,
        prompts={"assigner_user.txt": marker},
    )
    assert "MARKER-BENCH" in _sent(seen)
    assert "cost_usd" in frame.columns and "cached_tokens" in frame.columns
    pefa = frame[frame["method"] == "pefa"]
    assert (pefa["llm_calls"] > 0).all()
    for cost, calls in zip(pefa["cost_usd"], pefa["llm_calls"]):
        assert cost == pytest.approx(calls * PER_CALL, rel=1e-12)
    assert (frame[frame["method"] == "optimal"]["cost_usd"] == 0.0).all()
    costs = coherent.report(frame).costs
    assert {"cost_usd", "cost_per_task", "cost_per_success"} <= set(costs.columns)
    total = float(pefa["cost_usd"].sum())
    successes = int(pefa["success"].sum())
    assert costs.loc["pefa", "cost_per_task"] == pytest.approx(total / len(pefa))
    if successes:
        assert costs.loc["pefa", "cost_per_success"] == pytest.approx(total / successes)
    else:
        assert math.isnan(costs.loc["pefa", "cost_per_success"])
    assert costs.loc["optimal", "cost_per_task"] == 0.0
    assert "Cost / task" in coherent.report(frame).markdown()
    # The same tokens without a price: NaN, and so are the report's cost columns.
    unpriced = coherent.bench(tasks[:1], ["pefa"], backend=llm, out=tmp_path / "u.jsonl")
    assert unpriced["cost_usd"].isna().all()
    assert math.isnan(coherent.report(unpriced).costs.loc["pefa", "cost_per_task"])
    with pytest.raises(coherent.CoherentError, match="outptu"):
        coherent.bench(tasks[:1], ["pefa"], out=tmp_path / "x.jsonl", prices={"m": {"input": 1, "outptu": 2}})


def _line(*, method: str, model: str, task_id: int, success: bool, cost: float | None) -> dict[str, Any]:
    """A results line written by hand: env0, mono, seed 0, 5 steps, 10 calls."""
    return {
        "method": method,
        "scene": "env0",
        "task_id": task_id,
        "task_type": "mono",
        "seed": 0,
        "success": success,
        "status": "success" if success else "failure",
        "steps": 5,
        "gt_steps": 5,
        "max_steps": 10,
        "llm_calls": 10,
        "prompt_tokens": 1000,
        "completion_tokens": 100,
        "cost_usd": cost,
        "wall_ms": 1.0,
        "backend": {"kind": "openai", "model": model, "base_url": None},
        "uses_model": method != "optimal",
        "transcript": "t.jsonl",
    }


def test_pareto_draws_a_point_per_method_and_model_and_the_front(tmp_path: Path) -> None:
    lines = [
        # pefa on a cheap model: SR 0.5 at 0.02 per task; on a dear one: SR 1.0 at 0.3.
        _line(method="pefa", model="cheap", task_id=0, success=True, cost=0.01),
        _line(method="pefa", model="cheap", task_id=1, success=False, cost=0.03),
        _line(method="pefa", model="dear", task_id=0, success=True, cost=0.2),
        _line(method="pefa", model="dear", task_id=1, success=True, cost=0.4),
        # cmrs on the dear model: SR 0.5 at 0.1, beaten by pefa on the cheap one.
        _line(method="cmrs", model="dear", task_id=0, success=True, cost=0.1),
        _line(method="cmrs", model="dear", task_id=1, success=False, cost=0.1),
        # The optimal plan asks no model: one point whatever the backend, at no cost.
        _line(method="optimal", model="dear", task_id=0, success=False, cost=0.0),
        _line(method="optimal", model="cheap", task_id=1, success=False, cost=0.0),
        # A model without a price is left out and named.
        _line(method="dmrs-1d", model="unpriced", task_id=0, success=True, cost=None),
    ]
    frame = pd.DataFrame(
        [
            {**{k: v for k, v in line.items() if k != "backend"}, **{f"backend_{k}": v for k, v in line["backend"].items()}}
            for line in lines
        ]
    )
    for data in (frame, lines):
        ax = plot.pareto(data)
        labels = sorted(t.get_text() for t in ax.texts if not t.get_text().startswith("no price"))
        assert labels == ["cmrs (dear)", "optimal", "pefa (cheap)", "pefa (dear)"]
        points = sorted((float(x), float(y)) for c in ax.collections for x, y in c.get_offsets())
        expected = [(0.0, 0.0), (0.02, 0.5), (0.1, 0.5), (0.3, 1.0)]
        assert len(points) == len(expected)
        for (x, y), (ex, ey) in zip(points, expected):
            assert (x, y) == (pytest.approx(ex), pytest.approx(ey))
        front = [line for line in ax.get_lines() if line.get_label() == "Pareto front"][0]
        assert list(front.get_xdata()) == pytest.approx([0.0, 0.02, 0.3])
        assert list(front.get_ydata()) == pytest.approx([0.0, 0.5, 1.0])
        assert any("dmrs-1d (unpriced)" in t.get_text() for t in ax.texts)
        assert ax.get_xlabel() == "cost per task (USD)" and ax.get_ylabel() == "success rate"
    path = tmp_path / "r.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    ax = plot.pareto(path)
    ax.figure.savefig(tmp_path / "pareto.png")
    assert (tmp_path / "pareto.png").stat().st_size > 5_000
    with pytest.raises(ValueError, match="prices="):
        plot.pareto([_line(method="pefa", model="unpriced", task_id=0, success=True, cost=None)])


def test_pareto_counts_a_conceded_episode_as_right_and_keeps_executions_apart() -> None:
    """An episode that conceded a goal put out of reach is right, as the report counts it;
    results of both executions are two points, each labelled with its execution."""
    lines = []
    for execution in ("sequential", "parallel"):
        conceded = {**_line(method="pefa", model="m", task_id=0, success=True, cost=0.1), "status": "conceded"}
        failed = _line(method="pefa", model="m", task_id=1, success=execution == "parallel", cost=0.1)
        lines += [{**line, "execution": execution} for line in (conceded, failed)]
    ax = plot.pareto(lines)
    labels = sorted(t.get_text() for t in ax.texts)
    assert labels == ["pefa (m, parallel)", "pefa (m, sequential)"]
    points = sorted((float(x), float(y)) for c in ax.collections for x, y in c.get_offsets())
    assert points == [(pytest.approx(0.1), 0.5), (pytest.approx(0.1), 1.0)]


ASKS_THE_STUB = (
    "import os\n"
    "import coherent\n\n"
    "class AsksTheStub:\n"
    "    name = 'asks-the-stub'\n"
    "    llm = coherent.LLM(base_url=os.environ['STUB_URL'], model='stub-model')\n"
    "    def __init__(self, task):\n"
    "        pass\n"
    "    def act(self, view):\n"
    "        schema = {'type': 'object', 'properties': {'action': {'type': 'string', 'enum': ['go']}}}\n"
    "        self.llm.chat('Which robot?', schema, max_tokens=10)\n"
    "        return next((r, a[0]) for r, a in view.actions.items() if a)\n"
)


def test_a_python_method_s_calls_cost_the_same_from_every_entry_point(
    task0: coherent.Task,
    env0_path: Path,
    stub: tuple[coherent.LLM, list[dict[str, Any]]],
    coherent_exe: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The price given: run(prices=), the command's run --prices, bench(prices=) agree.
    monkeypatch.setenv("STUB_URL", stub[0].base_url)
    (tmp_path / "asks.py").write_text(ASKS_THE_STUB)
    (tmp_path / "prices.json").write_text(json.dumps(PRICES))
    method = f"{tmp_path / 'asks.py'}:AsksTheStub"
    episode = coherent.run(task0, method, max_steps=2, out=tmp_path / "run", prices=PRICES)
    assert episode.llm_calls == 2
    assert episode.cost_usd == pytest.approx(2 * PER_CALL, rel=1e-12)
    cli = subprocess.run(
        [coherent_exe, "run", str(env0_path), "--task", str(task0.task_id), "--method", "asks.py:AsksTheStub",
         "--max-steps", "2", "--prices", "prices.json", "--out", "cli", "--json"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert cli.returncode == 1, cli.stderr  # the budget of 2 steps spent
    assert json.loads(cli.stdout)["cost_usd"] == pytest.approx(episode.cost_usd, rel=1e-12)
    # The summary line shows the cached tokens beside the cost, so that it adds up by hand.
    lines = subprocess.run(
        [coherent_exe, "run", str(env0_path), "--task", str(task0.task_id), "--method", "asks.py:AsksTheStub",
         "--max-steps", "2", "--prices", "prices.json", "--out", "cli"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert lines.returncode == 1, lines.stderr
    assert f"tokens {2 * PROMPT} prompt ({2 * CACHED} cached) + {2 * COMPLETION} completion | cost ${2 * PER_CALL:.6f}" in lines.stdout
    frame = coherent.bench([task0], [method], max_steps=2, out=tmp_path / "r.jsonl", prices=PRICES)
    assert list(frame["cost_usd"]) == [pytest.approx(episode.cost_usd, rel=1e-12)]


def test_finished_results_are_priced_anew_from_their_tokens(
    env0_tasks: list[coherent.Task], stub: tuple[coherent.LLM, list[dict[str, Any]]], coherent_exe: str, tmp_path: Path
) -> None:
    llm, _ = stub
    out = tmp_path / "r.jsonl"
    unpriced = coherent.bench(env0_tasks[:2], ["pefa"], backend=llm, max_steps=2, out=out)
    assert unpriced["cost_usd"].isna().all()
    expected = [pytest.approx(calls * PER_CALL, rel=1e-12) for calls in unpriced["llm_calls"]]
    # results(prices=), report(prices=), and bench(prices=) resuming: the finished lines too.
    assert list(coherent.results(out, prices=PRICES)["cost_usd"]) == expected
    report = coherent.report(out, prices=PRICES)
    assert report.costs.loc["pefa", "cost_per_task"] == pytest.approx(float(unpriced["llm_calls"].mean()) * PER_CALL)
    resumed = coherent.bench(env0_tasks[:2], ["pefa"], backend=llm, max_steps=2, out=out, prices=PRICES)
    assert resumed.attrs["outcome"]["skipped"] == 2 and list(resumed["cost_usd"]) == expected
    assert coherent.results(out)["cost_usd"].isna().all(), "the file keeps what it recorded"
    # The command's report re-prices the same way.
    (tmp_path / "prices.json").write_text(json.dumps(PRICES))
    cli = subprocess.run(
        [coherent_exe, "bench", "--report", str(out), "--prices", str(tmp_path / "prices.json"), "--format", "json"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert cli.returncode == 0, cli.stderr
    (pefa,) = [c for c in json.loads(cli.stdout)["costs"] if c["method"] == "pefa"]
    assert pefa["cost_per_task"] == pytest.approx(report.costs.loc["pefa", "cost_per_task"], rel=1e-12)


def test_achat_runs_outside_a_running_loop_too(stub: tuple[coherent.LLM, list[dict[str, Any]]]) -> None:
    # asyncio.run(llm.achat(...)): the call starts on the loop that awaits it.
    llm, seen = stub
    schema = {"type": "object", "properties": {"action": {"type": "string", "enum": ["go"]}}}
    reply = asyncio.run(llm.achat("Which action?", schema, max_tokens=10))
    assert json.loads(reply.text)["action"] == "go" and reply.prompt_tokens == PROMPT
    assert len(seen) == 1

    async def twice() -> list[coherent.Reply]:
        return await asyncio.gather(llm.achat("A?", schema), llm.achat("B?", schema))

    assert [json.loads(r.text)["action"] for r in asyncio.run(twice())] == ["go", "go"]
