"""A results file knows what it holds, from Python: ``coherent.bench`` records each line's
settings, refuses to resume a file of other settings (``ArgumentError`` naming each
argument, before anything runs, the file left as it was), resumes one of the same,
names the file by its settings when given none; ``coherent.report`` refuses the lines of
several runs and says what it was computed with; a method written in Python replays by
its name once its code is gone (``bench`` and the ``coherent`` command)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

import coherent


@pytest.fixture(scope="module")
def few(env0_tasks: list[coherent.Task]) -> list[coherent.Task]:
    tasks, missing = coherent.select(env0_tasks, [("env0", 2), ("env0", 4), ("env0", 9)])
    assert missing == []
    return tasks


def test_resuming_with_other_settings_raises_naming_each_argument(few: list[coherent.Task], tmp_path: Path) -> None:
    out = tmp_path / "results.jsonl"
    first = coherent.bench(few, ["pefa"], out=out)
    assert (first["settings_backend"] == "builtin").all() and (first["settings_seeds"] == 1).all()
    before = out.read_bytes()
    # The case: the simulated backend at other error rates on the built-in file.
    with pytest.raises(coherent.ArgumentError) as raised:
        coherent.bench(few, ["pefa"], backend="simulated", sim_errors="all=0.3", seeds=2, out=out)
    message = str(raised.value)
    for said in [
        f"{out} holds episodes run with other settings",
        "\n  backend: builtin in the file, simulated now",
        "\n  sim_errors: none in the file, hallucinate=0.3,wrong_robot=0.3,malformed=0.3,suboptimal=0.3 now",
        "\n  seeds: 1 in the file, 2 now",
        "give this one another out=",
        "run with its settings",
    ]:
        assert said in message, message
    assert "history" not in message and "--" not in message, "Python's arguments, not the CLI's flags"
    assert out.read_bytes() == before, "nothing ran"
    with pytest.raises(coherent.ArgumentError, match="max_steps: 2 x GT in the file, 30 now"):
        coherent.bench(few, ["pefa"], max_steps=30, out=out)
    # A method's own settings are settings too.

    class Tuned:
        name = "tuned"
        settings = {"depth": 2}

        def __init__(self, task: coherent.Task) -> None:
            self.plan = [(s["robot"], s["action"]) for s in coherent.plan(task)["plan"]]

        def act(self, view: coherent.View) -> tuple[int, str]:
            return self.plan[view.step - 1]

    coherent.bench(few, [Tuned], out=out)
    Tuned.settings = {"depth": 3}
    with pytest.raises(coherent.ArgumentError, match=r'own settings \(its `settings`\) of tuned: \{"depth":2\} in the file, \{"depth":3\} now'):
        coherent.bench(few, [Tuned], out=out)
    # The same settings resume as before, and another method joins the same file.
    Tuned.settings = {"depth": 2}
    again = coherent.bench(few, ["pefa", "optimal", Tuned], out=out)
    outcome = again.attrs["outcome"]
    assert (outcome["total"], outcome["skipped"], outcome["finished"], outcome["unfinished"]) == (9, 6, 3, 0)
    assert again.attrs["path"] == str(out)


def test_without_out_the_file_is_named_by_its_settings(
    few: list[coherent.Task], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    built_in = coherent.bench(few, ["optimal"])
    name = built_in.attrs["path"]
    assert name.startswith("results-builtin-") and name.endswith(".jsonl") and len(name) == len("results-builtin-") + 14
    assert (tmp_path / name).exists()
    # The same call resumes its own file; other settings write another.
    assert coherent.bench(few, ["optimal"]).attrs["outcome"]["skipped"] == 3
    simulated = coherent.bench(few, ["optimal"], backend="simulated", sim_errors="all=0.3")
    assert simulated.attrs["path"].startswith("results-simulated-") and simulated.attrs["path"] != name
    assert simulated.attrs["outcome"]["skipped"] == 0


def test_a_report_of_two_runs_refuses_and_one_run_says_its_settings(few: list[coherent.Task], tmp_path: Path) -> None:
    built_in = coherent.bench(few, ["pefa"], out=tmp_path / "a.jsonl")
    simulated = coherent.bench(few, ["pefa"], backend="simulated", sim_errors="all=0.5", out=tmp_path / "b.jsonl")
    import pandas as pd

    both = pd.concat([built_in, simulated], ignore_index=True)
    with pytest.raises(coherent.ArgumentError) as raised:
        coherent.report(both)
    message = str(raised.value)
    assert "2 runs" in message and "backend" in message and "sim_errors" in message, message
    assert 'coherent.report(df[df.settings_backend == "builtin"])' in message, message
    one = coherent.report(both[both.settings_backend == "builtin"])
    assert one.settings is not None and one.settings["backend"] == "builtin"
    assert "Settings: backend builtin, sim_errors none, seeds 1" in one.markdown()


PLANNED = (
    "import coherent\n\n"
    "class Planned:\n"
    "    name = 'planned'\n"
    "    def __init__(self, task):\n"
    "        self.plan = [(s['robot'], s['action']) for s in coherent.plan(task)['plan']]\n"
    "    def act(self, view):\n"
    "        return self.plan[view.step - 1]\n"
)


def test_a_python_method_replays_by_its_name_without_its_code(
    few: list[coherent.Task], env0_path: Path, coherent_exe: str, tmp_path: Path
) -> None:
    module = tmp_path / "planned.py"
    module.write_text(PLANNED)
    recorded = coherent.bench(few, ["optimal", f"{module}:Planned"], out=tmp_path / "r.jsonl")
    assert recorded["success"].all()
    module.unlink()
    # Python: by its name, or by the class itself where it is still at hand.
    replayed = coherent.bench(
        few, ["planned", "optimal"], backend="replay", replay_from=tmp_path / "r.jsonl", out=tmp_path / "again.jsonl"
    )
    planned = replayed[replayed.method == "planned"]
    assert len(planned) == 3 and planned["success"].all() and planned["error"].isna().all()
    with pytest.raises(coherent.ArgumentError, match="its methods are optimal, planned"):
        coherent.bench(few, ["greedy"], backend="replay", replay_from=tmp_path / "r.jsonl", out=tmp_path / "x.jsonl")
    # The command, with the module gone: by name it replays; MODULE:CLASS says to use the name.
    (tmp_path / "three.txt").write_text("env0 2\nenv0 4\nenv0 9\n")
    cli = subprocess.run(
        [coherent_exe, "bench", "--tasks", str(env0_path), "--subset", "three.txt", "--methods", "planned",
         "--backend", "replay", "--replay-from", "r.jsonl", "--out", "cli.jsonl"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert cli.returncode == 0, cli.stderr
    assert coherent.results(tmp_path / "cli.jsonl")["success"].all()
    gone = subprocess.run(
        [coherent_exe, "bench", "--tasks", str(env0_path), "--subset", "three.txt", "--methods", "planned.py:Planned",
         "--backend", "replay", "--replay-from", "r.jsonl", "--out", "gone.jsonl"],
        capture_output=True, text=True, cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert gone.returncode == 2, gone.stderr
    assert "name the method as r.jsonl records it (optimal, planned)" in gone.stderr
