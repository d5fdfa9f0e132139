"""The `coherent` console script and cli_main."""

from __future__ import annotations

import json
import os
import signal
import subprocess
from pathlib import Path

import pytest

import coherent
from coherent import _cli
from conftest import TASK0_PLAN


def test_console_script_plan(coherent_exe: str, env0_path: Path) -> None:
    # By its bare name, as a user types it; PATH may lack the scripts folder (`.venv/bin/pytest`).
    path = f"{Path(coherent_exe).parent}{os.pathsep}{os.environ.get('PATH', '')}"
    out = subprocess.run(
        ["coherent", "plan", str(env0_path), "--task", "0", "--json"],
        capture_output=True, text=True, check=False, env={**os.environ, "PATH": path},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    (line,) = out.stdout.splitlines()
    result = json.loads(line)
    assert result["optimal_steps"] == 5
    assert [(s["robot"], s["action"]) for s in result["plan"]] == TASK0_PLAN


def test_console_script_usage_error(coherent_exe: str) -> None:
    out = subprocess.run([coherent_exe, "frobnicate"], capture_output=True, text=True, check=False)
    assert out.returncode == 2
    assert "Usage: coherent" in out.stderr


def test_console_script_version(coherent_exe: str) -> None:
    out = subprocess.run([coherent_exe, "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"coherent {coherent.__version__}"


def test_cli_main_in_process(env0_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    assert coherent.cli_main(["coherent", "plan", str(env0_path), "--task", "1", "--json"]) == 0
    result = json.loads(capfd.readouterr().out)
    assert result["task_id"] == 1
    assert result["optimal_steps"] == 4


def test_cli_main_exit_statuses(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    assert coherent.cli_main(["coherent", "--help"]) == 0
    assert "Usage: coherent" in capfd.readouterr().out
    assert coherent.cli_main(["coherent", "plan", str(tmp_path / "missing.json")]) == 2
    assert "missing.json" in capfd.readouterr().err
    assert coherent.cli_main(("coherent", "no-such-command")) == 2


def test_cli_main_rejects_a_string() -> None:
    with pytest.raises(TypeError):
        coherent.cli_main("coherent --help")  # a str is a Sequence[str], but not an argv


def test_cli_entry_point_exits_with_the_status(env0_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    previous = signal.getsignal(signal.SIGINT)
    try:
        with pytest.raises(SystemExit) as info:
            _cli.main(["plan", str(env0_path), "--task", "0"])
        # Ctrl-C ends the command at once, as it would the native binary.
        assert signal.getsignal(signal.SIGINT) == signal.SIG_DFL
    finally:
        signal.signal(signal.SIGINT, previous)
    assert info.value.code == 0
    assert "env0 task 0: 5 steps" in capfd.readouterr().out
