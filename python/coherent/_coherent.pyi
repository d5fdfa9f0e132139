"""Type stubs of the native module ``coherent._coherent`` (crates/coherent-py).

Names starting with ``_`` exist only here, to describe the dicts the module returns.
"""

import asyncio
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, NotRequired, TypeAlias, TypedDict, overload

__version__: str

METHODS: list[str]
"""The planning methods, in the paper's order: ``pefa``, ``pefa-no-history``, ``cmrs``,
``dmrs-1d``, ``dmrs-2d``, ``mcts``, ``llm-mcts``, ``optimal``."""

DEFAULT_MAX_STATES: int
"""The planner's bound on the states one search may visit when ``max_states`` is not
given (the command line's ``--max-states`` default)."""

_RobotType: TypeAlias = Literal["quadrotor", "robot dog", "robot arm"]
_TaskType: TypeAlias = Literal["mono", "dual", "trio"]
_Status: TypeAlias = Literal[
    "success", "failure", "backend_error", "interrupted", "error", "conceded"
]
_PathLike: TypeAlias = str | os.PathLike[str]
_Prompts: TypeAlias = _PathLike | Mapping[str, str]
"""A folder of prompt templates, ``"paper-layout"`` (the built-in templates in the paper's
layout), or ``{file name: text}`` (docs/prompts.md)."""

class _Price(TypedDict, total=False):
    input: float
    cached_input: float
    output: float
    date: str
    source: str

_Prices: TypeAlias = _PathLike | Mapping[str, _Price]
"""A price file (JSON, or TOML for ``.toml``), or ``{model: {"input", "cached_input",
"output"}}`` in USD per million tokens (docs/bench.md)."""

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
    # With parallel=True only: the fewest joint steps (docs/planner.md, "Parallel plans").
    makespan: NotRequired[int | None]
    makespan_proven: NotRequired[bool]
    makespan_lower: NotRequired[int]
    makespan_stop: NotRequired[Literal["states", "memory", "cancelled", "depth"] | None]
    parallel_plan: NotRequired[list[list[_PlanStep]] | None]
    makespan_states_expanded: NotRequired[int]
    makespan_ms: NotRequired[float]
    # With physics=True only: the plan carried out in Rapier (docs/physics.md).
    physics_ok: NotRequired[bool]
    physics_error: NotRequired[str | None]
    sim_seconds: NotRequired[float]
    physics_wall_ms: NotRequired[float]
    # With parallel=True and physics=True: the makespan plan carried out in Rapier.
    makespan_physics_ok: NotRequired[bool]
    makespan_physics_error: NotRequired[str | None]
    makespan_sim_seconds: NotRequired[float]
    makespan_physics_wall_ms: NotRequired[float]

class _Mention(TypedDict):
    name: str
    id: int

class _ParsedAction(TypedDict):
    verb: Literal["land_on", "movetowards", "takeoff_from", "open", "close", "grab", "putinto", "puton"]
    object: _Mention
    target: _Mention | None

class CoherentError(Exception):
    """Base class of every error raised by coherent; raised itself when coherent
    fails whatever the input (its async runtime cannot start: the process may
    open no more files or start no more threads; an episode's thread panicked)."""

class ArgumentError(CoherentError, ValueError):
    """An argument of the right type whose value cannot be used: an int out of range, a
    float that is not finite, text with a lone surrogate, an empty name, an unknown choice.
    The message names the argument and shows the value."""

class TaskFormatError(CoherentError, ValueError):
    """A task file or folder that cannot be read or does not follow its format."""

    file: str
    """The file (or folder) the error is about."""
    json_path: str | None
    """Where in the file, as ``$[0].init_graph.edges[3].to_id``; None when it could not be read."""

class UnknownRobotError(CoherentError):
    """A robot id that is not a robot of the task (an int beyond 64 bits included)."""

class ActionParseError(CoherentError, ValueError):
    """An action string that does not follow the grammar ``[verb] <name>(id)``, or a str
    that is not text (a lone surrogate)."""

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

class PromptError(CoherentError, ValueError):
    """A prompt template that cannot be used, raised before any model call."""

    file: str | None
    """The template file (``prompts/NAME`` for a dict of texts); None when the error is
    about no one file."""
    line: int | None
    """The line of an unknown placeholder (1-based); None for other errors."""
    placeholder: str | None
    """The unknown placeholder's name, as written between the braces."""

class MethodError(CoherentError):
    """A method written in Python raised an error during an episode (in its ``act``, or
    when it was made); the method's own exception is the ``__cause__``."""

    episode: Episode
    """The episode up to there (status ``"error"``; the transcript has the traceback)."""

class RobotError(CoherentError):
    """Robots over ROS 2 could not be reached (no action server for some of them within
    the wait, DDS could not start), or one stopped answering during an episode."""

    episode: Episode | None
    """The episode up to there (status ``"interrupted"``); None when no episode started."""

class DataFileError(CoherentError, ValueError):
    """A file of coherent's own formats other than tasks and prompt templates (a
    transcript, a results file, a price table, a subset list) that cannot be read or
    written, or does not follow its format."""

    file: str
    """The file the error is about."""
    line: int | None
    """The line the fault is on (1-based); None when it is not on one line."""

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
    def robot_names(self) -> dict[int, str]:
        """Robot node id -> its name (``"robot_dog_13"``): its ROS 2 name and its agent
        in ``coherent.marl``."""
    def most_actions(self, robot: int) -> int:
        """The most actions ``robot`` is ever offered at once (each of its type's verbs
        once per node): the size of a fixed action space."""
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
    """The environment of a task: robots observe and act, one action at a time or
    several robots at once in a joint step, by the rules, and with ``physics=True``
    also in Rapier (a physical failure is a refused step whose reason has the numbers;
    a scene that cannot be built raises :class:`PhysicsError`).

    With ``robots="ros2"`` the robots are ROS 2 action servers, one per robot at
    ``<namespace>/<robot>/execute`` (``coherent robots serve``, or real robots): the
    rules check each action, the robot carries it out, and the state follows its
    success. A joint step's goals are sent at once and awaited together. The
    constructor waits up to ``server_wait`` seconds for every robot's server and raises
    :class:`CoherentError` naming those without one; a step fails when a robot stays
    silent for ``robot_timeout`` seconds, and every later step is refused.

    The task's events (or those of ``events=``: a list, or a file, as for :func:`run`)
    happen as in an episode (docs/dynamic.md): each call of ``step`` is one step, and
    after it the events due before the next are carried out; ``news`` says what the team
    was told, ``robots`` is the team now. An action that a failing-actions event draws
    to fail does not run (``ok`` False, the episode's reason), the draws seeded by
    ``seed``. Robots over ROS 2 do not take events: a task with events raises
    :class:`ArgumentError` there; physics refuses a robot joining in a ``room`` with
    :class:`TaskFormatError`.

    Every method takes a robot by its node id and raises :class:`UnknownRobotError`
    for an id that is not one of the team's robots now (the task's, without those that
    went down or have not joined yet); an action str with a lone surrogate raises
    :class:`ActionParseError`.
    """

    def __init__(
        self,
        task: Task,
        physics: bool = False,
        *,
        robots: Literal["local", "ros2"] = "local",
        namespace: str | None = None,
        robot_timeout: float = 10.0,
        server_wait: float = 10.0,
        events: Sequence[dict[str, Any]] | dict[str, Any] | _PathLike | None = None,
        seed: int | None = 0,
    ) -> None: ...
    @property
    def task(self) -> Task: ...
    @property
    def physics(self) -> bool: ...
    @property
    def namespace(self) -> str | None:
        """The namespace of the robots' ROS 2 actions; None when they act in this process."""
    @property
    def robots(self) -> list[int]:
        """The team now: the task's robots without those that went down or have not
        joined yet."""
    @property
    def news(self) -> list[str]:
        """What the team was told before the coming step (empty when nothing happened)."""
    @property
    def steps(self) -> int:
        """The steps taken since the start or the last ``reset``: calls of ``step``."""
    @property
    def seed(self) -> int:
        """The seed of a failing-actions event's draws."""
    @property
    def goal(self) -> list[str]:
        """The goal predicates now, as ``Task.goal`` writes them (an event may change them)."""
    @property
    def instruction(self) -> str:
        """The instruction now (an event that changes the goal words it anew)."""
    def observe(self, robot: int) -> _Observation: ...
    def actions(self, robot: int) -> list[str]: ...
    def why_not(self, robot: int, action: str) -> str | None:
        """Why ``robot`` cannot do ``action`` now, by the rules, without doing it; None when
        it can."""
    @overload
    def step(self, robot: int, action: str) -> tuple[bool, str | None, bool]:
        """Tries ``action``: ``(ok, reason, done)``; an infeasible action gives ``ok`` False
        and the reason, and changes nothing."""
    @overload
    def step(
        self, robot: Mapping[int, str] | Sequence[tuple[int, str]], action: None = None
    ) -> tuple[list[bool], list[str | None], bool]:
        """``step(actions)``: one joint step, several robots at once, at most one action
        each (``{robot: action}`` or ``[(robot, action), ...]``): ``(oks, reasons,
        done)``, a list each in the order given. A step the rules refuse (an action not
        offered, two that interfere) carries out nothing; each reason says why."""
    def goal_satisfied(self) -> bool: ...
    def goal_holds(self) -> list[bool]:
        """Whether each goal predicate holds now, in the order of ``Env.goal`` (``Task.goal``
        unless an event changed the goal)."""
    def graph(self) -> _Graph: ...
    def reset(self, seed: int | None = None) -> None:
        """Back to the task's initial state, its events from the start; ``seed``, when
        given, seeds the failing actions' draws from now on."""

def load_tasks(path: _PathLike) -> list[Task]:
    """Every task at ``path``: an original env file, a native task file, or a folder."""

def read_tasks(path: _PathLike) -> tuple[list[Task], list[TaskFormatError]]:
    """Every well-formed task at ``path``, and an error for each malformed one; raises
    only when a file cannot be read or is not JSON."""

def benchmark_tasks(subset: Literal["40"] | None = None) -> list[Task]:
    """The project's own benchmark, compiled in: every task, or its 40-task subset."""

def plan(task: Task, max_states: int = ..., parallel: bool = False, physics: bool = False) -> _PlanResult:
    """Plans ``task`` optimally (one line of ``coherent plan --json``); with ``parallel``,
    also its fewest joint steps, robots acting at once (``coherent plan --parallel
    --json``: ``makespan``, ``makespan_proven``, ``makespan_lower``, ``parallel_plan``...);
    with ``physics``, carries the plan out in Rapier (``--physics``: ``physics_ok``,
    ``sim_seconds``...), and with both the makespan plan too, each joint step's robots
    moving at once (``makespan_physics_ok``, ``makespan_sim_seconds``...).
    Ctrl-C interrupts it and stops the search."""

def generate(
    tasks: int | None = None,
    *,
    seed: int | None = None,
    scenes: int | None = None,
    rooms: int | str | None = None,
    upstairs: float | None = None,
    closed: float | None = None,
    team: str | Mapping[str, int | str] | None = None,
    robots: int | str | None = None,
    predicates: int | str | None = None,
    type: str | Sequence[str] | None = None,
    needed: int | str | None = None,
    steps: int | str | None = None,
    ratio: float | str | None = None,
    proven: bool = False,
    physics: bool = False,
    max_states: int | None = None,
    max_memory: int | None = None,
    max_draws: int | None = None,
    split: str | Sequence[float] | None = None,
    jobs: int | None = None,
    out: str | os.PathLike[str] | None = None,
) -> list[tuple[Task, dict[str, Any]]]:
    """A generated task set (docs/generate.md), the same tasks as ``coherent generate``
    makes with the same knobs: a list of ``(task, manifest)``, ``manifest`` the task's
    line of ``manifest.jsonl`` (``id``, ``scene``, ``team``, ``type``, ``optimal_steps``,
    ``makespan``, its bounds, ``proven``, ``split``...). With ``out``, the folder is
    written too, byte for byte what the command writes. A knob left as None has the
    command's default (``tasks=100``, ``rooms="2-6"``, ``predicates="1-3"``,
    ``upstairs=0.25``, ``closed=0.35``, ``split="0.8,0.1,0.1"``, one thread per core);
    spans are an int or a str (``"2-6"``), ``team`` a str (``"quadrotor=2,legged=0-3"``)
    or a dict by kind. A knob out of range, or a request the draws cannot meet, raises
    ``ArgumentError`` naming the knob. Ctrl-C stops it; the folder then holds the tasks
    made so far, whole."""

def export_sft(
    files: Sequence[str | os.PathLike[str]],
    method: str,
    out: str | os.PathLike[str],
    *,
    execution: str | Sequence[str] | None = None,
    roles: Sequence[str] | None = None,
    sim_errors: str = "all=0.1",
    seeds: int = 2,
    history: int | None = None,
    prompts: str | os.PathLike[str] | Mapping[str, str] | None = None,
    split: tuple[float, float, float] = (0.8, 0.1, 0.1),
    include_eval: bool = False,
    max_states: int | None = None,
    command: str = "",
) -> dict[str, Any]:
    """The training data of ``coherent export sft`` written into ``out``, and its counts
    (``examples`` and ``by_role`` as dicts, ``tasks``, ``left_out_eval``, ``malformed``,
    ``no_answer``, ``duplicates``, ``conflicts``, ``unreadable``, ``files``); use
    ``coherent.training.dataset``."""

def pddl(task: Task) -> tuple[str, str]:
    """The task in PDDL (docs/pddl.md): ``(domain, problem)``, its rule set's domain and
    its problem, each naming the task and coherent's version. A task the domain cannot
    express exactly raises ``TaskFormatError`` with the reason."""

def check_pddl_plan(task: Task, text: str) -> dict[str, Any]:
    """Plays the PDDL plan ``text`` (a planner's output, one ``(action args...)`` a line)
    through ``task``'s rules: ``valid`` (every action allowed in turn and the goal holds
    after the last), ``length``, ``goal_reached``, ``failure`` (``(line, reason)`` of the
    first action refused, or None) and ``actions`` (the rules' actions up to it)."""

def budget(
    task: Task,
    execution: str = "sequential",
    max_steps: int | None = None,
    max_states: int = ...,
) -> int:
    """The step budget an episode of ``task`` gets in ``execution`` (``coherent run``,
    ``coherent.run``, ``coherent.gym`` and ``coherent.marl`` alike): ``max_steps`` when
    given, else twice the ground truth, else twice the optimum the planner finds; in joint
    steps (``"parallel"``) twice the makespan. Raises ``ArgumentError`` when there is no
    ground truth and no plan to size it by."""

def validate(task: Task, max_states: int = ...) -> list[str]:
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
    cached_tokens: int
    wall_ms: float
    error: str | None
    sim_seconds: NotRequired[float]
    # With events (docs/dynamic.md): the oracle's steps, why the goal is out of reach
    # for good, the optimum at the start and the recoveries.
    reference: NotRequired[dict[str, Any]]

class _BenchOutcome(TypedDict):
    # total = skipped + finished + unfinished
    total: int
    skipped: int
    written: int
    finished: int
    unfinished: int
    # Of the unfinished: ended in the method's own error; never started (Ctrl-C) or a
    # task that cannot run.
    method_errors: int
    not_started: int
    interrupted: bool
    skipped_tasks: list[str]
    repaired_bytes: int
    # Transcripts of episodes killed mid-run, renamed *.jsonl.unfinished before the run.
    orphaned: list[str]
    # The results file (the name the settings give when none was).
    out: str

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
    def chat(
        self,
        messages: str | Sequence[Mapping[str, str]],
        schema: Mapping[str, Any] | None = None,
        *,
        max_tokens: int = 400,
        role: Literal["assigner", "executor"] = "assigner",
        robot: int | None = None,
    ) -> Reply:
        """Asks the model through the project's client: ``messages`` are
        ``{"role", "content"}`` dicts (or one str, a user message); with ``schema`` (a JSON
        schema) the answer follows it, by the server's structured outputs or the client's
        fallbacks (check it). Timeouts, retries with backoff and ``Retry-After``, the key
        in no text; raises :class:`BackendError` when the server fails for good. Inside a
        method's ``act`` the call, its tokens and latency are filed in the step's round
        (``role`` and ``robot`` say whom it was for)."""
    def achat(
        self,
        messages: str | Sequence[Mapping[str, str]],
        schema: Mapping[str, Any] | None = None,
        *,
        max_tokens: int = 400,
        role: Literal["assigner", "executor"] = "assigner",
        robot: int | None = None,
    ) -> asyncio.Future[Reply]:
        """:meth:`chat`, to await in a coroutine (``reply = await llm.achat(...)``)."""

class Reply:
    """A model's answer to :meth:`LLM.chat`; ``str(reply)`` is its text."""

    @property
    def text(self) -> str: ...
    @property
    def prompt_tokens(self) -> int: ...
    @property
    def completion_tokens(self) -> int: ...
    @property
    def latency_ms(self) -> float:
        """From the request to the answer, retries included."""
    @property
    def attempts(self) -> int:
        """HTTP attempts it took (1 without retries)."""
    @property
    def finish(self) -> str:
        """``"stop"``, ``"length"`` (cut at ``max_tokens``), ``"refusal"``, ``"content_filter"``
        or the server's own word."""
    @property
    def refusal(self) -> str | None:
        """The model's words when it refused."""
    @property
    def format(self) -> Literal["json_schema", "json_object", "text"]:
        """The answer format asked for (a server that refuses a schema gets the next)."""

_History: TypeAlias = tuple[int | None, str | None, bool, str | None]

class View:
    """What a method written in Python is shown at each step (``act(view)``)."""

    @property
    def task(self) -> Task:
        """The episode's task (the object the method was made with)."""
    @property
    def step(self) -> int:
        """The step about to be taken, from 1."""
    @property
    def max_steps(self) -> int:
        """The step budget (2 x GT unless set; 2 x the fewest joint steps in parallel)."""
    @property
    def news(self) -> list[str]:
        """What happened since the last step that the team did not do (the task's events,
        docs/dynamic.md), a sentence each; empty without events."""
    @property
    def execution(self) -> Literal["sequential", "parallel"]:
        """``"parallel"``: ``act`` answers a list, one decision per robot that acts, all
        carried out at once as one joint step."""
    @property
    def robots(self) -> list[int]:
        """Node ids of the robots."""
    @property
    def robot_types(self) -> dict[int, _RobotType]: ...
    @property
    def actions(self) -> dict[int, list[str]]:
        """Each robot's action strings now."""
    @property
    def history(self) -> list[_History]:
        """Every earlier step, oldest first: ``(robot, action, ok, reason)``; robot and
        action None for a step without an action, reason None when it ran; of a parallel
        step, one for each robot given an action in it."""
    def observation(self, robot: int) -> _Observation:
        """What ``robot`` sees, as :meth:`Env.observe` gives it."""
    def observation_text(self, robot: int | None = None) -> str:
        """The observation of ``robot`` as facts, one per line, in one block (the paper's
        layout of the executors' prompts); with no robot, every robot's merged, as the
        assigner's and CMRS's prompts have it."""

class Decision:
    """A method's decision for one step; a ``(robot, action)`` tuple will do as well."""

    def __init__(
        self,
        robot: int | None,
        action: str | None,
        note: str = "",
        prompt_tokens: int = 0,
        completion_tokens: int = 0,
        calls: int = 0,
    ) -> None: ...
    @property
    def robot(self) -> int | None:
        """The robot that acts; None for no action this step (the step still counts)."""
    @property
    def action(self) -> str | None:
        """As written; one outside the robot's list is refused with the reason."""
    @property
    def note(self) -> str:
        """Your words about the step, kept in the transcript."""
    @property
    def prompt_tokens(self) -> int:
        """Tokens and calls of models asked through your own clients (calls through
        :class:`LLM` inside ``act`` are counted already)."""
    @property
    def completion_tokens(self) -> int: ...
    @property
    def calls(self) -> int: ...

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
    def cached_tokens(self) -> int:
        """The part of ``prompt_tokens`` the server read from its prompt cache."""
    @property
    def cost_usd(self) -> float | None:
        """What the model calls cost in USD at the price table given to :func:`run` or
        :func:`replay` (the built-in one for :func:`load_episode`); None without a price."""
    @property
    def wall_ms(self) -> float: ...
    @property
    def execution(self) -> Literal["sequential", "parallel"]: ...
    @property
    def makespan(self) -> int | None:
        """The joint steps it took to reach the goal (its steps); None when it did not."""
    @property
    def actions(self) -> int:
        """The actions carried out (several a step in a parallel episode)."""
    @property
    def sim_seconds(self) -> float | None:
        """The simulated seconds it took, with physics; None otherwise."""
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

_MethodFactory: TypeAlias = Callable[[Task], Any]

def run(
    task: Task,
    method: str | _MethodFactory = "pefa",
    *,
    execution: Literal["sequential", "parallel"] = "sequential",
    llm: LLM | None = None,
    sim_errors: str | Mapping[str, float] | None = None,
    history: int = 5,
    max_steps: int | None = None,
    physics: bool = False,
    seed: int | None = None,
    out: _PathLike = "runs",
    max_states: int = ...,
    prompts: _Prompts | None = None,
    prices: _Prices | None = None,
    robots: Literal["local", "ros2"] = "local",
    namespace: str | None = None,
    robot_timeout: float = 10.0,
    server_wait: float = 10.0,
    step_timeout: float | None = None,
    events: Sequence[dict[str, Any]] | dict[str, Any] | _PathLike | None = None,
) -> Episode:
    """Runs ``method`` on ``task`` as ``coherent run`` does; the transcript goes to
    ``out``. ``method`` is one of :data:`METHODS`, or a method written in Python: a class
    (or any callable) ``M``, made as ``M(task)``, whose ``act(view)`` (plain or ``async``)
    gives each step's :class:`Decision` or ``(robot, action)`` (``"MODULE:CLASS"`` loads
    one). Without ``llm`` the built-in planner plays the model's roles, or with
    ``sim_errors`` (``"all=0.1"``, or rates by kind) the simulated backend. ``prompts``
    replaces built-in templates (a bad one raises :class:`PromptError` before anything
    runs); ``prices`` adds to the built-in price table (``Episode.cost_usd``, the same as
    :func:`load_episode` gives for the transcript at the same prices). With
    ``robots="ros2"`` one ROS 2 action server per robot under ``namespace`` carries the
    actions out, as for :class:`Env`. ``execution="parallel"`` runs the robots in joint
    steps (the budget is 2 x the fewest joint steps; MCTS and LLM-MCTS are sequential
    only and raise :class:`ArgumentError`). Raises :class:`BackendError` when the server
    fails for good, :class:`MethodError` when the method raises or one of its steps
    (``M(task)`` and ``act``) takes longer than ``step_timeout`` seconds,
    :class:`RobotError` when a robot stops answering; Ctrl-C stops the episode, whatever
    ``act`` is doing, and raises ``KeyboardInterrupt``. ``events`` (a list of events, or
    the path of a JSON file of them) replaces the task's own: what happens mid-task that
    the team does not do (docs/dynamic.md); a bad one raises :class:`TaskFormatError`
    naming ``events=`` (or the file), the JSON path and the value."""

def replay(transcript: _PathLike, *, out: _PathLike = "runs", prices: _Prices | None = None) -> Episode:
    """Re-runs a transcript's episode answering from it (no network) with the prompt set
    it recorded; raises :class:`ReplayMismatchError` when a round comes out differently."""

def load_episode(path: _PathLike) -> Episode:
    """The finished episode recorded in a transcript file."""

def select(
    tasks: Sequence[Task], subset: Literal["all", "paper40", "native40"] | _PathLike | Sequence[tuple[str, int]]
) -> tuple[list[Task], list[tuple[str, int]]]:
    """The tasks a subset picks (``"paper40"``, a file of ``scene task_id`` lines, or
    pairs), in its order, and the pairs it names that are missing."""

def run_bench(
    tasks: Sequence[Task],
    methods: Sequence[str | _MethodFactory],
    *,
    execution: str | Sequence[str] = "sequential",
    backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
    sim_errors: str | Mapping[str, float] | None = None,
    replay_from: _PathLike | None = None,
    seeds: int = 1,
    concurrency: int = 4,
    history: int = 5,
    max_states: int = ...,
    max_steps: int | None = None,
    out: _PathLike | None = None,
    progress: Literal["bar", "lines"] | None = None,
    prompts: _Prompts | None = None,
    prices: _Prices | None = None,
    physics: bool = False,
    robots: Literal["local", "ros2"] = "local",
    namespace: str | None = None,
    robot_timeout: float = 10.0,
    server_wait: float = 10.0,
    step_timeout: float | None = None,
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
        methods: Sequence[str | _MethodFactory],
        *,
        seeds: int,
        out: _PathLike | None,
        execution: str | Sequence[str] = "sequential",
        backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
        sim_errors: str | Mapping[str, float] | None = None,
        replay_from: _PathLike | None = None,
        history: int = 5,
        max_states: int = ...,
        max_steps: int | None = None,
        physics: bool = False,
        progress: Literal["bar", "lines"] | None = None,
        prompts: _PathLike | Mapping[str, str] | None = None,
        prices: _PathLike | Mapping[str, Mapping[str, Any]] | None = None,
    ) -> None: ...
    @property
    def out(self) -> str:
        """The results file (the name the settings give when ``out`` was None)."""
    def pending(self) -> list[tuple[str, str, int, int, str]]:
        """The episodes to run: ``(method, scene, task_id, seed, execution)``."""
    def worker_settings(self) -> dict[str, Any]:
        """``prompts`` (the replaced templates by file name) and ``prices`` (the whole
        table) as data, for the workers."""
    def record(self, handed: tuple[str, str | None]) -> bool:
        """Writes what a worker handed back; False when that line was written already."""
    def finish(self, *, interrupted: bool, orphans: bool = False) -> _BenchOutcome:
        """Ends the run: what it did."""

class _BenchWorker:
    """Runs a run's episodes by key, as a Ray worker does (tasks as native task JSON)."""

    def __init__(
        self,
        tasks: Sequence[str],
        methods: Sequence[str | _MethodFactory],
        *,
        execution: str | Sequence[str] = "sequential",
        backend: Literal["builtin", "simulated", "replay"] | LLM | None = None,
        sim_errors: str | Mapping[str, float] | None = None,
        replay_from: _PathLike | None = None,
        history: int = 5,
        max_states: int = ...,
        max_steps: int | None = None,
        physics: bool = False,
        out: _PathLike,
        prompts: Mapping[str, str],
        prices: Mapping[str, Mapping[str, Any]],
        step_timeout: float | None = None,
    ) -> None: ...
    def run(self, key: tuple[str, str, int, int, str]) -> tuple[str, str | None]:
        """``("line", json)``, ``("skipped", why)`` or ``("not_started", None)``."""

def read_results(path: _PathLike, prices: _PathLike | Mapping[str, Mapping[str, Any]] | None = None) -> list[dict[str, Any]]:
    """The lines of a results file; a last line cut off mid-write is left out. With
    ``prices``, each ``cost_usd`` is the line's recorded tokens at those prices."""

def price_lines(lines: list[dict[str, Any]], prices: _PathLike | Mapping[str, Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Results lines with each ``cost_usd`` worked out anew from their tokens at ``prices``."""

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

def view_page(source_: Episode | _PathLike, other: Episode | _PathLike | None = None) -> str:
    """The HTML page of an episode (an :class:`Episode` or a transcript's path), of two
    side by side, or of a results file's index (``coherent.view`` wraps it). Raises
    :class:`DataFileError` for a file that cannot be read or does not follow its format,
    :class:`ArgumentError` for two episodes of different tasks or results where an
    episode belongs."""

def results_page(lines: list[dict[str, Any]], name: str) -> str:
    """The HTML index page of results lines, titled ``name``."""

def framed_page(html: str) -> str:
    """A page in a sandboxed ``<iframe srcdoc>``, as a notebook shows it inline."""
