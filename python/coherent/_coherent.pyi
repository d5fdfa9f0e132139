"""Type stubs of the native module ``coherent._coherent`` (crates/coherent-py).

Names starting with ``_`` exist only here, to describe the dicts the module returns.
"""

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, TypeAlias, TypedDict

__version__: str

METHODS: list[str]
"""The planning methods, in the paper's order: ``pefa``, ``pefa-no-history``, ``cmrs``,
``dmrs-1d``, ``dmrs-2d``, ``mcts``, ``llm-mcts``, ``optimal``."""

_RobotType: TypeAlias = Literal["quadrotor", "robot dog", "robot arm"]
_TaskType: TypeAlias = Literal["mono", "dual", "trio"]
_Status: TypeAlias = Literal["success", "failure", "backend_error", "interrupted"]
_PathLike: TypeAlias = str | os.PathLike[str]

class _RawNode(TypedDict):
    id: int
    category: str
    class_name: str
    prefab_name: str
    properties: list[str]
    states: list[str]

_RawEdge = TypedDict("_RawEdge", {"from_id": int, "to_id": int, "relation_type": str})

class _Graph(TypedDict):
    nodes: list[_RawNode]
    edges: list[_RawEdge]

class _Observation(TypedDict):
    room: int | None
    nodes: list[_RawNode]
    edges: list[_RawEdge]

class _PlanStep(TypedDict):
    robot: int
    action: str

class _PlanResult(TypedDict):
    scene: str
    task_id: int
    gt_steps: int | None
    optimal_steps: int | None
    solvable: bool
    reason: str | None
    task_type: _TaskType | None
    plan: list[_PlanStep]
    states_expanded: int
    elapsed_ms: float

class _Mention(TypedDict):
    name: str
    id: int

class _ParsedAction(TypedDict):
    verb: Literal["land_on", "movetowards", "takeoff_from", "open", "close", "grab", "putinto", "puton"]
    object: _Mention
    target: _Mention | None

class CoherentError(Exception):
    """Base class of every error raised by coherent."""

class TaskFormatError(CoherentError, ValueError):
    """A task file or folder that cannot be read or does not follow its format."""

    file: str
    """The file (or folder) the error is about."""
    json_path: str | None
    """Where in the file, as ``$[0].init_graph.edges[3].to_id``; None when it could not be read."""

class UnknownRobotError(CoherentError):
    """A robot id that is not a robot of the task."""

class ActionParseError(CoherentError, ValueError):
    """An action string that does not follow the grammar ``[verb] <name>(id)``."""

    action: str
    reason: str

class PhysicsError(CoherentError):
    """The physical simulation cannot build a task's scene; the message says why."""

class BackendError(CoherentError):
    """The model's endpoint is misconfigured, or its server failed for good mid-episode."""

    episode: Episode | None
    """The episode up to the failure (its transcript is on disk); None when none started."""

class ReplayMismatchError(CoherentError):
    """A replayed episode did not come out as recorded."""

    episode: Episode
    """The replayed episode."""

class Task:
    """A task: the scene graph at the start, the robots, the goal and the ground truth.

    Immutable; get tasks from :func:`load_tasks`.
    """

    @property
    def scene(self) -> str: ...
    @property
    def task_id(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def instruction(self) -> str: ...
    @property
    def gt(self) -> int | None:
        """The ground truth's number of steps, when the task file gives one."""
    @property
    def type(self) -> _TaskType | None:
        """The fewest robot types that can reach the goal, by the optimal planner (searched
        on first use); None when it finds no plan."""
    @property
    def robots(self) -> list[int]:
        """Node ids of the robots."""
    @property
    def robot_types(self) -> dict[int, _RobotType]: ...
    @property
    def goal(self) -> list[str]:
        """Goal predicates as ``on_<apple>(3)_<table>(5)`` or ``inside_<a>(i)_<b>(j)``."""
    def to_native(self) -> dict[str, Any]:
        """The task as a native task file (a JSON object)."""
    def to_json(self, indent: bool = False) -> str:
        """The native task file's text."""
    def to_original(self) -> dict[str, Any]:
        """The task in the paper's format: one element of an env file's list."""

class Env:
    """The environment of a task: robots observe and act one action at a time, by the
    rules, and with ``physics=True`` also in Rapier (a physical failure is a refused
    step whose reason has the numbers; a scene that cannot be built raises
    :class:`PhysicsError`).

    Every method takes a robot by its node id and raises :class:`UnknownRobotError`
    for an id that is not one of the task's robots.
    """

    def __init__(self, task: Task, physics: bool = False) -> None: ...
    @property
    def task(self) -> Task: ...
    @property
    def physics(self) -> bool: ...
    @property
    def robots(self) -> list[int]: ...
    def observe(self, robot: int) -> _Observation: ...
    def actions(self, robot: int) -> list[str]: ...
    def why_not(self, robot: int, action: str) -> str | None:
        """Why ``robot`` cannot do ``action`` now, by the rules, without doing it; None when
        it can."""
    def step(self, robot: int, action: str) -> tuple[bool, str | None, bool]:
        """Tries ``action``: ``(ok, reason, done)``; an infeasible action gives ``ok`` False
        and the reason, and changes nothing."""
    def goal_satisfied(self) -> bool: ...
    def graph(self) -> _Graph: ...
    def reset(self) -> None: ...

def load_tasks(path: _PathLike) -> list[Task]:
    """Every task at ``path``: an original env file, a native task file, or a folder."""

def read_tasks(path: _PathLike) -> tuple[list[Task], list[TaskFormatError]]:
    """Every well-formed task at ``path``, and an error for each malformed one; raises
    only when a file cannot be read or is not JSON."""

def benchmark_tasks(subset: Literal["40"] | None = None) -> list[Task]:
    """The project's own benchmark, compiled in: every task, or its 40-task subset."""

def plan(task: Task, max_states: int = 5_000_000) -> _PlanResult:
    """Plans ``task`` optimally (one line of ``coherent plan --json``). Ctrl-C interrupts
    it and stops the search."""

def validate(task: Task, max_states: int = 5_000_000) -> list[str]:
    """Semantic problems of ``task``, in words; empty when it is clean."""

def parse_action(text: str) -> _ParsedAction:
    """Parses an action string; raises :class:`ActionParseError` when it is not one."""

def cli_main(argv: Sequence[str]) -> int:
    """Runs the ``coherent`` command line (``argv[0]`` is the program name); returns the
    exit status."""

class _Backend(TypedDict):
    kind: str
    model: str
    base_url: str | None

class _Summary(TypedDict):
    status: _Status
    success: bool
    steps: int
    gt_steps: int | None
    max_steps: int
    llm_calls: int
    prompt_tokens: int
    completion_tokens: int
    wall_ms: float
    error: str | None

class _BenchOutcome(TypedDict):
    total: int
    skipped: int
    written: int
    unfinished: int
    interrupted: bool
    skipped_tasks: list[str]
    repaired_bytes: int

class LLM:
    """An OpenAI-compatible endpoint (OpenAI, vLLM, Ollama, llama.cpp, LM Studio, ...).

    ``base_url`` may list several servers of the same model (a list, or a comma-separated
    str as ``OPENAI_BASE_URL`` takes): each request goes to the one with the fewest
    requests in flight, and one that fails rests while the others carry on; the
    transcript names the endpoint of each call (``docs/scale.md``).
    Arguments left out come from ``OPENAI_BASE_URL``, ``OPENAI_API_KEY`` and
    ``COHERENT_MODEL``; raises :class:`BackendError` when no endpoint or no model results.
    The key never appears in ``repr``, transcripts or logs, and cannot be read back. A
    response body longer than ``max_response_bytes`` is a failed call, read no further.
    """

    def __init__(
        self,
        base_url: str | Sequence[str] | None = None,
        model: str | None = None,
        api_key: str | None = None,
        *,
        temperature: float = 0.0,
        seed: int | None = None,
        format: Literal["json_schema", "json_object", "text"] = "json_schema",
        connect_timeout: float = 10.0,
        read_timeout: float = 120.0,
        timeout: float = 300.0,
        max_retries: int = 4,
        concurrency: int = 4,
        max_response_bytes: int = 4194304,
    ) -> None: ...
    @property
    def base_url(self) -> str:
        """The base URL; several comma-separated when several serve the model."""
    @property
    def base_urls(self) -> list[str]: ...
    @property
    def model(self) -> str: ...
    @property
    def has_api_key(self) -> bool: ...
    @property
    def temperature(self) -> float: ...
    @property
    def seed(self) -> int | None: ...

class Episode:
    """An episode as recorded in its transcript; from :func:`run`, :func:`replay` or
    :func:`load_episode`."""

    @property
    def task(self) -> Task: ...
    @property
    def method(self) -> str: ...
    @property
    def status(self) -> _Status: ...
    @property
    def success(self) -> bool: ...
    @property
    def steps(self) -> int: ...
    @property
    def gt_steps(self) -> int | None: ...
    @property
    def max_steps(self) -> int: ...
    @property
    def llm_calls(self) -> int: ...
    @property
    def prompt_tokens(self) -> int: ...
    @property
    def completion_tokens(self) -> int: ...
    @property
    def tokens(self) -> int:
        """Prompt and completion tokens together."""
    @property
    def wall_ms(self) -> float: ...
    @property
    def error(self) -> str | None: ...
    @property
    def backend(self) -> _Backend: ...
    @property
    def path(self) -> Path:
        """The transcript file."""
    @property
    def header(self) -> dict[str, Any]:
        """The transcript's first line: the task, the method, the settings."""
    @property
    def transcript(self) -> list[dict[str, Any]]:
        """One dict per round, as in the transcript file."""
    @property
    def summary(self) -> _Summary: ...
    def to_dataframe(self) -> Any:
        """One row per step (a pandas DataFrame; see ``coherent.analysis.episode_frame``)."""

def run(
    task: Task,
    method: str = "pefa",
    *,
    llm: LLM | None = None,
    sim_errors: str | Mapping[str, float] | None = None,
    history: int = 5,
    max_steps: int | None = None,
    physics: bool = False,
    seed: int | None = None,
    out: _PathLike = "runs",
    max_states: int = 5_000_000,
) -> Episode:
    """Runs ``method`` (one of :data:`METHODS`) on ``task`` as ``coherent run`` does; the
    transcript goes to ``out``. Without ``llm`` the built-in planner plays the model's
    roles, or with ``sim_errors`` (``"all=0.1"``, or rates by kind) the simulated backend.
    Raises :class:`BackendError` when the server fails for good; Ctrl-C stops the episode
    and raises ``KeyboardInterrupt``."""

def replay(transcript: _PathLike, *, out: _PathLike = "runs") -> Episode:
    """Re-runs a transcript's episode answering from it (no network); raises
    :class:`ReplayMismatchError` when a round comes out differently."""

def load_episode(path: _PathLike) -> Episode:
    """The finished episode recorded in a transcript file."""

def select(
    tasks: Sequence[Task], subset: Literal["all", "paper40", "native40"] | _PathLike | Sequence[tuple[str, int]]
) -> tuple[list[Task], list[tuple[str, int]]]:
    """The tasks a subset picks (``"paper40"``, a file of ``scene task_id`` lines, or
    pairs), in its order, and the pairs it names that are missing."""

def run_bench(
    tasks: Sequence[Task],
    methods: Sequence[str],
    *,
    backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
    sim_errors: str | Mapping[str, float] | None = None,
    replay_from: _PathLike | None = None,
    seeds: int = 1,
    concurrency: int = 4,
    history: int = 5,
    max_states: int = 5_000_000,
    out: _PathLike = "results.jsonl",
    progress: bool = False,
) -> _BenchOutcome:
    """The benchmark run behind ``coherent.bench`` (which returns the results as a
    DataFrame)."""

class _BenchLedger:
    """The driver's side of a benchmark run on other executors than the local one
    (``coherent.executors.RayExecutor``): checks the settings, opens and repairs the
    results file, knows the episodes still to run, writes each result once."""

    def __init__(
        self,
        tasks: Sequence[Task],
        methods: Sequence[str],
        *,
        seeds: int,
        out: _PathLike,
        backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
        sim_errors: str | Mapping[str, float] | None = None,
        replay_from: _PathLike | None = None,
        progress: bool = False,
    ) -> None: ...
    def pending(self) -> list[tuple[str, str, int, int]]:
        """The episodes to run: ``(method, scene, task_id, seed)``."""
    def record(self, handed: tuple[str, str | None]) -> bool:
        """Writes what a worker handed back; False when that line was written already."""
    def finish(self, *, interrupted: bool, orphans: bool = False) -> _BenchOutcome:
        """Ends the run: what it did."""

class _BenchWorker:
    """Runs a run's episodes by key, as a Ray worker does (tasks as native task JSON)."""

    def __init__(
        self,
        tasks: Sequence[str],
        *,
        backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
        sim_errors: str | Mapping[str, float] | None = None,
        replay_from: _PathLike | None = None,
        history: int = 5,
        max_states: int = 5_000_000,
        out: _PathLike,
    ) -> None: ...
    def run(self, key: tuple[str, str, int, int]) -> tuple[str, str | None]:
        """``("line", json)``, ``("skipped", why)`` or ``("not_started", None)``."""

def read_results(path: _PathLike) -> list[dict[str, Any]]:
    """The lines of a results file; a last line cut off mid-write is left out."""

def report_tables(lines: list[dict[str, Any]]) -> dict[str, Any]:
    """Tables I and II and the costs of results lines (``coherent bench --format json``)."""

def report_text(lines: list[dict[str, Any]], format: Literal["markdown", "csv", "json"] = "markdown") -> str:
    """The tables as ``coherent bench --report`` prints them."""

def scene_layout(task: Task) -> dict[str, Any]:
    """The scene's geometry (the native format's ``geometry`` object): ``rooms`` (each
    on its storey's ``level``), ``doors``, ``stairs`` (when any), ``items``, ``robots``;
    metres, ``[x, z]`` on the floor plan, ``y`` up."""

def robot_paths(source: Task | Episode) -> dict[int, list[tuple[float, float, float]]]:
    """Each mobile robot's ``(x, y, z)`` track in physics (``y`` up) along a task's
    optimal plan or an episode's executed actions."""

def render_svg(source: Task | Episode, *, paths: bool = True) -> str:
    """The scene from above as SVG (``coherent render``), with the robots' paths."""
