"""coherent.run, replay, load_episode, Episode and LLM: episodes from Python as
`coherent run` runs them, with a real language model for a few rounds."""

from __future__ import annotations

import json
import os
import signal
import socket
import sys
import threading
import time
from pathlib import Path

import pytest

import coherent
from conftest import DEMO, MODEL_KEY


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


def test_builtin_backend_solves_the_demo_optimally(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, out=tmp_path)
    assert episode.success and episode.status == "success"
    assert episode.steps == episode.gt_steps == 22
    assert episode.max_steps == 44
    assert (episode.llm_calls, episode.tokens, episode.prompt_tokens, episode.completion_tokens) == (44, 0, 0, 0)
    assert episode.error is None and episode.wall_ms > 0
    assert episode.method == "pefa"
    assert episode.backend["kind"] == "builtin"
    assert episode.path.parent == tmp_path and episode.path.suffix == ".jsonl"
    assert episode.task.to_native() == demo.to_native()
    assert episode.header["method"] == "pefa" and episode.header["history"] == 5
    assert episode.summary["steps"] == 22
    rounds = episode.transcript
    assert [r["step"] for r in rounds] == list(range(1, 23))
    assert all(r["outcome"]["kind"] == "executed" for r in rounds)
    assert rounds[-1]["done"]
    assert repr(episode) == (
        "Episode(scene='demo-apartment', task_id=0, method='pefa', status='success', steps=22, gt_steps=22, tokens=0)"
    )


def test_the_transcript_file_is_the_episode(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, "cmrs", out=tmp_path)
    lines = [json.loads(line) for line in episode.path.read_text().splitlines()]
    assert [line.pop("type") for line in lines] == ["header"] + ["round"] * episode.steps + ["summary"]
    assert lines[0] == episode.header
    assert lines[1:-1] == episode.transcript
    assert lines[-1] == episode.summary
    again = coherent.load_episode(episode.path)
    assert again.transcript == episode.transcript and again.summary == episode.summary


def test_dataframe_one_row_per_step(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, sim_errors="all=0.3", seed=4, out=tmp_path)
    frame = episode.to_dataframe()
    assert list(frame["step"]) == list(range(1, episode.steps + 1))
    assert set(frame["outcome"]) >= {"executed"}
    assert len(set(frame["outcome"])) > 1, "mistakes at 0.3 show up as failed steps"
    assert frame["llm_calls"].sum() == episode.llm_calls
    executed = frame[frame["outcome"] == "executed"]
    assert executed["robot"].notna().all() and executed["action"].notna().all()
    assert set(executed["robot_type"]) <= {"quadrotor", "robot dog", "robot arm"}
    failed = frame[frame["outcome"] == "infeasible"]
    assert failed["reason"].notna().all()
    assert frame["done"].iloc[-1] == episode.success


@pytest.mark.parametrize("method", coherent.METHODS)
def test_every_method_runs(demo: coherent.Task, tmp_path: Path, method: str) -> None:
    episode = coherent.run(demo, method, max_steps=3, out=tmp_path)
    assert episode.method == method
    assert episode.status == "failure" and episode.steps == 3
    uses_model = method not in ("mcts", "optimal", "random")
    assert (episode.backend["kind"] == "builtin") == uses_model


def test_simulated_mistakes_are_seeded(demo: coherent.Task, tmp_path: Path) -> None:
    runs = [coherent.run(demo, sim_errors={"hallucinate": 0.2, "malformed": 0.1}, seed=7, out=tmp_path) for _ in range(2)]
    answers = [[[c["answer"]["text"] for c in r["calls"]] for r in run.transcript] for run in runs]
    assert answers[0] == answers[1]
    assert [r["outcome"] for r in runs[0].transcript] == [r["outcome"] for r in runs[1].transcript]
    assert runs[0].backend["kind"] == "simulated"


def test_history_zero_and_physics(demo: coherent.Task, tmp_path: Path) -> None:
    episode = coherent.run(demo, history=0, physics=True, out=tmp_path)
    assert episode.success
    assert episode.header["history"] == 0 and episode.header["physics"] is True


def test_replay_reproduces_the_episode(demo: coherent.Task, tmp_path: Path) -> None:
    recorded = coherent.run(demo, "dmrs-1d", sim_errors="all=0.2", seed=2, out=tmp_path / "a")
    replayed = coherent.replay(recorded.path, out=tmp_path / "b")
    assert replayed.backend["kind"] == "replay"
    assert replayed.steps == recorded.steps and replayed.status == recorded.status
    strip = [{**r, "wall_ms": 0} for r in recorded.transcript]
    assert [{**r, "wall_ms": 0} for r in replayed.transcript] == strip


def test_replay_mismatch(demo: coherent.Task, tmp_path: Path) -> None:
    recorded = coherent.run(demo, out=tmp_path / "a")
    lines = recorded.path.read_text().splitlines()
    # The recorded fifth round claims a different outcome than the one the replay gets.
    fifth = json.loads(lines[5])
    fifth["feedback"] = "something else"
    lines[5] = json.dumps(fifth)
    edited = tmp_path / "edited.jsonl"
    edited.write_text("\n".join(lines) + "\n")
    with pytest.raises(coherent.ReplayMismatchError, match="round 5 differs") as info:
        coherent.replay(edited, out=tmp_path / "b")
    assert isinstance(info.value, coherent.CoherentError)
    assert isinstance(info.value.episode, coherent.Episode)


def test_load_episode_errors(tmp_path: Path, demo: coherent.Task) -> None:
    with pytest.raises(coherent.CoherentError, match="missing.jsonl"):
        coherent.load_episode(tmp_path / "missing.jsonl")
    unfinished = tmp_path / "unfinished.jsonl"
    lines = coherent.run(demo, out=tmp_path).path.read_text().splitlines()
    unfinished.write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(coherent.CoherentError, match="did not finish"):
        coherent.load_episode(unfinished)
    garbage = tmp_path / "garbage.jsonl"
    garbage.write_text("{not json\n")
    with pytest.raises(coherent.CoherentError, match="line 1"):
        coherent.load_episode(garbage)


def test_run_argument_errors(demo: coherent.Task, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match='unknown method "pefa2"; the methods: pefa, '):
        coherent.run(demo, "pefa2", out=tmp_path)
    with pytest.raises(ValueError, match="sim_errors: .*not an error kind"):
        coherent.run(demo, sim_errors="typos=0.1", out=tmp_path)
    with pytest.raises(ValueError, match="sim_errors: .*from 0 to 1"):
        coherent.run(demo, sim_errors={"all": 2.0}, out=tmp_path)
    with pytest.raises(TypeError, match="sim_errors"):
        coherent.run(demo, sim_errors=0.1, out=tmp_path)  # type: ignore[arg-type]
    llm = coherent.LLM(base_url="http://127.0.0.1:9/v1", model="m")
    with pytest.raises(ValueError, match="simulated"):
        coherent.run(demo, llm=llm, sim_errors="all=0.1", out=tmp_path)
    with pytest.raises(TypeError):
        coherent.run("demo.json", out=tmp_path)  # type: ignore[arg-type]


def test_llm_settings_and_secrecy(monkeypatch: pytest.MonkeyPatch) -> None:
    llm = coherent.LLM(base_url="http://127.0.0.1:8080/v1", model="m", api_key=MODEL_KEY, temperature=0.5, seed=3)
    assert (llm.base_url, llm.model, llm.temperature, llm.seed, llm.has_api_key) == (
        "http://127.0.0.1:8080/v1",
        "m",
        0.5,
        3,
        True,
    )
    assert MODEL_KEY not in repr(llm) and "[hidden]" in repr(llm)
    assert not hasattr(llm, "api_key")
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY", "COHERENT_MODEL"):
        monkeypatch.delenv(name, raising=False)
    with pytest.raises(coherent.BackendError, match="no endpoint") as info:
        coherent.LLM()
    assert info.value.episode is None
    monkeypatch.setenv("OPENAI_BASE_URL", "http://127.0.0.1:8081/v1")
    with pytest.raises(coherent.BackendError, match="no model"):
        coherent.LLM()
    monkeypatch.setenv("COHERENT_MODEL", "from-env")
    from_env = coherent.LLM()
    assert (from_env.base_url, from_env.model, from_env.has_api_key) == ("http://127.0.0.1:8081/v1", "from-env", False)
    with pytest.raises(coherent.BackendError, match="not a URL"):
        coherent.LLM(base_url="not a url", model="m")
    with pytest.raises(ValueError, match="format"):
        coherent.LLM(base_url="http://127.0.0.1:8080/v1", model="m", format="yaml")  # type: ignore[arg-type]


def test_llm_with_several_endpoints(monkeypatch: pytest.MonkeyPatch) -> None:
    urls = ["http://127.0.0.1:8080/v1", "http://127.0.0.1:8081/v1"]
    llm = coherent.LLM(base_url=urls, model="m")
    assert llm.base_urls == urls and llm.base_url == ",".join(urls)
    assert repr(llm).startswith(f"LLM(base_url={urls!r}, model='m'")
    assert coherent.LLM(base_url=",".join(urls), model="m").base_urls == urls
    monkeypatch.setenv("OPENAI_BASE_URL", " , ".join(urls))
    monkeypatch.setenv("COHERENT_MODEL", "m")
    assert coherent.LLM().base_urls == urls
    with pytest.raises(ValueError, match="empty list"):
        coherent.LLM(base_url=[], model="m")
    with pytest.raises(TypeError, match="base_url"):
        coherent.LLM(base_url=8080, model="m")  # type: ignore[arg-type]
    with pytest.raises(coherent.BackendError, match="not a URL"):
        coherent.LLM(base_url=[urls[0], "not a url"], model="m")


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_a_dead_server_is_a_backend_error(demo: coherent.Task, tmp_path: Path) -> None:
    llm = coherent.LLM(base_url=f"http://127.0.0.1:{_closed_port()}/v1", model="m", api_key=MODEL_KEY, max_retries=0)
    with pytest.raises(coherent.BackendError, match="connection") as info:
        coherent.run(demo, llm=llm, out=tmp_path)
    episode = info.value.episode
    assert isinstance(episode, coherent.Episode)
    assert episode.status == "backend_error" and episode.steps == 1
    assert MODEL_KEY not in episode.path.read_text()


def test_a_real_model_runs_from_python(local_model: str, model_episode: coherent.Episode) -> None:
    episode = model_episode
    assert episode.status == "failure" and episode.steps == 1
    assert episode.backend == {"kind": "openai", "model": "smollm2-135m", "base_url": f"{local_model}/v1"}
    assert episode.prompt_tokens > 0 and episode.completion_tokens > 0
    frame = episode.to_dataframe()
    assert frame["prompt_tokens"].sum() == episode.prompt_tokens
    assert frame["completion_tokens"].sum() == episode.completion_tokens
    assert episode.header["temperature"] == 0.0
    for path in episode.path.parent.iterdir():
        assert MODEL_KEY not in path.read_text(), f"{path} holds the API key"


def _interrupt_soon(delay: float) -> threading.Timer:
    timer = threading.Timer(delay, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to oneself is POSIX")
def test_run_is_interruptible(tmp_path: Path) -> None:
    # A server that accepts and never answers: the episode waits in its first model call.
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        llm = coherent.LLM(base_url=f"http://127.0.0.1:{server.getsockname()[1]}/v1", model="m", timeout=60, read_timeout=60)
        demo = coherent.load_tasks(DEMO)[0]
        previous = signal.signal(signal.SIGINT, signal.default_int_handler)
        timer = _interrupt_soon(0.5)
        start = time.monotonic()
        try:
            with pytest.raises(KeyboardInterrupt):
                coherent.run(demo, llm=llm, out=tmp_path)
        finally:
            timer.cancel()
            signal.signal(signal.SIGINT, previous)
        assert time.monotonic() - start < 5
    (transcript,) = tmp_path.iterdir()
    summary = json.loads(transcript.read_text().splitlines()[-1])
    assert summary["type"] == "summary" and summary["status"] == "interrupted"
