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


def _cli_findings(coherent_exe: str, *paths: Path) -> dict[tuple[str, int], list[str]]:
    """`coherent validate`'s findings by (scene, task_id), parsed from its lines."""
    out = subprocess.run([coherent_exe, "validate", *map(str, paths)], capture_output=True, text=True, check=False)
    assert out.returncode in (0, 1), out.stderr
    found: dict[tuple[str, int], list[str]] = {}
    for line in out.stdout.splitlines()[:-1]:  # the last line is the count
        head, finding = line.split(": ", 1)
        scene, _, rest = head.partition(" task ")
        found.setdefault((scene, int(rest.split(" ")[0])), []).append(finding)
    return found


def test_validate_in_python_and_on_the_command_line_agree(coherent_exe: str, tmp_path: Path) -> None:
    # Every task of our benchmark, and one whose stairs break the scene rules: the two
    # front ends go through one check, so they report the same findings.
    folder = Path(__file__).parents[2] / "benchmark" / "tasks"
    task = json.loads((folder / "s5-house" / "task-00.json").read_text())
    task["geometry"]["stairs"][0]["width"] = 0.6
    task["task_id"] = 999
    broken = tmp_path / "narrow-stairs.json"
    broken.write_text(json.dumps(task))
    cli = _cli_findings(coherent_exe, folder, broken)
    tasks = coherent.load_tasks(folder) + coherent.load_tasks(broken)
    assert len(tasks) == 101
    py: dict[tuple[str, int], list[str]] = {}
    for t in tasks:
        found = coherent.validate(t)
        if found:
            py.setdefault((t.scene, t.task_id), []).extend(found)
    assert py == cli
    stairs = py[(task["scene"], task["task_id"])]
    assert "geometry: stairs 17: 0.60 m wide; a flight is at least 1 m wide" in stairs
