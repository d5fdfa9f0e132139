"""coherent.bench on a local Ray cluster of 2 CPUs: the same results lines as the local
executor (timings and transcript paths aside), a worker killed mid-run costing nothing
(every episode once, the same lines), an LLM's episodes on the endpoint of their node,
and the key never sent to the workers."""

from __future__ import annotations

import importlib.util
import json
import os
import secrets
import signal
import sys
import threading
import time
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import coherent

METHODS = ["pefa", "cmrs", "dmrs-2d"]
# What may differ between two runs of the same episodes: the time they took and where
# their transcripts went.
VARYING = ["wall_ms", "transcript"]
KEY = ["method", "scene", "task_id", "seed"]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A local Ray cluster of 2 CPUs with its files in the test's temporary folder (that
    folder is given) and its token in the environment (not under the home folder)."""
    if importlib.util.find_spec("ray") is None:
        pytest.fail("Ray is not installed: `make venv` installs it (the ray extra)")
    saved = {k: os.environ.get(k) for k in ("RAY_AUTH_MODE", "RAY_AUTH_TOKEN", "OPENAI_API_KEY")}
    os.environ["RAY_AUTH_MODE"] = "token"
    os.environ["RAY_AUTH_TOKEN"] = secrets.token_hex(16)
    # The workers inherit this environment: no key there.
    os.environ.pop("OPENAI_API_KEY", None)
    # Imported once the environment is set: Ray reads its settings on import.
    import ray

    files = tmp_path_factory.mktemp("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _temp_dir=str(files))
    try:
        yield files
    finally:
        ray.shutdown()
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@pytest.fixture(scope="module")
def paper40(env0_path: Path) -> list[coherent.Task]:
    tasks, _ = coherent.read_tasks(env0_path.parent)
    chosen, _ = coherent.select(tasks, "paper40")
    return chosen


def _bench(tasks: list[coherent.Task], out: Path, **kwargs: Any) -> pd.DataFrame:
    return coherent.bench(tasks, METHODS, backend="simulated", sim_errors="all=0.1", seeds=2, out=out, **kwargs)


@pytest.fixture(scope="module")
def local_run(paper40: list[coherent.Task], tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    """The uninterrupted run on the local executor."""
    return _bench(paper40, tmp_path_factory.mktemp("local") / "results.jsonl")


def _same_lines(a: pd.DataFrame, b: pd.DataFrame) -> None:
    def lines(frame: pd.DataFrame) -> pd.DataFrame:
        return frame.drop(columns=VARYING).sort_values(KEY).reset_index(drop=True)

    pd.testing.assert_frame_equal(lines(a), lines(b))


def test_ray_gives_the_local_lines(cluster: Path, paper40: list[coherent.Task], local_run: pd.DataFrame, tmp_path: Path) -> None:
    out = tmp_path / "results.jsonl"
    frame = _bench(paper40, out, executor="ray")
    assert len(frame) == len(local_run) == 32 * 2 * 3
    assert frame.attrs["outcome"]["written"] == 192 and frame.attrs["outcome"]["resubmitted"] == 0
    _same_lines(local_run, frame)
    # The workers wrote the transcripts where the local executor would.
    transcripts = tmp_path / "results.transcripts"
    assert all(Path(t).parent.parent == transcripts for t in frame["transcript"])
    assert all(coherent.load_episode(t).steps == s for t, s in zip(frame["transcript"], frame["steps"]))
    # The driver alone wrote the results file, which resumes as the local one does.
    again = _bench(paper40, out, executor="ray")
    assert again.attrs["outcome"]["skipped"] == 192 and again.attrs["outcome"]["written"] == 0
    assert coherent.report(again).markdown() == coherent.report(local_run).markdown()


def test_ray_runs_both_executions_as_the_local_executor_does(
    cluster: Path, paper40: list[coherent.Task], tmp_path: Path
) -> None:
    # An episode's key holds its execution: the workers run the one the driver names.
    both = {"execution": ["sequential", "parallel"]}
    local = _bench(paper40[:4], tmp_path / "local.jsonl", **both)
    on_ray = _bench(paper40[:4], tmp_path / "ray.jsonl", executor="ray", **both)
    assert len(on_ray) == 4 * 2 * 3 * 2
    assert on_ray.attrs["outcome"]["written"] == 48
    assert set(on_ray["execution"]) == {"sequential", "parallel"}
    order = [*KEY, "execution"]
    pd.testing.assert_frame_equal(
        local.drop(columns=VARYING).sort_values(order).reset_index(drop=True),
        on_ray.drop(columns=VARYING).sort_values(order).reset_index(drop=True),
    )
    again = _bench(paper40[:4], tmp_path / "ray.jsonl", executor="ray", **both)
    assert again.attrs["outcome"]["skipped"] == 48


def _descendants(pid: int) -> set[int]:
    """The processes below `pid` (this test's Ray cluster: its raylet and workers)."""
    parents: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            parents[int(entry)] = int(stat.rsplit(")", 1)[1].split()[1])
    below: set[int] = set()
    frontier = {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - below
        below |= frontier
    return below


def _runners() -> list[int]:
    """The processes of this test's episode-running actors."""
    found = []
    for pid in _descendants(os.getpid()):
        try:
            title = Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace")
        except OSError:
            continue
        if title.startswith("ray::EpisodeRunner"):
            found.append(pid)
    return found


@pytest.mark.skipif(sys.platform != "linux", reason="finds the worker through /proc")
def test_a_killed_worker_takes_no_results_with_it(
    cluster: Path, paper40: list[coherent.Task], local_run: pd.DataFrame, tmp_path: Path
) -> None:
    out = tmp_path / "results.jsonl"
    killed: list[tuple[int, int]] = []

    def kill_one_midway() -> None:
        # Once a tenth of the episodes are written, one worker dies (SIGKILL: no goodbye).
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            written = len(out.read_text().splitlines()) if out.exists() else 0
            runners = _runners()
            if written >= 20 and runners:
                os.kill(runners[0], signal.SIGKILL)
                killed.append((runners[0], written))
                return
            time.sleep(0.01)

    killer = threading.Thread(target=kill_one_midway)
    killer.start()
    frame = _bench(paper40, out, executor="ray")
    killer.join()
    assert killed, "a worker was killed"
    assert killed[0][1] < 192, "mid-run"
    outcome = frame.attrs["outcome"]
    # The episodes it was running ran again elsewhere; none of its finished ones did.
    assert outcome["resubmitted"] >= 1
    assert outcome["written"] == 192 and outcome["unfinished"] == 0
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    keys = [(line["method"], line["scene"], line["task_id"], line["seed"]) for line in lines]
    assert len(keys) == len(set(keys)) == 192, "every episode exactly once"
    _same_lines(local_run, frame)
    # What the killed episodes had written of their transcripts is set aside, as a
    # resumed run would.
    assert all(p.endswith(".jsonl.unfinished") for p in map(str, outcome["orphaned"]))


class _Stub(BaseHTTPRequestHandler):
    """An OpenAI-compatible server that answers every role with the first robot and its
    first action."""

    served = 0

    def do_POST(self) -> None:
        body = json.loads(self.rfile.read(int(self.headers["content-length"])))
        fmt = body["response_format"]["json_schema"]
        props = fmt["schema"]["properties"]
        if fmt["name"] == "proposal":
            content = {"reasoning": "go", "robot": props["robot"]["enum"][0], "subtask": "the first thing"}
        else:
            content = {"action": props["action"]["enum"][0], "subtask_complete": False, "note": ""}
        reply = json.dumps(
            {
                "choices": [{"message": {"role": "assistant", "content": json.dumps(content)}, "finish_reason": "stop"}],
                "usage": {"prompt_tokens": 10, "completion_tokens": 5},
            }
        ).encode()
        type(self).served += 1
        self.send_response(200)
        self.send_header("content-type", "application/json")
        self.send_header("content-length", str(len(reply)))
        self.end_headers()
        self.wfile.write(reply)

    def log_message(self, *args: Any) -> None:
        pass


@pytest.fixture()
def stub_url() -> Iterator[str]:
    server = ThreadingHTTPServer(("127.0.0.1", 0), _Stub)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/v1"
    finally:
        server.shutdown()
        server.server_close()


def test_episodes_use_the_endpoint_of_their_node(
    cluster: Path, paper40: list[coherent.Task], stub_url: str, tmp_path: Path
) -> None:
    # The LLM names a server nobody listens on; each node has its own (here the one
    # node, at this machine's address), and the episodes use that one.
    import ray

    llm = coherent.LLM(base_url="http://127.0.0.1:9/v1", model="stub")
    node = ray.util.get_node_ip_address()
    executor = coherent.RayExecutor(endpoint_per_node={node: stub_url})
    before = _Stub.served
    frame = coherent.bench(paper40[:2], ["pefa"], backend=llm, max_states=10_000, out=tmp_path / "r.jsonl", executor=executor)
    assert set(frame["status"]) <= {"success", "failure"}
    assert len(frame) == 2
    calls = [c for t in frame["transcript"] for r in coherent.load_episode(t).transcript for c in r["calls"]]
    assert calls and all(c["endpoint"] == stub_url for c in calls)
    assert _Stub.served - before == len(calls)
    # The results name the endpoint the episodes used: their node's.
    assert set(frame["backend_base_url"]) == {stub_url}
    with pytest.raises(ValueError, match="endpoint_per_node needs an LLM"):
        coherent.bench(paper40[:1], ["pefa"], out=tmp_path / "x.jsonl", executor=executor)


def test_the_key_is_not_sent_to_the_workers(cluster: Path, paper40: list[coherent.Task], tmp_path: Path) -> None:
    llm = coherent.LLM(base_url="http://127.0.0.1:9/v1", model="stub", api_key="sk-ray-test-SECRET-4242")
    with pytest.raises(coherent.CoherentError, match="never sent to Ray workers"):
        coherent.bench(paper40[:1], ["pefa"], backend=llm, out=tmp_path / "r.jsonl", executor="ray")
    # Nothing of the key in what the run left: the results file, Ray's logs.
    for path in [*tmp_path.rglob("*"), *cluster.rglob("*")]:
        if path.is_file():
            assert b"sk-ray-test-SECRET-4242" not in path.read_bytes(), path


def test_ray_is_an_optional_extra(paper40: list[coherent.Task], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(ImportError, match=r"pip install \"\.\[ray\]\""):
        coherent.bench(paper40[:1], ["pefa"], out=tmp_path / "r.jsonl", executor="ray")
    with pytest.raises(ValueError, match="executor"):
        coherent.bench(paper40[:1], ["pefa"], out=tmp_path / "r.jsonl", executor="dask")  # type: ignore[arg-type]
    assert not (tmp_path / "r.jsonl").exists()


def test_methods_written_in_python_prompts_and_prices_reach_the_workers(
    cluster: Path, paper40: list[coherent.Task], stub_url: str, tmp_path: Path
) -> None:
    # A class defined here has no module to import it from: Ray ships it by value.
    class FirstAction:
        name = "first-action"

        def __init__(self, task: coherent.Task) -> None:
            self.task = task

        def act(self, view: coherent.View) -> tuple[int, str]:
            robot = view.robots[0]
            return robot, view.actions[robot][0]

    mine = "You assign subtasks (MARKER-RAY-1). The team:\n{{team}}\nAnswer in JSON."
    prices = {"stub": {"input": 2.0, "cached_input": 0.5, "output": 8.0}}
    llm = coherent.LLM(base_url=stub_url, model="stub")

    def run(out: Path, **kwargs: Any) -> pd.DataFrame:
        return coherent.bench(
            paper40[:3],
            ["pefa", FirstAction],
            backend=llm,
            max_steps=4,
            prompts={"assigner_system.txt": mine},
            prices=prices,
            out=out,
            **kwargs,
        )

    local = run(tmp_path / "local.jsonl")
    on_ray = run(tmp_path / "ray.jsonl", executor="ray")
    assert sorted(set(on_ray["method"])) == ["first-action", "pefa"]
    assert set(on_ray["status"]) <= {"success", "failure"}
    _same_lines(local, on_ray)
    pefa = on_ray[on_ray["method"] == "pefa"]
    # Priced on the workers from the table given on the driver: 10 prompt and 5
    # completion tokens a call.
    assert list(pefa["cost_usd"]) == pytest.approx(list(pefa["llm_calls"] * (10 * 2.0 + 5 * 8.0) / 1e6))
    for path in pefa["transcript"]:
        episode = coherent.load_episode(path)
        assert list(episode.header["prompts"]["replaced"]) == ["assigner_system.txt"]
        assert "MARKER-RAY-1" in episode.transcript[0]["calls"][0]["messages"][0]["content"]
