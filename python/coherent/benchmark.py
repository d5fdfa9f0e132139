"""The project's own benchmark (``benchmark/`` in the repository), embedded in the
package: its scenes with geometry and their tasks."""

from __future__ import annotations

from typing import Literal

from . import _coherent
from ._coherent import Task


def tasks(subset: Literal["40"] | None = None) -> list[Task]:
    """Every task of the benchmark, or its 40-task subset with ``subset="40"``."""
    return _coherent.benchmark_tasks(subset)
