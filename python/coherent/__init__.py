"""coherent: plan and execute long-horizon tasks for heterogeneous robot teams (COHERENT).

Load tasks (the paper's original env files, native task files, or folders of them),
step a symbolic environment by hand, and plan optimally::

    import coherent

    task = coherent.load_tasks("env0.json")[0]
    result = coherent.plan(task)            # the shortest plan, its length, the task type
    env = coherent.Env(task)
    for step in result["plan"]:
        ok, reason, done = env.step(step["robot"], step["action"])

Everything here is implemented in Rust (``coherent._coherent``); errors derive from
:class:`CoherentError`.
"""

from ._coherent import (
    ActionParseError,
    CoherentError,
    Env,
    PhysicsError,
    Task,
    TaskFormatError,
    UnknownRobotError,
    __version__,
    cli_main,
    load_tasks,
    parse_action,
    plan,
    read_tasks,
    validate,
)

__all__ = [
    "ActionParseError",
    "CoherentError",
    "Env",
    "PhysicsError",
    "Task",
    "TaskFormatError",
    "UnknownRobotError",
    "__version__",
    "cli_main",
    "load_tasks",
    "parse_action",
    "plan",
    "read_tasks",
    "validate",
]
