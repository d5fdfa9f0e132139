"""coherent.training and the fine-tuning recipe (docs/training.md): the data written from
Python is the command's, loads with `datasets` and counts its tokens with a GGUF file's
tokenizer; what cannot be taught, or a tokenizer that cannot be loaded, is refused
before anything is written; and examples/finetune.py runs end to end on a tiny randomly
initialised model: a few LoRA steps on the data, the loss falls, the merged model is
written as GGUF, and llama.cpp's server loads it and answers a chat request."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

import coherent
import coherent.training
from conftest import DEMO, REPO, smollm2_gguf


def test_the_data_from_python_is_the_commands_and_loads_with_datasets(
    env0_path: Path, tmp_path: Path, coherent_exe: str
) -> None:
    data = coherent.training.dataset(
        env0_path, "cmrs", tmp_path / "py", execution="sequential", seeds=1, split=(0.5, 0.25, 0.25)
    )
    run = subprocess.run(
        [coherent_exe, "export", "sft", str(env0_path), "--method", "cmrs", "--execution", "sequential",
         "--seeds", "1", "--split", "0.5,0.25,0.25", "--out", str(tmp_path / "cli")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    for split in coherent.training.SPLITS:
        assert (tmp_path / "py" / f"{split}.jsonl").read_bytes() == (tmp_path / "cli" / f"{split}.jsonl").read_bytes()
    assert data.tasks == 13, "env0's 21 tasks less paper40's 8"
    assert data.by_role == {"central": sum(data.examples.values())}
    assert data.left_out["left_out_eval"] == 8 and data.left_out["unreadable"] == 0
    loaded = data.load()
    assert set(loaded) == {"train"}, "one scene: every example in train, the empty splits not loaded"
    assert sum(len(loaded[s]) for s in loaded) == sum(data.examples.values())
    first = loaded["train"][0]
    assert [m["role"] for m in first["prompt"]] == ["system", "user"]
    assert first["completion"][0]["role"] == "assistant"
    assert json.loads(first["completion"][0]["content"])["action"], "the answer is the central model's JSON"
    assert set(loaded["train"]["scene"]) == {"env0"}


def test_tokens_are_counted_with_a_gguf_files_tokenizer(tmp_path: Path, coherent_exe: str) -> None:
    gguf = smollm2_gguf()
    data = coherent.training.dataset(DEMO, "pefa", tmp_path / "d", seeds=0, split=(1, 0, 0), tokenizer=gguf)
    assert data.tokens is not None
    train = data.tokens["train"]
    assert train["examples"] == data.examples["train"] > 0
    assert train["tokens"] > 500 * train["examples"], "a prompt is a scene and a list of actions"
    assert 0 < train["answer_tokens"] < train["tokens"]
    assert "## Tokens" in (tmp_path / "d" / "README.md").read_text()
    run = subprocess.run(
        [coherent_exe, "export", "sft", str(DEMO), "--method", "cmrs", "--seeds", "0", "--tokenizer", str(gguf),
         "--out", str(tmp_path / "cli")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "tokens: train" in run.stdout
    assert "## Tokens" in (tmp_path / "cli" / "README.md").read_text()


def test_what_cannot_be_taught_is_refused_before_anything_is_written(tmp_path: Path, coherent_exe: str) -> None:
    out = tmp_path / "never"
    with pytest.raises(coherent.ArgumentError, match="asks no model"):
        coherent.training.dataset(DEMO, "optimal", out)
    with pytest.raises(coherent.ArgumentError, match="not one of pefa's"):
        coherent.training.dataset(DEMO, "pefa", out, roles=["central"])
    with pytest.raises(coherent.ArgumentError, match="cannot be loaded"):
        coherent.training.dataset(DEMO, "pefa", out, tokenizer=tmp_path / "missing.gguf")
    assert not out.exists()
    run = subprocess.run(
        [coherent_exe, "export", "sft", str(DEMO), "--method", "pefa", "--tokenizer", str(tmp_path / "no-such-model"),
         "--out", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 2 and "--tokenizer" in run.stderr and "cannot be loaded" in run.stderr, run.stderr
    assert not out.exists()


def test_the_recipe_fine_tunes_a_tiny_model_into_a_gguf_that_llama_cpp_serves(tmp_path: Path) -> None:
    """examples/finetune.py on a tiny randomly initialised model (2 layers, width 64,
    SmolLM2's tokenizer): LoRA steps on one example, so that the loss must fall; the
    merged model in GGUF; llama.cpp's server loads it and answers."""
    data = tmp_path / "data"
    coherent.training.dataset(DEMO, "pefa", data, execution="sequential", roles=["executor"], seeds=0, split=(1, 0, 0))
    out = tmp_path / "tuned"
    run = subprocess.run(
        [sys.executable, str(REPO / "examples" / "finetune.py"), "--data", str(data), "--base", str(smollm2_gguf()),
         "--out", str(out), "--tiny", "--max-examples", "1", "--max-steps", "5", "--batch-size", "1",
         "--grad-accum", "1", "--lr", "0.01", "--threads", "1"],
        capture_output=True, text=True, timeout=900, env={**os.environ, "OMP_NUM_THREADS": "1"},
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads((out / "train_report.json").read_text())
    assert report["steps"] == 5
    assert report["last_loss"] < report["first_loss"], report["losses"]
    gguf = out / "model.gguf"
    assert gguf.is_file() and report["gguf"] == str(gguf)
    assert (out / "merged" / "config.json").is_file() and (out / "adapter").is_dir()

    # The adapter alone, merged again into the same base (as after training on another
    # machine): the same GGUF, byte for byte, and the training's report kept.
    again = tmp_path / "merged-again"
    merged = subprocess.run(
        [sys.executable, str(REPO / "examples" / "finetune.py"), "--adapter", str(out / "adapter"), "--base",
         str(smollm2_gguf()), "--out", str(again), "--tiny", "--threads", "1"],
        capture_output=True, text=True, timeout=900, env={**os.environ, "OMP_NUM_THREADS": "1"},
    )  # fmt: skip
    assert merged.returncode == 0, merged.stderr[-3000:]
    assert (again / "model.gguf").read_bytes() == gguf.read_bytes()
    remerged = json.loads((again / "train_report.json").read_text())
    assert remerged["merged_from"] == str(out / "adapter") and remerged["steps"] == 5

    # Served by examples/serve_gguf.py, as docs/training.md serves a tuned model.
    server = subprocess.Popen(
        [sys.executable, str(REPO / "examples" / "serve_gguf.py"), str(gguf), "--port", "0", "--threads", "1",
         "--ctx", "1024"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    try:
        address = server.stdout.readline().strip()
        assert address.startswith("http://127.0.0.1:"), address
        body = json.dumps({"model": "tuned", "messages": [{"role": "user", "content": "Which action?"}], "max_tokens": 8})
        request = urllib.request.Request(
            f"{address}/v1/chat/completions", body.encode(), {"Content-Type": "application/json"}
        )
        with urllib.request.urlopen(request, timeout=120) as r:
            answer = json.loads(r.read())
    finally:
        server.terminate()
        stopped = server.wait(timeout=60)
        server.stdout.close()
    assert stopped == 0, "the server stops at SIGTERM"
    assert answer["choices"][0]["message"]["role"] == "assistant"
    assert answer["usage"]["completion_tokens"] > 0
