"""coherent: plan and execute long-horizon tasks for heterogeneous robot teams (COHERENT).

Everything the ``coherent`` command line does, from Python::

    import coherent

    tasks = coherent.load_tasks("env0.json")          # original env files, native files, folders
    task = tasks[2]
    coherent.plan(task)                               # the shortest plan, its length, the task type
    env = coherent.Env(task)                          # step the world by hand
    episode = coherent.run(task, method="pefa")       # an episode (the built-in backend here)
    episode = coherent.run(task, llm=coherent.LLM(base_url="http://127.0.0.1:8080/v1", model="m"))
    episode = coherent.run(task, method=MyMethod)     # a method written in Python: MyMethod(task).act(view)
    df = coherent.bench(tasks, ["pefa", "cmrs"], backend="simulated", sim_errors="all=0.1", seeds=3)
    df = coherent.bench(tasks, ["pefa"], backend=llm, executor="ray")   # on a Ray cluster
    coherent.report(df).table1                        # the paper's Table I as a DataFrame
    coherent.view(episode)                            # the episode's page (inline in Jupyter)

``coherent.plot`` draws the paper's tables, episode timelines, tokens per step, success
against cost (``pareto``) and the scene map (matplotlib); ``coherent.gym`` is a Gymnasium
environment, ``coherent.marl`` a PettingZoo one with the robots as agents;
``coherent.training`` writes training data for the methods' models from the optimal
planner. The engine is Rust (``coherent._coherent``); errors derive from
:class:`CoherentError`.

Planning, stepping and running need no other package. The DataFrames (``bench``,
``results``, ``report``, ``Episode.to_dataframe``) and ``coherent.plot`` need pandas and
matplotlib, ``pip install '.[analysis]'``; ``coherent.gym`` needs gymnasium,
``pip install '.[gym]'``; ``coherent.marl`` needs pettingzoo, ``pip install '.[marl]'``.
"""

# The imports the package needs for itself are bound to underscored names, so that the
# namespace holds the API (`__all__`), the submodules and nothing else.
import importlib as _importlib
from typing import Any as _Any

from ._coherent import (
    DEFAULT_MAX_STATES,
    LLM,
    METHODS,
    ActionParseError,
    ArgumentError,
    BackendError,
    CoherentError,
    DataFileError,
    Decision,
    Env,
    Episode,
    MethodError,
    PhysicsError,
    PromptError,
    Reply,
    ReplayMismatchError,
    RobotError,
    Task,
    TaskFormatError,
    UnknownRobotError,
    __version__,
    budget,
    check_pddl_plan,
    cli_main,
    generate,
    load_episode,
    load_tasks,
    parse_action,
    pddl,
    plan,
    read_tasks,
    render_svg,
    replay,
    robot_paths,
    run,
    scene_layout,
    select,
    validate,
    View,
)
from ._view import Page, view
from .analysis import Report, bench, report, results
from .executors import RayExecutor

__all__ = [
    "DEFAULT_MAX_STATES",
    "LLM",
    "METHODS",
    "ActionParseError",
    "ArgumentError",
    "BackendError",
    "CoherentError",
    "DataFileError",
    "Decision",
    "Env",
    "Episode",
    "MethodError",
    "PhysicsError",
    "PromptError",
    "RayExecutor",
    "Reply",
    "Page",
    "ReplayMismatchError",
    "Report",
    "RobotError",
    "Task",
    "TaskFormatError",
    "UnknownRobotError",
    "__version__",
    "bench",
    "budget",
    "cli_main",
    "generate",
    "load_episode",
    "load_tasks",
    "parse_action",
    "plan",
    "pddl",
    "check_pddl_plan",
    "read_tasks",
    "render_svg",
    "replay",
    "report",
    "results",
    "robot_paths",
    "run",
    "scene_layout",
    "select",
    "validate",
    "view",
    "View",
]

# The public submodules. `analysis` and `executors` are imported above; the others load on
# first use: `coherent.plot` imports matplotlib (slow to import; the extra
# `analysis`), `coherent.gym` gymnasium (the extra `gym`), `coherent.marl` pettingzoo (the
# extra `marl`).
_SUBMODULES = ("analysis", "benchmark", "executors", "gym", "marl", "plot", "training")


def __getattr__(name: str) -> _Any:
    if name in _SUBMODULES:
        return _importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # What `dir(coherent)` and completion show: the API and the submodules, not the
    # private modules (`_coherent`, `_methods`, ...) that importing the package loads.
    return sorted([*__all__, *_SUBMODULES])
