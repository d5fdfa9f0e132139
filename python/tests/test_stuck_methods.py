"""Methods written in Python that never return: Ctrl-C stops them in `coherent run
--method`, in `coherent.run` and in `coherent bench` (exit 130, the transcript closed
as interrupted), whatever `act` is doing (a busy loop, a wait on a lock, an `await` that
never ends); `step_timeout` (`--step-timeout`) ends such a step as the method's error
while the rest of a benchmark goes on, and a constructor that never returns obeys it
too."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import pytest

import coherent
from conftest import DEMO

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="signals are POSIX")

# Methods that never answer, in a module the command line and child processes load. Each
# writes a file when its first act starts, so that a test knows when to send a signal.
STUCK = textwrap.dedent(
    '''
    import asyncio, os, threading, time

    def started():
        path = os.environ.get("COHERENT_TEST_STARTED")
        if path:
            open(path, "a").close()

    class Spins:
        def __init__(self, task):
            pass
        def act(self, view):
            started()
            while True:
                pass

    class Waits:
        def __init__(self, task):
            pass
        def act(self, view):
            started()
            threading.Event().wait()

    class Sleeps:
        def __init__(self, task):
            pass
        async def act(self, view):
            started()
            await asyncio.sleep(1e9)

    class NeverMade:
        def __init__(self, task):
            started()
            while True:
                time.sleep(0.01)
        def act(self, view):
            return None, None
    '''
)


@pytest.fixture()
def stuck(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    module = tmp_path / "stuck.py"
    module.write_text(STUCK)
    monkeypatch.syspath_prepend(str(tmp_path))
    return module


def records(folder: Path) -> list[dict[str, Any]]:
    (transcript,) = [p for p in folder.rglob("*.jsonl")]
    return [json.loads(line) for line in transcript.read_text().splitlines()]


def interrupt_when_started(process: subprocess.Popen[str], started: Path) -> tuple[int, str, str]:
    """Sends SIGINT once `started` exists; the process must then end within 20 s."""
    deadline = time.monotonic() + 60
    while not started.exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "act never started"
        time.sleep(0.05)
    time.sleep(0.2)
    process.send_signal(signal.SIGINT)
    try:
        out, err = process.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate()
        pytest.fail(f"still running 20 s after Ctrl-C\n{out}\n{err}")
    return process.returncode, out, err


@pytest.mark.parametrize("method", ["Spins", "Waits", "Sleeps"])
def test_ctrl_c_stops_coherent_run_whatever_act_does(coherent_exe: str, stuck: Path, tmp_path: Path, method: str) -> None:
    started = tmp_path / "started"
    runs = tmp_path / "runs"
    process = subprocess.Popen(
        [coherent_exe, "run", str(DEMO), "--method", f"{stuck}:{method}", "--out", str(runs)],
        env={**os.environ, "COHERENT_TEST_STARTED": str(started)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    code, out, err = interrupt_when_started(process, started)
    assert code == 130, f"{out}\n{err}"
    assert "interrupted" in out
    summary = records(runs)[-1]
    assert summary["type"] == "summary" and summary["status"] == "interrupted"


def test_ctrl_c_stops_coherent_run_in_python_and_bench(stuck: Path, tmp_path: Path) -> None:
    started = tmp_path / "started"
    script = textwrap.dedent(
        f"""
        import signal, sys
        # Ctrl-C as in a terminal, even when this test runs from a background job, which
        # starts its children with SIGINT ignored (and Python then keeps it ignored).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        sys.path.insert(0, {str(stuck.parent)!r})
        import coherent, stuck
        task = coherent.load_tasks({str(DEMO)!r})[0]
        try:
            if sys.argv[1] == "run":
                coherent.run(task, method=stuck.Spins, out={str(tmp_path / "runs")!r})
            else:
                coherent.bench([task], [stuck.Waits], seeds=4, concurrency=4, out={str(tmp_path / "r.jsonl")!r})
        except KeyboardInterrupt:
            print("KeyboardInterrupt")
        """
    )
    for what in ["run", "bench"]:
        started.unlink(missing_ok=True)
        process = subprocess.Popen(
            [sys.executable, "-c", script, what],
            env={**os.environ, "COHERENT_TEST_STARTED": str(started)},
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        code, out, err = interrupt_when_started(process, started)
        assert code == 0 and "KeyboardInterrupt" in out, f"{what}: {code}\n{out}\n{err}"
    assert records(tmp_path / "runs")[-1]["status"] == "interrupted"
    lines = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert len(lines) == 4 and {line["status"] for line in lines} == {"interrupted"}


def test_a_step_over_its_time_limit_is_the_methods_error_and_the_bench_goes_on(
    stuck: Path, tmp_path: Path
) -> None:
    import stuck as methods  # the module the fixture wrote

    task = coherent.load_tasks(DEMO)[0]
    start = time.monotonic()
    frame = coherent.bench(
        [task],
        [methods.Spins, methods.Sleeps, methods.NeverMade, "optimal"],
        seeds=2,
        concurrency=4,
        step_timeout=1.0,
        out=tmp_path / "r.jsonl",
    )
    assert time.monotonic() - start < 60
    assert len(frame) == 8
    ours = frame[frame["method"] != "optimal"]
    assert set(ours["status"]) == {"error"}
    for error in ours["error"]:
        assert "took longer than its time limit of 1 s" in error
    assert set(frame[frame["method"] == "optimal"]["status"]) == {"success"}
    with pytest.raises(coherent.MethodError, match="time limit of 0.5 s"):
        coherent.run(task, method=methods.Waits, step_timeout=0.5, out=tmp_path / "runs")
    for bad in [0, -1, float("nan")]:
        with pytest.raises(coherent.ArgumentError, match="step_timeout"):
            coherent.run(task, method=methods.Waits, step_timeout=bad, out=tmp_path / "runs")


def test_step_timeout_on_the_command_line(coherent_exe: str, stuck: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    bench = subprocess.run(
        [
            coherent_exe, "bench", "--tasks", str(DEMO), "--methods", f"{stuck}:Spins,optimal",
            "--seeds", "2", "--step-timeout", "1", "--out", str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bench.returncode == 0, bench.stderr
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert sorted(line["status"] for line in lines) == ["error", "error", "success", "success"]
    run = subprocess.run(
        [coherent_exe, "run", str(DEMO), "--method", f"{stuck}:Sleeps", "--step-timeout", "1", "--out", str(tmp_path / "runs")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 4, run.stdout + run.stderr
    assert "took longer than its time limit of 1 s" in run.stdout
