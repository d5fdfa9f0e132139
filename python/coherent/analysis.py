"""Results as pandas DataFrames: benchmark runs, the paper's tables, an episode's steps
and its model calls (``pip install '.[analysis]'`` from a checkout brings pandas).

The numbers come from Rust (``coherent_agents::bench`` and ``::report``, the same code
as ``coherent bench``); this module only shapes them into DataFrames, but for
:func:`events_table`, which works the report's events table out from a results frame
in pandas (by the report's definitions, for frames the report does not take).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any, Literal, Union

from . import _coherent, _view
from ._coherent import LLM, Episode, Task
from ._extras import needs
from .executors import RayExecutor, resolve

if TYPE_CHECKING:
    import pandas as pd

PathLike = Union[str, "os.PathLike[str]"]
Results = Union["pd.DataFrame", PathLike, Sequence[Mapping[str, Any]]]
# A price file (JSON, or TOML for a .toml file), or {model: {"input": .., "output": ..}}.
Prices = Union[PathLike, Mapping[str, Mapping[str, Any]]]

# The results file's `backend` object, spread over three columns of the DataFrame.
_BACKEND_FIELDS = ("kind", "model", "base_url")
# Its `settings` object (what makes lines comparable), spread over columns `settings_*`.
_SETTINGS_FIELDS = (
    "backend",
    "model",
    "sim_errors",
    "temperature",
    "model_seed",
    "seeds",
    "prompts",
    "history",
    "max_steps",
    "max_states",
    "physics",
    "robots",
    "coherent",
    "executions",
    "method",
)
# The settings columns that hold ints, none negative, kept ints (pandas's nullable
# UInt64, which holds a u64 seed whole) where some lines record no settings.
_SETTINGS_INTS = ("model_seed", "seeds", "history", "max_steps", "max_states")
# The columns a line's `reference` (an episode with events, docs/dynamic.md) adds, in
# their order; a frame none of whose lines has one has none of them.
_REFERENCE_COLUMNS = (
    "event_kinds",
    "reference_steps",
    "over_reference",
    "unreachable",
    "recoveries",
    "recovered",
    "recovery_rounds",
    "recovery_wasted",
    "recovery_calls",
)
# Those that hold ints, kept ints (nullable Int64) where some lines have no reference.
_REFERENCE_INTS = (
    "reference_steps",
    "over_reference",
    "recoveries",
    "recovered",
    "recovery_rounds",
    "recovery_wasted",
    "recovery_calls",
)


def _pandas(what: str) -> ModuleType:
    """pandas, imported when first needed; without it, an ImportError naming ``what`` and
    the extra to install."""
    with needs(what, "analysis"):
        import pandas
    return pandas


def results(path: PathLike, *, prices: Prices | None = None) -> pd.DataFrame:
    """The results file of :func:`bench` (or ``coherent bench --out``) as a DataFrame,
    one row per line; the ``backend`` object is spread over ``backend_kind``,
    ``backend_model`` and ``backend_base_url``, the ``settings`` object over
    ``settings_backend``, ``settings_sim_errors``, ``settings_seeds``, ... (NA on lines
    that record none). With ``prices`` (a price file or a dict, as :func:`bench` takes),
    each ``cost_usd`` is the line's recorded tokens at those prices.

    Where some line has a ``reference`` (an episode of a task with events,
    ``docs/dynamic.md``), the frame keeps it (a dict) and adds, NA on the lines without
    one: ``event_kinds`` (the kinds of the task's events in its order, joined by ``+``,
    as the events table groups them), ``reference_steps`` (the oracle's steps, joint
    steps in a parallel episode; NA when the goal went out of reach or its optimum is
    unknown), ``over_reference`` (``steps - reference_steps``, whatever the status),
    ``unreachable`` (why the goal is out of reach for good, else None), ``recoveries``
    (the events that changed the world), ``recovered`` (those after which the team
    carried out an action that brought the goal nearer), and, summed over the episode's
    events, ``recovery_rounds`` (the rounds until then, of the events recovered from),
    ``recovery_wasted`` (actions meanwhile that did not) and ``recovery_calls`` (model
    calls of those rounds): divide by ``recovered`` or ``recoveries`` for the means per
    event (:func:`events_table` does). The counts are nullable ints (``Int64``). A file
    without events gives the frame it gave before events existed."""
    pandas = _pandas("coherent.results's DataFrame")
    frame = _frame(pandas, _coherent.read_results(path, prices=prices))
    frame.attrs["path"] = os.fspath(path)
    return frame


def _frame(pandas: ModuleType, lines: list[dict[str, Any]]) -> pd.DataFrame:
    rows = []
    for line in lines:
        row = {k: v for k, v in line.items() if k not in ("backend", "settings")}
        for name in _BACKEND_FIELDS:
            row[f"backend_{name}"] = line["backend"][name]
        settings = line.get("settings") or {}
        for name in _SETTINGS_FIELDS:
            row[f"settings_{name}"] = settings.get(name)
        rows.append(row)
    # Only where some line has a reference, so that a file without events is as before.
    referenced = any(line.get("reference") is not None for line in lines)
    if referenced:
        for row, line in zip(rows, lines):
            row.update(_reference_columns(line))
    # `df.coherent` shows the results page in Jupyter (coherent.view).
    _view.register(pandas)
    frame = pandas.DataFrame(rows)
    if not frame.empty:
        frame = frame.astype({f"settings_{name}": "UInt64" for name in _SETTINGS_INTS})
    if referenced:
        frame = frame.astype({name: "Int64" for name in _REFERENCE_INTS})
    return frame


def _reference_columns(line: Mapping[str, Any]) -> dict[str, Any]:
    """The ``reference`` columns of one results line (see :func:`results`); None each
    for a line without one."""
    reference = line.get("reference")
    if reference is None:
        return dict.fromkeys(_REFERENCE_COLUMNS)
    recoveries = reference.get("recoveries") or []
    rounds = [r["rounds"] for r in recoveries if r.get("rounds") is not None]
    steps = reference.get("steps")
    return {
        "event_kinds": "+".join(reference.get("kinds") or []),
        "reference_steps": steps,
        "over_reference": None if steps is None else line["steps"] - steps,
        "unreachable": reference.get("unreachable"),
        "recoveries": len(recoveries),
        "recovered": len(rounds),
        "recovery_rounds": sum(rounds),
        "recovery_wasted": sum(r["wasted"] for r in recoveries),
        "recovery_calls": sum(r["calls"] for r in recoveries),
    }


def _lines(data: Results) -> list[dict[str, Any]]:
    """Results lines as the Rust side reads them, from a DataFrame, a file or dicts."""
    if isinstance(data, (str, os.PathLike)):
        return _coherent.read_results(data)
    records = data.to_dict("records") if hasattr(data, "to_dict") else list(data)
    lines = []
    for record in records:
        # The reference's columns are the frame's reading of `reference`, which stays.
        line = {k: _missing_to_none(v) for k, v in record.items() if k not in _REFERENCE_COLUMNS}
        if "backend" not in line:
            line["backend"] = {name: line.pop(f"backend_{name}", None) for name in _BACKEND_FIELDS}
        if "settings" not in line:
            settings = {name: line.pop(f"settings_{name}", None) for name in _SETTINGS_FIELDS}
            # A line that records no settings has none of them.
            line["settings"] = settings if settings["backend"] is not None else None
            if line["settings"] is not None and line["settings"]["method"] is None:
                line["settings"]["method"] = {}
            # A sequential run records no executions (NA in its column).
            if line["settings"] is not None and line["settings"]["executions"] is None:
                del line["settings"]["executions"]
        lines.append(line)
    return lines


def _missing_to_none(value: Any) -> Any:
    # pandas marks a missing value NaN (float columns) or NA/None (others).
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    if type(value).__name__ in ("NAType", "NaTType"):
        return None
    return value


def bench(
    tasks: PathLike | Iterable[Task],
    methods: Sequence[str | Callable[[Task], Any]],
    *,
    execution: Literal["sequential", "parallel"] | Sequence[str] = "sequential",
    backend: Literal["builtin", "simulated", "replay"] | LLM = "builtin",
    sim_errors: str | Mapping[str, float] | None = None,
    replay_from: PathLike | None = None,
    seeds: int = 1,
    concurrency: int = 4,
    history: int = 5,
    max_states: int = _coherent.DEFAULT_MAX_STATES,
    max_steps: int | None = None,
    out: PathLike | None = None,
    progress: bool | None = None,
    prompts: PathLike | Mapping[str, str] | None = None,
    prices: Prices | None = None,
    executor: Literal["local", "ray"] | RayExecutor = "local",
    physics: bool = False,
    robots: Literal["local", "ros2"] = "local",
    namespace: str | None = None,
    robot_timeout: float = 10.0,
    server_wait: float = 10.0,
    step_timeout: float | None = None,
) -> pd.DataFrame:
    """Runs every method on every task for every seed, as ``coherent bench`` does, and
    returns the whole results file ``out`` as a DataFrame (see :func:`results`).

    ``tasks`` is a list of tasks (e.g. from :func:`coherent.select`) or a path, of which
    every well-formed task runs. ``backend``: ``"builtin"`` (the optimal planner plays
    every role), ``"simulated"`` (the planner with seeded mistakes at the ``sim_errors``
    rates, e.g. ``"all=0.1"``), an :class:`LLM`, or ``"replay"``: the episodes of the
    earlier results file ``replay_from`` answer from their transcripts (no network), with
    their recorded settings; a line's ``error`` says when one came out differently.
    ``methods`` may then name methods written in Python by their name, without their
    code.

    ``out`` is the results file, appended to and resumable: episodes already finished
    in it are skipped, so after Ctrl-C (``KeyboardInterrupt``) the same call finishes the
    rest. Each line records the settings that make it comparable (the backend and its
    model, the error rates, the seeds, the prompt set, the history, the budget, physics,
    the robots, each method's own settings, the version); a file whose lines have other
    settings raises :class:`~coherent.ArgumentError` naming each one before anything
    runs. Without ``out`` the name comes from the settings,
    ``results-<backend>-<8 hex digits>.jsonl`` in the current folder (in
    ``df.attrs["path"]``): other settings, another file.

    ``methods`` are built-in methods' names (:data:`METHODS`) and methods written in
    Python: a class (or any callable) ``M``, made once per episode as ``M(task)``, whose
    ``act(view)`` gives each step's :class:`Decision` (see :func:`coherent.run` and
    ``docs/methods.md``), named ``M.name`` or its class's name; ``M.settings``, a dict,
    declares its own settings; ``"MODULE:CLASS"`` loads one. An exception in ``act``
    ends that episode alone with status ``"error"`` and the traceback in ``error`` and
    in its transcript; the report lists such episodes by method. ``step_timeout``
    (seconds) ends a step of a method written in Python that takes longer (its ``act``,
    or ``M(task)`` at the first step) as that method's error, and the run goes on.
    ``max_steps`` sets every episode's budget (2 x GT by default).

    ``execution``: ``"sequential"`` (one robot's action a step, the paper's),
    ``"parallel"`` (joint steps: every robot at most one action, all at once; the budget
    is 2 x the fewest joint steps) or both, ``["sequential", "parallel"]``: each method
    runs in each, the lines say which (``execution``), and :func:`report` compares them
    (``Report.makespan``). MCTS and LLM-MCTS are sequential only (``ArgumentError``).

    ``prompts`` (a folder of template files, or ``{file name: text}``) replaces built-in
    prompt templates; a template with an unknown placeholder raises
    :class:`~coherent.PromptError` before anything runs. ``prices`` (a JSON or TOML price
    file, or ``{model: {"input": .., "cached_input": .., "output": ..}}`` in USD per
    million tokens) adds to the built-in price table; every row's ``cost_usd`` is its
    tokens at its model's price (NaN when the model has none), the rows of episodes
    finished before this call included. What the run did is in ``df.attrs["outcome"]``;
    with a path, the malformed tasks left out are in ``df.attrs["malformed"]``.

    ``progress``: a bar on stderr with the episodes done, their rate and the time left
    (redrawn in place in a terminal or a notebook); ``None`` (the default) shows it when
    Python runs interactively (a terminal, IPython, Jupyter), ``True`` always (one line
    per episode when stderr is no terminal), ``False`` never.

    ``physics=True`` carries every action out in Rapier too (a physical failure is an
    infeasible step whose message has the numbers). ``robots="ros2"`` sends the actions
    to one ROS 2 action server per robot under ``namespace`` (``coherent robots serve``,
    or real robots; ``robot_timeout`` and ``server_wait`` as for :class:`Env`): the robots
    of a namespace carry out one episode at a time, so the episodes run one by one (a
    ``UserWarning`` says so when ``concurrency`` asks for more), and from this machine
    only (``executor="local"``).

    ``executor``: ``"local"`` runs the episodes here, ``concurrency`` at once;
    ``"ray"`` (a local Ray cluster, or the one this process joined) or a
    :class:`~coherent.executors.RayExecutor` runs them on a Ray cluster, ``concurrency``
    at once across it, with the same results lines; this process alone writes ``out``,
    so resuming, the report and the tables work alike (``docs/scale.md``).
    """
    # Before the run, not after it.
    pandas = _pandas("coherent.bench's DataFrame")
    runner = resolve(executor)
    malformed: list[_coherent.TaskFormatError] = []
    if isinstance(tasks, (str, os.PathLike)):
        chosen, malformed = _coherent.read_tasks(tasks)
    else:
        chosen = list(tasks)
    settings: dict[str, Any] = {
        "execution": execution,
        "backend": backend,
        "sim_errors": sim_errors,
        "replay_from": replay_from,
        "seeds": seeds,
        "concurrency": concurrency,
        "history": history,
        "max_states": max_states,
        "max_steps": max_steps,
        "out": out,
        "progress": _progress_mode(progress),
        "prompts": prompts,
        "prices": prices,
        "physics": physics,
        "step_timeout": step_timeout,
    }
    robot_settings = {
        "robots": robots,
        "namespace": namespace,
        "robot_timeout": robot_timeout,
        "server_wait": server_wait,
    }
    if runner is None:
        outcome = _coherent.run_bench(chosen, list(methods), **settings, **robot_settings)
    elif robots != "local":
        raise _coherent.ArgumentError(
            f"robots={robots!r}: robots over ROS 2 carry out one episode at a time from this "
            'machine: use executor="local"'
        )
    else:
        outcome = runner.run(chosen, list(methods), **settings)
    frame = _frame(pandas, _coherent.read_results(outcome["out"], prices=prices))
    frame.attrs["outcome"] = outcome
    frame.attrs["malformed"] = [str(e) for e in malformed]
    frame.attrs["path"] = outcome["out"]
    return frame


def _progress_mode(progress: bool | None) -> Literal["bar", "lines"] | None:
    """How :func:`bench` shows its progress: a bar redrawn in place (stderr a terminal,
    IPython, a notebook), a line per episode (otherwise, with ``progress=True`` or in an
    interactive session), or not at all (``progress=False``, or ``None`` when Python
    runs neither interactively nor into a terminal), as tqdm users would expect."""
    in_place = _stderr_is_terminal() or _in_ipython()
    interactive = in_place or hasattr(sys, "ps1") or bool(sys.flags.interactive)
    if progress is False or (progress is None and not interactive):
        return None
    return "bar" if in_place else "lines"


def _stderr_is_terminal() -> bool:
    isatty = getattr(sys.stderr, "isatty", None)
    try:
        return bool(isatty and isatty())
    except ValueError:  # a closed stream
        return False


def _in_ipython() -> bool:
    """Whether this runs in IPython or a Jupyter kernel, whose output redraws a line on
    a carriage return as a terminal does."""
    shell = sys.modules.get("IPython")
    get = getattr(shell, "get_ipython", None)
    return get is not None and get() is not None


@dataclass(frozen=True)
class Report:
    """The paper's tables of a benchmark's results (:func:`report`).

    ``table1`` (by task type: mono, dual, trio, Avg), ``table2`` (by scene, then Avg)
    and ``table3`` (by team size, ``"3 robots"`` and so on, then Avg; None unless the
    tasks have teams of more than one size, as generated sets do) have one row per method and a last ``ground truth`` row (its AS is the mean GT
    steps), and columns ``(column, stat)`` with ``stat`` one of ``SR``, ``SR ci95``,
    ``AS``, ``AS ci95`` (the half-width of a 95% interval over seeds; NaN with one
    seed). ``costs`` has a row per method: LLM calls and tokens per episode and per
    step, the prompt tokens the servers read from their caches (``cached_tokens``) and
    their share of all prompt tokens (``cached_share``, NaN without prompt tokens), and
    the cost in USD (cached tokens at the cached input price) in all, per task
    (episode) and per success (NaN where a model has no price). A method's parallel
    episodes are rows of their own, ``"<method> (parallel)"``, and ``makespan`` (empty
    without parallel episodes) has a row per method, execution and task type (``mono``,
    ``dual``, ``trio``, ``Avg``): SR, the mean makespan of the successful episodes and
    the optimal makespan of their tasks, actions per episode, LLM calls per action,
    simulated seconds (physics), and the speed-up over the same method run sequentially
    (its steps over the parallel ones', on the (task, seed) pairs both solved; ``pairs``
    says how many). ``events`` (empty without tasks with events) is the events table,
    "Events: success and recovery", as :func:`events_table` describes it.
    """

    table1: pd.DataFrame
    table2: pd.DataFrame
    table3: pd.DataFrame | None
    costs: pd.DataFrame
    makespan: pd.DataFrame
    events: pd.DataFrame
    backends: list[str]
    seeds: list[int]
    unfinished: int
    """Episodes without a final result (backend error, the method's error or interrupted),
    left out."""
    errors: int
    """Those of them that failed with an error their line names: raised by the method
    (status ``error``), or why the episode could not go on (status ``interrupted`` with
    an ``error``: a robot that stopped answering, a transcript that could not be
    created)."""
    untyped_tasks: int
    """Tasks the planner finds no plan for: counted in Avg only."""
    settings: dict[str, Any] | None
    """The settings every line was run with (the results file's ``settings`` without a
    method's own); None for lines that record none."""
    method_settings: dict[str, dict[str, Any]]
    """The settings each method written in Python declared, by method."""
    failures: list[dict[str, Any]]
    """The episodes that failed with an error (as counted in ``errors``), by method:
    ``method``, ``episodes``, ``first_error`` (the method's exception and where it was
    raised, or why the episode could not go on) and the ``transcript`` (a method's whole
    traceback is there)."""
    lines: list[dict[str, Any]] = field(repr=False)

    def markdown(self) -> str:
        """The tables as ``coherent bench --report`` prints them."""
        return _coherent.report_text(self.lines, "markdown")

    def csv(self) -> str:
        """The tables as ``coherent bench --report --format csv`` prints them."""
        return _coherent.report_text(self.lines, "csv")

    def _repr_markdown_(self) -> str:
        return self.markdown()


def report(data: Results, *, prices: Prices | None = None) -> Report:
    """Table I and Table II of the paper, and the costs, from benchmark results: a
    DataFrame of :func:`bench` or :func:`results`, a results file, or its lines.

    The lines must share their settings (one run, resumed as often as you like): lines
    of several raise :class:`~coherent.ArgumentError` naming the runs and the settings
    in which they differ; pick one run's rows by its ``settings_*`` columns. With
    ``prices`` (a price file or a dict, as :func:`bench` takes) each line's cost is its
    recorded tokens at those prices."""
    pandas = _pandas("coherent.report's Report")
    lines = _lines(data)
    if prices is not None:
        lines = _priced(lines, prices)
    r = _coherent.report_tables(lines)
    costs = pandas.DataFrame(r["costs"]).set_index("method") if r["costs"] else pandas.DataFrame()
    if not costs.empty:
        # A model without a price leaves None: NaN, as in the results' cost_usd; so does
        # a method without prompt tokens its cached share.
        costs = costs.astype({name: float for name in (*_COST_COLUMNS, "cached_share")})
    speed = r.get("makespan", [])
    makespan = (
        pandas.DataFrame(speed).set_index(["method", "execution", "column"]) if speed else pandas.DataFrame()
    )
    if not makespan.empty:
        makespan = makespan.astype({name: float for name in _MAKESPAN_COLUMNS})
    return Report(
        table1=_table(pandas, r["table1"]),
        table2=_table(pandas, r["table2"]),
        table3=_table(pandas, r["table3"]) if r.get("table3") else None,
        costs=costs,
        makespan=makespan,
        events=_events_frame(pandas, r.get("events", []), ()),
        backends=r["backends"],
        seeds=r["seeds"],
        unfinished=r["unfinished"],
        errors=r["errors"],
        untyped_tasks=r["untyped_tasks"],
        settings=r["settings"],
        method_settings=r["method_settings"],
        failures=r["failures"],
        lines=lines,
    )


def _priced(lines: list[dict[str, Any]], prices: Prices) -> list[dict[str, Any]]:
    """The lines with their ``cost_usd`` worked out anew from their tokens."""
    return _coherent.price_lines(lines, prices)


# The report's cost columns, in USD (None where a model has no price).
_COST_COLUMNS = ("cost_usd", "cost_per_task", "cost_per_success")

# The makespan table's columns that may be None (NaN in the DataFrame).
_MAKESPAN_COLUMNS = ("makespan", "optimal_makespan", "actions", "calls_per_action", "sim_seconds", "speedup")


# The events table's columns (the Rust report's `EventRow`), after its index.
_EVENT_INDEX = ("method", "execution", "kind")
_EVENT_COLUMNS = (
    "episodes",
    "sr",
    "conceded",
    "over_reference",
    "recovered",
    "recoveries",
    "recovery_rounds",
    "wasted",
    "recovery_calls",
)
# Those that are means, None (NaN) where there is nothing to average.
_EVENT_MEANS = ("sr", "over_reference", "recovery_rounds", "wasted", "recovery_calls")
# The statuses of a final results line, as the report counts them.
_FINAL = ("success", "failure", "conceded")


def _events_frame(pandas: ModuleType, rows: list[dict[str, Any]], by: Sequence[str]) -> pd.DataFrame:
    index = [*_EVENT_INDEX, *by]
    frame = pandas.DataFrame(rows, columns=[*index, *_EVENT_COLUMNS]).set_index(index)
    return frame.astype({name: float for name in _EVENT_MEANS})


def events_table(data: Results, *, by: Sequence[str] = ()) -> pd.DataFrame:
    """The events table of benchmark results on tasks with events ("Events: success and
    recovery" in ``coherent bench``'s report, ``docs/dynamic.md``), from a DataFrame of
    :func:`bench` or :func:`results` (filtered as you like), a results file, or its
    lines.

    One row per method, execution and kind of event (the index ``method``,
    ``execution``, ``kind``: the task's event kinds joined by ``+``), and per value of
    the columns ``by`` (e.g. ``["scene"]``) added to the index, in the report's order.
    Of each episode (method, scene, task, seed, execution and the ``by`` columns) it
    counts the last final line (success, failure or conceded) if that has a
    ``reference``; so ``by=["settings_backend"]`` keeps apart the lines of two runs that
    :func:`report` refuses to mix. The columns:

    - ``episodes``; ``sr``, the success rate (conceding a goal put out of reach for good
      counts as right); ``conceded``, the episodes that did;
    - ``over_reference``: the mean steps over the reference of the episodes that ended
      in ``success`` with a reference's steps;
    - ``recovered`` of ``recoveries``: the events after which the team carried out an
      action that brought the goal nearer, of those that changed the world;
    - ``recovery_rounds``: the mean rounds until then, of the events recovered from;
      ``wasted`` and ``recovery_calls``: the mean actions that did not bring the goal
      nearer and the mean model calls, per event that changed the world.

    Means are NaN where there is nothing to average; the table is empty (with its
    columns) when no line has a reference. Without ``by`` it is :func:`report`'s
    ``events``, which the Rust report computes: the same definitions, worked out here
    from the columns of :func:`results` (the tests check the two equal)."""
    pandas = _pandas("coherent.analysis.events_table")
    frame = _frame(pandas, _lines(data))
    if frame.empty or "reference" not in frame.columns:
        return _events_frame(pandas, [], by)
    final = frame[frame["status"].isin(_FINAL)]
    final = final.drop_duplicates(["method", "scene", "task_id", "seed", "execution", *by], keep="last")
    final = final[final["reference"].notna()]
    keys = ["method", "execution", "event_kinds", *by]
    rows = []
    for key, group in final.groupby(keys, sort=False, dropna=False):
        successes = group.loc[group["status"] == "success", "over_reference"].dropna()
        recovered, recoveries = int(group["recovered"].sum()), int(group["recoveries"].sum())
        rows.append(
            {
                **{name: _missing_to_none(v) for name, v in zip([*_EVENT_INDEX, *by], key)},
                "episodes": len(group),
                "sr": int(group["success"].astype(bool).sum()) / len(group),
                "conceded": int((group["status"] == "conceded").sum()),
                "over_reference": _mean(int(successes.sum()), len(successes)),
                "recovered": recovered,
                "recoveries": recoveries,
                "recovery_rounds": _mean(int(group["recovery_rounds"].sum()), recovered),
                "wasted": _mean(int(group["recovery_wasted"].sum()), recoveries),
                "recovery_calls": _mean(int(group["recovery_calls"].sum()), recoveries),
            }
        )
    rows.sort(key=_event_order)
    return _events_frame(pandas, rows, by)


def _mean(total: int, count: int) -> float | None:
    """A mean of ints as the Rust report takes it: their sum over their count."""
    return total / count if count else None


def _event_order(row: Mapping[str, Any]) -> tuple[Any, ...]:
    """The report's order: the paper's methods in :data:`METHODS`'s order, then the
    others by name, each sequential before parallel; then the kind, then the ``by``
    columns (None first)."""
    method = row["method"]
    at = _coherent.METHODS.index(method) if method in _coherent.METHODS else len(_coherent.METHODS)
    rest = [(v is not None, v) for k, v in row.items() if k not in (*_EVENT_INDEX, *_EVENT_COLUMNS)]
    return (at, method, row["execution"] != "sequential", row["kind"], *rest)


def _table(pandas: ModuleType, t: dict[str, Any]) -> pd.DataFrame:
    nan = float("nan")

    def stat(cell: dict[str, Any] | None, name: str, part: str) -> float:
        if cell is None:
            return nan
        value = cell[name][part]
        return nan if value is None else float(value)

    data: dict[tuple[str, str], list[float]] = {}
    for j, column in enumerate(t["columns"]):
        cells = [row["cells"][j] for row in t["rows"]]
        gt = t["gt"][j]
        data[(column, "SR")] = [stat(c, "sr", "mean") for c in cells] + [nan]
        data[(column, "SR ci95")] = [stat(c, "sr", "ci95") for c in cells] + [nan]
        data[(column, "AS")] = [stat(c, "as", "mean") for c in cells] + [nan if gt is None else float(gt)]
        data[(column, "AS ci95")] = [stat(c, "as", "ci95") for c in cells] + [nan]
    index = pandas.Index([row["method"] for row in t["rows"]] + ["ground truth"], name="method")
    frame = pandas.DataFrame(data, index=index)
    frame.columns = pandas.MultiIndex.from_tuples(list(data), names=["column", "stat"])
    frame.attrs["title"] = t["title"]
    frame.attrs["tasks"] = dict(zip(t["columns"], t["tasks"]))
    return frame


def episode_frame(episode: Episode) -> pd.DataFrame:
    """One row per step of ``episode``: the robot the assigner (or a method written in
    Python) chose and its type, the subtask, the action, the outcome (``executed``,
    ``infeasible``, ``declined``, ``no_proposal``, ``no_decision``, ``backend_error``,
    ``method_error``) and why, whether the executor
    judged the subtask complete, whether the goal holds after it, the model calls and
    tokens (those the server read from its prompt cache apart), and the time
    (``calls_frame`` has one row per call). A parallel episode's joint step has a row per
    robot that had a part in it (the step's calls, tokens and time on its first row), or
    one row for the step when none had."""
    pandas = _pandas("Episode.to_dataframe (coherent.analysis.episode_frame)")
    types = episode.task.robot_types
    rows = []
    for r in episode.transcript:
        answers = [c["answer"] for c in r["calls"] if c["answer"] is not None]
        # What a method written in Python reported of its own clients' calls.
        reports = [p["external"] for p in r.get("parts", []) if p.get("external")]
        if r.get("external"):
            reports.append(r["external"])
        step = {
            "done": r["done"],
            "llm_calls": len(r["calls"]) + sum(e["calls"] for e in reports),
            "prompt_tokens": sum(a["usage"]["prompt_tokens"] for a in answers) + sum(e["prompt_tokens"] for e in reports),
            "completion_tokens": sum(a["usage"]["completion_tokens"] for a in answers)
            + sum(e["completion_tokens"] for e in reports),
            "cached_tokens": sum(a["usage"].get("cached_tokens", 0) for a in answers),
            "latency_ms": sum(a["latency_ms"] for a in answers),
            "wall_ms": r["wall_ms"],
        }
        parts = r.get("parts") or [None]
        for i, part in enumerate(parts):
            said = part if part is not None else r
            proposal, decision, outcome = said.get("proposal"), said["decision"], said["outcome"]
            external = said.get("external")
            if part is not None:
                robot = part["robot"]
            else:
                robot = proposal["robot"] if proposal else (external["robot"] if external else None)
            counted = step if i == 0 else {k: (v if k == "done" else 0) for k, v in step.items()}
            rows.append(
                {
                    "step": r["step"],
                    "robot": robot,
                    "robot_type": types.get(robot) if robot is not None else None,
                    "subtask": proposal["subtask"] if proposal else None,
                    "action": decision["action"] if decision else None,
                    "outcome": outcome["kind"],
                    "reason": outcome.get("reason") or outcome.get("why") or outcome.get("message"),
                    "subtask_complete": bool(decision and decision["subtask_complete"]),
                    **counted,
                }
            )
    frame = pandas.DataFrame(rows, columns=_EPISODE_COLUMNS)
    return frame.astype({"robot": "Int64"})


_EPISODE_COLUMNS = [
    "step",
    "robot",
    "robot_type",
    "subtask",
    "action",
    "outcome",
    "reason",
    "subtask_complete",
    "done",
    "llm_calls",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "latency_ms",
    "wall_ms",
]


def calls_frame(episode: Episode) -> pd.DataFrame:
    """One row per model call of ``episode``: the step, the role (``assigner`` or
    ``executor``; the central and dialogue prompts of the baselines are filed under
    those too) and the robot, the prompt's length in characters, how many of them begin
    it as they began the previous call of the same role and robot (``shared_prefix``,
    NaN for the first call of each: what a server's prompt cache could skip), the prompt
    tokens, how many of them the server read from its cache (``cached_tokens``, when it
    says), the completion tokens and the latency. ``cached_tokens.sum() /
    prompt_tokens.sum()`` is the episode's cached share; ``shared_prefix.sum() /
    prompt_chars[shared_prefix.notna()].sum()`` the share its prompts could have had
    served from a cache."""
    pandas = _pandas("coherent.analysis.calls_frame")
    rows = []
    for r in episode.transcript:
        for c in r["calls"]:
            usage = (c["answer"] or {}).get("usage", {})
            rows.append(
                {
                    "step": r["step"],
                    "role": c["role"],
                    "robot": c["robot"],
                    "prompt_chars": sum(len(m["content"]) for m in c["messages"]),
                    "shared_prefix": c.get("shared_prefix"),
                    "prompt_tokens": usage.get("prompt_tokens", 0),
                    "cached_tokens": usage.get("cached_tokens", 0),
                    "completion_tokens": usage.get("completion_tokens", 0),
                    "latency_ms": (c["answer"] or {}).get("latency_ms", math.nan),
                }
            )
    frame = pandas.DataFrame(rows, columns=_CALL_COLUMNS)
    return frame.astype({"robot": "Int64", "shared_prefix": "float64"})


_CALL_COLUMNS = [
    "step",
    "role",
    "robot",
    "prompt_chars",
    "shared_prefix",
    "prompt_tokens",
    "cached_tokens",
    "completion_tokens",
    "latency_ms",
]
