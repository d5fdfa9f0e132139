"""What one step of a method written in Python costs the harness, against a built-in
method's step: every solvable released task run by `optimal` (Rust) and by two Python
methods that follow the same plan, one with a plain `act` and one with an `async def act`;
then the median time of a step (a round's `wall_ms` in the transcripts: the view, the
call, the check and the transition, the record) of each.

    python examples/methods/step_cost.py [--tasks ../shared/coherent-original/env] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path
from typing import Any

import coherent


class FollowPlan:
    """A plain `act`: the plan's next step (the plan is made before the first step)."""

    name = "python-sync"

    def __init__(self, task: coherent.Task) -> None:
        self.plan = [(s["robot"], s["action"]) for s in coherent.plan(task)["plan"]]

    def act(self, view: coherent.View) -> tuple[int, str]:
        return self.plan[view.step - 1]


class FollowPlanAsync(FollowPlan):
    """The same, as a coroutine on the run's event loop."""

    name = "python-async"

    async def act(self, view: coherent.View) -> tuple[int, str]:  # type: ignore[override]
        return self.plan[view.step - 1]


def step_times(results: Any, method: str) -> list[float]:
    times = []
    for path in results[results["method"] == method]["transcript"]:
        for line in Path(path).read_text().splitlines():
            record = json.loads(line)
            if record["type"] == "round":
                times.append(record["wall_ms"])
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", default=str(Path(__file__).resolve().parents[3] / "shared/coherent-original/env"))
    parser.add_argument("--out", default=None, help="folder for the results (a temporary one by default)")
    args = parser.parse_args()
    tasks, _ = coherent.read_tasks(args.tasks)
    tasks = [t for t in tasks if coherent.plan(t)["solvable"]]
    out = Path(args.out or tempfile.mkdtemp(prefix="step-cost-")) / "results.jsonl"
    results = coherent.bench(tasks, ["optimal", FollowPlan, FollowPlanAsync], concurrency=1, out=out)
    assert results["success"].all(), "every method follows the optimal plan"
    print(f"{len(tasks)} tasks, concurrency 1; median (and 90th percentile) of one step's wall time:")
    for method in ("optimal", "python-sync", "python-async"):
        times = step_times(results, method)
        p90 = statistics.quantiles(times, n=10)[-1]
        print(f"  {method:13} {statistics.median(times) * 1e3:7.1f} us  ({p90 * 1e3:.1f} us)  over {len(times)} steps")


if __name__ == "__main__":
    main()
