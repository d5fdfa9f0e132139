"""The example scripts run: the figures script on a small subset, the notebook-style
walk-through in full; and the project's own benchmark through coherent.benchmark."""

from __future__ import annotations

import runpy
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

import coherent
from conftest import REPO


def test_benchmark_figures_writes_the_figures(env0_path: Path, tmp_path: Path) -> None:
    subset = tmp_path / "subset.txt"
    subset.write_text("env0 2\nenv0 9\nenv0 15\n")
    out = tmp_path / "figures"
    script = REPO / "examples" / "benchmark_figures.py"
    args = ["--tasks", str(env0_path), "--subset", str(subset), "--methods", "pefa,cmrs", "--seeds", "2", "--out", str(out)]
    run = subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    figures = sorted(p.name for p in out.glob("*.png"))
    assert figures == [
        "builtin-by-scene.png",
        "builtin-by-type.png",
        "scene.png",
        "simulated-by-scene.png",
        "simulated-by-type.png",
        "timeline.png",
        "tokens.png",
    ]
    assert all((out / f).stat().st_size > 10_000 for f in figures)
    assert "3 tasks, methods pefa, cmrs" in run.stdout
    # Run again, it only redraws: every episode is in the results files already.
    again = subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert "6 episodes: 6 already finished in the results file, 0 to run" in again.stderr  # builtin: 3 tasks x 2 methods
    assert "12 episodes: 12 already finished in the results file, 0 to run" in again.stderr  # simulated: and 2 seeds


def test_step_by_hand_runs(capsys: pytest.CaptureFixture[str]) -> None:
    runpy.run_path(str(REPO / "examples" / "step_by_hand.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "goal satisfied: True" in out
    assert "return 1.0, terminated True, truncated False, after 22 steps" in out
    assert "before step 18: <robot arm>(6) broke down" in out
    assert "24 steps, as the episode took 24; team [11, 13]; goal satisfied: True" in out


def test_benchmark_tasks_and_its_40_subset() -> None:
    every = coherent.benchmark.tasks()
    subset = coherent.benchmark.tasks(subset="40")
    assert len(every) == 100
    assert len(subset) == 40
    keys = {(t.scene, t.task_id) for t in every}
    assert len(keys) == 100
    assert {(t.scene, t.task_id) for t in subset} <= keys
    # Per scene 2 mono, 3 dual and 3 trio tasks, as the planner types them.
    types = Counter((t.scene, coherent.plan(t)["task_type"]) for t in subset)
    assert set(types.values()) == {2, 3} and len(types) == 15
    assert all(n == (2 if ty == "mono" else 3) for (_, ty), n in types.items())
    with pytest.raises(ValueError, match="subset"):
        coherent.benchmark.tasks(subset="41")
