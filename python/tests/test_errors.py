"""The exception class of each kind of error the engine reports, and of each way an
episode ends that is not a result (the session's `Error` and `Ending`,
docs/architecture.md, "Errors"). The command line's exit status for the same kinds:
tests/error_kinds.rs. Robots over ROS 2 that cannot be reached or stop answering
(`RobotError`) need the network namespaces of test_ros_interop.py, which has them."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest

import coherent
from conftest import DEMO


def _one_sided_door(tmp_path: Path) -> coherent.Task:
    """The demo with its door leading to one room only: the rules take it, and no
    layout, so no physical world, can be made of it."""
    task = json.loads(DEMO.read_text())
    task["graph"]["edges"] = [
        e for e in task["graph"]["edges"] if not (e["from_id"] == 4 and e["to_id"] == 2 and e["relation_type"] == "LEADING TO")
    ]
    path = tmp_path / "one-sided-door.json"
    path.write_text(json.dumps(task))
    return coherent.load_tasks(path)[0]


def _cases(tmp_path: Path, demo: coherent.Task) -> list[tuple[str, Callable[[], Any], type[BaseException], str]]:
    garbage = tmp_path / "garbage.jsonl"
    garbage.write_text("not a transcript\n")
    return [
        ("invalid", lambda: coherent.run(demo, sim_errors="bogus", out=tmp_path), coherent.ArgumentError, "sim_errors"),
        (
            "backend settings",
            lambda: coherent.bench([demo], ["pefa"], backend="replay", out=tmp_path / "r.jsonl"),
            coherent.ArgumentError,
            "replay_from",
        ),
        ("task", lambda: coherent.load_tasks(tmp_path / "no-such-task.json"), coherent.TaskFormatError, "no-such-task"),
        (
            "prompt",
            lambda: coherent.run(demo, prompts={"central.txt": "{{no_such_placeholder}}"}, out=tmp_path),
            coherent.PromptError,
            "no_such_placeholder",
        ),
        ("data file", lambda: coherent.replay(garbage, out=tmp_path), coherent.DataFileError, "garbage.jsonl: line 1"),
        ("data file", lambda: coherent.load_episode(garbage), coherent.DataFileError, "garbage.jsonl: line 1"),
        # A transcript that cannot be created: its folder would be a regular file.
        ("no transcript", lambda: coherent.run(demo, out=garbage), coherent.DataFileError, "garbage.jsonl/demo-apartment"),
        ("endpoint", lambda: coherent.LLM(base_url="not a url", model="m"), coherent.BackendError, "not a URL"),
        (
            "physics",
            lambda: coherent.run(_one_sided_door(tmp_path), physics=True, out=tmp_path),
            coherent.PhysicsError,
            "leads to 1 rooms",
        ),
    ]


def test_each_kind_of_error_raises_its_class(tmp_path: Path) -> None:
    demo = coherent.load_tasks(DEMO)[0]
    for kind, call, cls, says in _cases(tmp_path, demo):
        with pytest.raises(cls, match=says) as raised:
            call()
        assert isinstance(raised.value, coherent.CoherentError), kind
    garbage = tmp_path / "garbage.jsonl"
    with pytest.raises(coherent.DataFileError) as raised:
        coherent.load_episode(garbage)
    assert (raised.value.file, raised.value.line) == (str(garbage), 1)
    assert not list(tmp_path.glob("*-task*.jsonl")), "no episode started"


class _Refusing(BaseHTTPRequestHandler):
    """A server that refuses every request's key: a failure for good."""

    def do_POST(self) -> None:  # noqa: N802 (the standard library's name)
        self.rfile.read(int(self.headers["content-length"]))
        body = b'{"error": {"message": "bad key"}}'
        self.send_response(401)
        self.send_header("content-type", "application/json")
        self.send_header("content-length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: Any) -> None:
        pass


@pytest.fixture()
def refusing() -> Iterator[str]:
    server = ThreadingHTTPServer(("127.0.0.1", 0), _Refusing)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_port}/v1"
    server.shutdown()
    server.server_close()


class _Raises:
    def __init__(self, task: coherent.Task) -> None:
        pass

    def act(self, view: coherent.View) -> Any:
        raise KeyError("nothing to do")


def test_each_way_an_episode_ends_raises_its_class_or_returns(refusing: str, tmp_path: Path) -> None:
    demo = coherent.load_tasks(DEMO)[0]
    assert coherent.run(demo, out=tmp_path).status == "success"
    assert coherent.run(demo, max_steps=1, out=tmp_path).status == "failure"
    with pytest.raises(coherent.BackendError, match="HTTP 401") as backend:
        coherent.run(demo, llm=coherent.LLM(base_url=refusing, model="m", max_retries=0), out=tmp_path)
    assert backend.value.episode is not None and backend.value.episode.status == "backend_error"
    with pytest.raises(coherent.MethodError, match="KeyError") as method:
        coherent.run(demo, _Raises, out=tmp_path)
    assert method.value.episode.status == "error"
    # A replay whose recording says otherwise than the replay does.
    recorded = coherent.run(demo, out=tmp_path / "recorded")
    lines = recorded.path.read_text().splitlines()
    summary = json.loads(lines[-1])
    summary["steps"] += 1
    tampered = tmp_path / "tampered.jsonl"
    tampered.write_text("\n".join([*lines[:-1], json.dumps(summary)]) + "\n")
    with pytest.raises(coherent.ReplayMismatchError, match="summary differs") as replay:
        coherent.replay(tampered, out=tmp_path)
    assert replay.value.episode.status == "success"


# Loads the demo, then lowers the file limit so that the process has one descriptor left
# (enough for a module Python imports on first use, which it opens and closes again) and
# runs it: the async runtime, which keeps five (epoll, an eventfd, a socket pair and a
# copy of one), cannot start. In a process of its own: the runtime is built once per
# process.
_NO_DESCRIPTORS = """
import os, resource, sys
import coherent
task = coherent.load_tasks(sys.argv[1])[0]
lowest_free = os.open(os.devnull, os.O_RDONLY)
os.close(lowest_free)
resource.setrlimit(resource.RLIMIT_NOFILE, (lowest_free + 1, resource.getrlimit(resource.RLIMIT_NOFILE)[1]))
try:
    coherent.run(task, out=sys.argv[2])
except coherent.CoherentError as e:
    print(type(e).__name__)
    print(e)
"""


def test_a_runtime_that_cannot_start_raises_coherent_error_itself(tmp_path: Path) -> None:
    ran = subprocess.run(
        [sys.executable, "-c", _NO_DESCRIPTORS, str(DEMO), str(tmp_path / "runs")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert ran.returncode == 0, ran.stderr
    kind, message = ran.stdout.splitlines()
    assert kind == "CoherentError", "coherent failed, not the input: the base class itself"
    assert message.startswith("cannot start the async runtime: ") and "Too many open files" in message, message
    assert not (tmp_path / "runs").exists(), "no episode started"
