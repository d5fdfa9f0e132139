"""Type stubs of the native module ``coherent._coherent`` (crates/coherent-py).

Names starting with ``_`` exist only here, to describe the dicts the module returns.
"""

import os
from collections.abc import Sequence
from typing import Any, Literal, TypeAlias, TypedDict

__version__: str

_RobotType: TypeAlias = Literal["quadrotor", "robot dog", "robot arm"]

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
    task_type: Literal["mono", "dual", "trio"] | None
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
    def gt_steps(self) -> int | None: ...
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
    def step(self, robot: int, action: str) -> tuple[bool, str | None, bool]:
        """Tries ``action``: ``(ok, reason, done)``; an infeasible action gives ``ok`` False
        and the reason, and changes nothing."""
    def goal_satisfied(self) -> bool: ...
    def graph(self) -> _Graph: ...
    def reset(self) -> None: ...

def load_tasks(path: str | os.PathLike[str]) -> list[Task]:
    """Every task at ``path``: an original env file, a native task file, or a folder."""

def read_tasks(path: str | os.PathLike[str]) -> tuple[list[Task], list[TaskFormatError]]:
    """Every well-formed task at ``path``, and an error for each malformed one; raises
    only when a file cannot be read or is not JSON."""

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
