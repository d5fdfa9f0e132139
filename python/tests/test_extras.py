"""The package without its extras: `pip install .` brings no other package, planning,
stepping and running need none, and each entry point that needs pandas, matplotlib,
gymnasium or pettingzoo says which extra to install. Each check runs in a fresh interpreter in which
the packages it hides cannot be imported (`sys.modules[name] = None`)."""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

import coherent
from coherent._extras import needs
from conftest import DEMO, REPO

EXTRA_PACKAGES = ("pandas", "matplotlib", "numpy", "gymnasium", "pettingzoo")
# The packages as the installed metadata pins them, and the extra from a checkout.
EXTRAS = "; the extras: analysis, gym, marl, ray"
ANALYSIS = 'pip install "pandas>=3.1" "matplotlib>=3.11" (from a checkout of the repository: pip install ".[analysis]")' + EXTRAS
GYM = 'pip install "gymnasium>=1.4" (from a checkout of the repository: pip install ".[gym]")' + EXTRAS
MARL = 'pip install "pettingzoo>=1.27" "gymnasium>=1.4" (from a checkout of the repository: pip install ".[marl]")' + EXTRAS


def _run_without(hidden: tuple[str, ...], code: str, **paths: Path) -> subprocess.CompletedProcess[str]:
    """Runs `code` in a new interpreter where the `hidden` packages cannot be imported,
    with `DEMO` and each of `paths` defined as a path string."""
    prelude = ["import sys", *(f"sys.modules[{name!r}] = None" for name in hidden)]
    prelude += [f"{name} = {str(path)!r}" for name, path in {"DEMO": DEMO, **paths}.items()]
    source = "\n".join(prelude) + "\n" + textwrap.dedent(code)
    return subprocess.run([sys.executable, "-c", source], capture_output=True, text=True, timeout=300, cwd=REPO)


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A results file and an episode's transcript, made with every package at hand."""
    out = tmp_path_factory.mktemp("finished")
    task = coherent.load_tasks(DEMO)[0]
    coherent.bench([task], ["optimal"], out=out / "results.jsonl")
    episode = coherent.run(task, method="optimal", out=out / "runs")
    return {"RESULTS": out / "results.jsonl", "TRANSCRIPT": episode.path}


def test_the_package_requires_nothing_but_its_extras() -> None:
    # The installed wheel's metadata: every requirement belongs to an extra.
    requires = importlib.metadata.requires("coherent-robots") or []
    assert requires and all("extra ==" in r for r in requires), requires
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["dependencies"] == []
    extras = project["optional-dependencies"]
    assert extras["analysis"] == ["pandas>=3.1", "matplotlib>=3.11"]
    assert extras["gym"] == ["gymnasium>=1.4"]
    assert extras["marl"] == ["pettingzoo>=1.27", "gymnasium>=1.4"]


def test_planning_stepping_and_running_need_no_extra(tmp_path: Path) -> None:
    code = """
        import coherent
        import coherent.benchmark
        task = coherent.load_tasks(DEMO)[0]
        assert coherent.plan(task)["optimal_steps"] == 22
        assert coherent.validate(task) == []
        env = coherent.Env(task)
        assert env.step(13, "[movetowards] <fridge>(8)")[0]
        assert coherent.parse_action("[grab] <mug>(7)")["verb"] == "grab"
        assert coherent.render_svg(task, paths=False).startswith("<svg")
        assert len(coherent.benchmark.tasks("40")) == 40
        episode = coherent.run(task, out=OUT)
        print(episode.success, episode.steps)
    """
    run = _run_without(EXTRA_PACKAGES, code, OUT=tmp_path / "runs")
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["True", "22"]


@pytest.mark.parametrize(
    ("hidden", "code", "message"),
    [
        (
            "pandas",
            "coherent.bench(coherent.load_tasks(DEMO), ['optimal'], out=NEW)",
            f"coherent.bench's DataFrame needs pandas: {ANALYSIS}",
        ),
        ("pandas", "coherent.results(RESULTS)", f"coherent.results's DataFrame needs pandas: {ANALYSIS}"),
        ("pandas", "coherent.report(RESULTS)", f"coherent.report's Report needs pandas: {ANALYSIS}"),
        (
            "pandas",
            "coherent.load_episode(TRANSCRIPT).to_dataframe()",
            f"Episode.to_dataframe (coherent.analysis.episode_frame) needs pandas: {ANALYSIS}",
        ),
        ("matplotlib", "import coherent.plot", f"coherent.plot needs matplotlib: {ANALYSIS}"),
        ("pandas", "coherent.plot.table(RESULTS)", f"coherent.plot needs pandas: {ANALYSIS}"),
        ("gymnasium", "from coherent.gym import CoherentEnv", f"coherent.gym needs gymnasium: {GYM}"),
        ("numpy", "coherent.gym.CoherentEnv", f"coherent.gym needs numpy: {GYM}"),
        ("pettingzoo", "from coherent.marl import CoherentParallelEnv", f"coherent.marl needs pettingzoo: {MARL}"),
        ("gymnasium", "coherent.marl.CoherentParallelEnv", f"coherent.marl needs gymnasium: {MARL}"),
    ],
)
def test_what_needs_an_extra_names_it(
    hidden: str, code: str, message: str, finished: dict[str, Path], tmp_path: Path
) -> None:
    new = tmp_path / "new.jsonl"
    run = _run_without((hidden,), f"import coherent\n{code}", NEW=new, **finished)
    assert run.returncode == 1
    assert run.stderr.strip().splitlines()[-1] == f"ImportError: {message}"
    # The cause, chained: the hidden package.
    assert "ModuleNotFoundError" in run.stderr.split("The above exception was the direct cause")[0]
    assert not new.exists()  # bench says so before it runs anything


def test_other_import_errors_pass_through() -> None:
    with pytest.raises(ModuleNotFoundError, match="no_such_package") as info:
        with needs("coherent.plot", "analysis"):
            import no_such_package  # type: ignore[import-not-found]  # noqa: F401
    assert info.value.name == "no_such_package"
    # gymnasium belongs to the other extra.
    with pytest.raises(ImportError, match="^halted$"):
        with needs("coherent.plot", "analysis"):
            raise ImportError("halted", name="gymnasium")
