"""`coherent run`, the main job: the built-in backend on our demo task, and a real
language model (SmolLM2-135M-Instruct served by llama.cpp's server in this process, on
loopback, one thread) for a few rounds. The small model is not expected to succeed;
what is checked is that the loop around it is sound."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path


REPO = Path(__file__).resolve().parents[2]
DEMO = REPO / "examples" / "tasks" / "demo.json"
KEY = "sk-local-test-SECRET-4242"


def run(exe: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([exe, "run", *args], capture_output=True, text=True, timeout=600)


def read_transcript(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def test_builtin_backend_solves_the_demo_optimally(coherent_exe: str, tmp_path: Path) -> None:
    p = run(coherent_exe, str(DEMO), "--out", str(tmp_path), "--json")
    assert p.returncode == 0, p.stderr
    first = p.stderr.splitlines()[0]
    assert first.startswith("backend: built-in") and "OPENAI_BASE_URL" in first
    summary = json.loads(p.stdout)
    assert summary["success"] is True
    assert summary["steps"] == summary["gt_steps"] == 22
    assert summary["llm_calls"] == 44 and summary["prompt_tokens"] == 0
    records = read_transcript(Path(summary["transcript"]))
    assert [r["type"] for r in records] == ["header"] + ["round"] * 22 + ["summary"]


def test_run_without_json_prints_the_backend_first_and_a_line_per_step(coherent_exe: str, tmp_path: Path) -> None:
    p = run(coherent_exe, str(DEMO), "--out", str(tmp_path), "--max-steps", "3")
    assert p.returncode == 1  # the budget runs out before the goal
    lines = p.stdout.splitlines()
    assert lines[0].startswith("backend: built-in")
    assert [line.split()[1] for line in lines if line.startswith("step ")] == ["1/3", "2/3", "3/3"]
    assert any(line.startswith("failure: step budget spent") for line in lines)


def test_run_rejects_a_file_with_many_tasks_without_task(coherent_exe: str, env0_path: Path, tmp_path: Path) -> None:
    p = run(coherent_exe, str(env0_path), "--out", str(tmp_path))
    assert p.returncode == 2
    assert "choose one with --task ID" in p.stderr
    p = run(coherent_exe, str(env0_path), "--task", "999", "--out", str(tmp_path))
    assert p.returncode == 2 and "no well-formed task with task_id 999" in p.stderr


def test_a_real_model_runs_a_few_rounds_and_replays(
    local_model: str, coherent_exe: str, env0_path: Path, tmp_path: Path
) -> None:
    out = tmp_path / "runs"
    # env0 task 2: bread into the plate, milk box into the microwave (GT 5).
    args = ["--task", "2", "--base-url", f"{local_model}/v1", "--model", "smollm2-135m"]
    p = run(coherent_exe, str(env0_path), *args, "--max-steps", "3", "--out", str(out), "--json", "--api-key", KEY)
    assert p.returncode in (0, 1), p.stderr
    assert KEY not in p.stdout + p.stderr
    assert p.stderr.splitlines()[0].startswith(f"backend: OpenAI-compatible endpoint {local_model}/v1")
    summary = json.loads(p.stdout)
    assert summary["status"] in ("success", "failure")
    assert 1 <= summary["steps"] <= 3
    assert summary["llm_calls"] >= summary["steps"]
    assert summary["prompt_tokens"] > 0 and summary["completion_tokens"] > 0

    records = read_transcript(Path(summary["transcript"]))
    header, rounds, last = records[0], records[1:-1], records[-1]
    assert header["type"] == "header" and header["backend"]["kind"] == "openai"
    assert last["type"] == "summary" and last["steps"] == len(rounds) == summary["steps"]
    for r in rounds:
        assert r["calls"], "every round asks the assigner"
        for call in r["calls"]:
            assert call["messages"] and (call["answer"] or call["error"])
            if call["answer"]:
                assert call["answer"]["latency_ms"] > 0
        if r["outcome"]["kind"] == "executed":
            assert r["decision"]["action"] in r["actions"], "only listed actions run"

    # The replay answers from the transcript alone and must match it round for round.
    again = tmp_path / "replay"
    p = run(coherent_exe, "--replay", summary["transcript"], "--out", str(again), "--json")
    assert p.returncode in (0, 1), p.stderr
    assert "rounds match the recording" in p.stderr
    replayed = json.loads(p.stdout)
    assert (replayed["steps"], replayed["prompt_tokens"]) == (summary["steps"], summary["prompt_tokens"])
    for path in list(out.iterdir()) + list(again.iterdir()):
        assert KEY not in path.read_text(), f"{path} holds the API key"
