#!/usr/bin/env python3
"""Makespan-optimal plans of a set of tasks: `coherent plan FILE --parallel --json` on
each file given, summed up. The figures in docs/planner.md, "Parallel plans", come
from it.

    python3 scripts/measure-makespan.py target/release/coherent \\
        ../shared/coherent-original/env/env0.json ... native

Prints, as Markdown: how many tasks are solvable, how many makespans are proven optimal
within the default limits (and, for the others, the lower bound and the plan's
length), the planning time of both searches in all, the actions of the parallel plans
against the sequential optima, and how many tasks have each ratio of sequential steps
to joint steps. Exits 1 when a parallel plan is longer than the
sequential optimum, or a solvable task has no parallel plan.
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
import time


def plans(binary: str, source: str) -> list[dict]:
    out = subprocess.run(
        [binary, "plan", source, "--parallel", "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    # Exit 2 comes with malformed tasks in a file (env3 has one): the others still print.
    if out.returncode not in (0, 2):
        sys.exit(f"{source}: exit {out.returncode}: {out.stderr}")
    return [json.loads(line) for line in out.stdout.splitlines() if line.strip()]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("binary", help="the coherent executable")
    parser.add_argument("sources", nargs="+", help="task files, folders, or native")
    args = parser.parse_args()

    start = time.monotonic()
    lines = [line for source in args.sources for line in plans(args.binary, source)]
    wall = time.monotonic() - start
    solvable = [p for p in lines if p["solvable"]]
    bad = []
    for p in solvable:
        name = f"{p['scene']} task {p['task_id']}"
        if p["makespan"] is None:
            bad.append(f"{name}: no parallel plan")
        elif p["makespan"] > p["optimal_steps"]:
            bad.append(f"{name}: {p['makespan']} joint steps > {p['optimal_steps']} steps")
        elif len(p["parallel_plan"]) != p["makespan"]:
            bad.append(f"{name}: makespan {p['makespan']} but {len(p['parallel_plan'])} joint steps")
    proven = [p for p in solvable if p["makespan_proven"]]
    open_ = [p for p in solvable if not p["makespan_proven"]]
    ratios = collections.Counter(
        f"{p['optimal_steps'] / p['makespan']:.2f}" for p in solvable if p["makespan"]
    )
    sequential_ms = sum(p["elapsed_ms"] for p in lines)
    parallel_ms = sum(p.get("makespan_ms", 0.0) for p in lines)
    print(f"- {len(lines)} tasks planned, {len(solvable)} solvable")
    print(f"- makespan proven optimal: {len(proven)} of {len(solvable)}")
    for p in open_:
        print(
            f"  - {p['scene']} task {p['task_id']}: {p['makespan_lower']} to {p['makespan']} "
            f"joint steps (stopped at {p['makespan_stop']}; {p['optimal_steps']} sequential)"
        )
    print(
        f"- time: {sequential_ms / 1e3:.2f} s sequential search, {parallel_ms / 1e3:.2f} s "
        f"makespan search, {wall:.2f} s wall in all"
    )
    steps = sum(p["optimal_steps"] for p in solvable)
    joint = sum(p["makespan"] or 0 for p in solvable)
    print(f"- {steps} sequential steps, {joint} joint steps in all ({steps / max(joint, 1):.2f}x)")
    acted = sum(len(step) for p in solvable for step in p["parallel_plan"] or [])
    padded = [p for p in solvable if sum(len(s) for s in p["parallel_plan"] or []) > p["optimal_steps"]]
    print(
        f"- {acted} actions in the parallel plans ({acted - steps:+} against the sequential optima; "
        f"{len(padded)} plans with more actions than their sequential optimum)"
    )
    print()
    print("| sequential steps / makespan | tasks |")
    print("|---|---|")
    for ratio, n in sorted(ratios.items(), key=lambda kv: float(kv[0])):
        print(f"| {ratio} | {n} |")
    for line in bad:
        print(f"INVALID {line}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
