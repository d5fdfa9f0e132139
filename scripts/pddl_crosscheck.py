#!/usr/bin/env python3
"""Two planners, one answer: every task's optimal plan checked by a PDDL plan validator,
and Fast Downward's optimal plan of the same task read back and checked by our rules
(docs/pddl.md, "The cross-check"). The figures of docs/pddl.md and the speed table of
docs/planner.md come from it.

    .venv/bin/python scripts/pddl_crosscheck.py .venv/bin/coherent \\
        ../shared/coherent-original/env/env*.json benchmark/tasks/s* --out crosscheck.jsonl

Each source is one scene: a released file, or one folder of our benchmark (task ids
repeat across our scenes).

For each task: `coherent export --format pddl --plans` writes the domain, the problem
and our optimal plan; unified-planning's plan validator checks our plan against the
domain and problem (a); Fast Downward (`up-fast-downward`, A* with h^max, admissible)
plans the problem, and `coherent plan --check` plays its plan through our rules (b).
Our planner and Fast Downward are timed in alternation, task by task, each proving its
plan optimal. Prints a Markdown summary; exits 1 on any disagreement.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path

# A* with h^max: admissible, so the first plan it finds is optimal. Fast Downward's LM-cut
# refuses the domain's conditional effects ("This configuration does not support
# conditional effects"); h^max supports them. On the largest tasks (three robots, tens of
# thousands of ground operators) h^max costs tens of milliseconds a state; `--search` runs
# another optimal search that takes conditional effects: A* with the admissible landmark
# heuristic, `astar(landmark_cost_partitioning(lm_rhw()))`, decided the three tasks h^max
# did not (docs/pddl.md); blind A* and merge-and-shrink did not.
SEARCH = "astar(hmax())"
# The driver's exit codes for "no plan exists" (translator or search proved it).
UNSOLVABLE = {10, 11}


def fast_downward() -> list[str]:
    """The command that runs Fast Downward's driver of the installed up-fast-downward."""
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("up-fast-downward is not installed: `make venv` installs it")
    driver = Path(spec.submodule_search_locations[0]) / "downward" / "fast-downward.py"
    return [sys.executable, str(driver)]


@dataclass
class Downward:
    """One run of Fast Downward on a problem."""

    length: int | None
    unsolvable: bool
    wall_s: float
    translate_s: float | None
    search_s: float | None
    expanded: int | None
    operators: int | None
    exit: int | None
    plan: Path | None
    timed_out: bool = False


def _number(pattern: str, log: str) -> float | None:
    m = re.search(pattern, log)
    return float(m.group(1)) if m else None


def run_downward(domain: Path, problem: Path, work: Path, timeout: float, search: str = SEARCH) -> Downward:
    """Fast Downward on one problem; after `timeout` seconds its driver and the
    translator or search it started are stopped together (their own process group)."""
    plan = work / (problem.stem + ".fd")
    start = time.monotonic()
    with subprocess.Popen(
        [*fast_downward(), "--plan-file", str(plan), str(domain), str(problem), "--search", search],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=work, start_new_session=True,
    ) as proc:  # fmt: skip
        try:
            log, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            return Downward(None, False, time.monotonic() - start, None, None, None, None, None, None, timed_out=True)
    wall = time.monotonic() - start
    length = _number(r"Plan length: (\d+) step", log)
    expanded = _number(r"Expanded (\d+) state", log)
    operators = _number(r"Translator operators: (\d+)", log)
    return Downward(
        length=int(length) if length is not None and proc.returncode == 0 else None,
        unsolvable=proc.returncode in UNSOLVABLE,
        wall_s=wall,
        translate_s=_number(r"Done! \[[\d.]+s CPU, ([\d.]+)s wall-clock\]", log),
        search_s=_number(r"Total time: ([\d.]+)s", log),
        expanded=int(expanded) if expanded is not None else None,
        operators=int(operators) if operators is not None else None,
        exit=proc.returncode,
        plan=plan if plan.is_file() else None,
    )


def validate(domain: Path, problem: Path, plan: Path) -> tuple[bool, str]:
    """unified-planning's sequential plan validator on `plan`."""
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import PlanValidator, get_environment

    get_environment().credits_stream = None
    reader = PDDLReader()
    with warnings.catch_warnings():
        # unified-planning 1.3.0's PDDL reader calls pyparsing's old names (parseString),
        # which pyparsing 3.3 deprecates; no other warning is silenced.
        warnings.filterwarnings("ignore", message=r"'\w+' deprecated - use '\w+'", category=DeprecationWarning)
        parsed = reader.parse_problem(str(domain), str(problem))
        actions = reader.parse_plan(parsed, str(plan))
    with PlanValidator(problem_kind=parsed.kind) as validator:
        result = validator.validate(parsed, actions)
    ok = result.status == ValidationResultStatus.VALID
    return ok, "; ".join(str(m.message) for m in result.log_messages or [])


@dataclass
class Result:
    source: str
    scene: str
    task_id: int
    task_type: str | None
    ours: int | None
    ours_ms: float
    validator: str = "-"
    downward: int | None = None
    downward_unsolvable: bool = False
    downward_s: float = 0.0
    downward_translate_s: float | None = None
    downward_search_s: float | None = None
    downward_expanded: int | None = None
    downward_operators: int | None = None
    read_back: str = "-"
    downward_timed_out: bool = False
    downward_search: str = SEARCH
    problems: list[str] = field(default_factory=list)


def our_plans(exe: str, source: str) -> list[dict]:
    out = subprocess.run([exe, "plan", source, "--json"], capture_output=True, text=True, check=False)
    if out.returncode not in (0, 2):
        raise RuntimeError(f"{source}: exit {out.returncode}: {out.stderr}")
    return [json.loads(line) for line in out.stdout.splitlines() if line.strip()]


def check_task(exe: str, source: str, planned: dict, work: Path, timeout: float, search: str = SEARCH) -> Result:
    """Both checks on one task, ours timed again just before Fast Downward runs."""
    tid = planned["task_id"]
    # Exit 1 for an unsolvable task, 2 when the file also holds a malformed one (env3.json):
    # the task's line is what counts.
    timed = subprocess.run(
        [exe, "plan", source, "--task", str(tid), "--json"], capture_output=True, text=True, check=False
    )
    lines = [line for line in timed.stdout.splitlines() if line.strip()]
    if not lines:
        raise RuntimeError(f"{source} task {tid}: exit {timed.returncode}, no plan line: {timed.stderr}")
    if len(lines) != 1:
        raise ValueError(
            f"{source} holds {len(lines)} tasks with id {tid} (several scenes): "
            "give each scene's file or folder as a source of its own"
        )
    ours = json.loads(lines[0])
    r = Result(source, ours["scene"], tid, ours["task_type"], ours["optimal_steps"], ours["elapsed_ms"])
    subprocess.run(
        [exe, "export", source, "--task", str(tid), "--format", "pddl", "--plans", "--out", str(work)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    problems = sorted(work.glob(f"*_task-{tid}.pddl"))
    domains = sorted(work.glob("domain-*.pddl"))
    if len(problems) != 1 or len(domains) != 1:
        r.problems.append(f"export wrote {len(problems)} problems and {len(domains)} domains")
        return r
    problem, domain = problems[0], domains[0]
    ours_plan = problem.with_suffix(".plan")
    if ours_plan.is_file():
        ok, why = validate(domain, problem, ours_plan)
        r.validator = "valid" if ok else f"invalid: {why}"
        if not ok:
            r.problems.append(f"our plan is not valid in PDDL: {why}")
    fd = run_downward(domain, problem, work, timeout, search)
    r.downward_search = search
    r.downward, r.downward_unsolvable, r.downward_s = fd.length, fd.unsolvable, fd.wall_s
    r.downward_translate_s, r.downward_search_s = fd.translate_s, fd.search_s
    r.downward_expanded, r.downward_operators = fd.expanded, fd.operators
    if fd.timed_out:
        # Undecided, not a disagreement: said apart in the summary.
        r.downward_timed_out = True
        return r
    if r.ours is None and not fd.unsolvable:
        r.problems.append(f"we find no plan; Fast Downward: exit {fd.exit}, length {fd.length}")
    if r.ours is not None and fd.length != r.ours:
        r.problems.append(f"optimal lengths differ: ours {r.ours}, Fast Downward {fd.length} (exit {fd.exit})")
    if fd.plan is not None:
        back = subprocess.run(
            [exe, "plan", source, "--task", str(tid), "--check", str(fd.plan), "--json"],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
        verdict = json.loads(back.stdout.splitlines()[0]) if back.stdout.strip() else {}
        r.read_back = "valid" if verdict.get("valid") else f"invalid: {verdict.get('failure')}"
        if not verdict.get("valid"):
            r.problems.append(f"Fast Downward's plan fails in our rules: {verdict.get('failure') or back.stderr}")
    return r


def table(results: list[Result]) -> str:
    """Median and slowest time per task, by type: ours against Fast Downward's whole run
    (its driver: translating, then searching) and against its search alone, with the
    median of the per-task ratios."""
    rows = ["| type | tasks | ours: median / slowest | Fast Downward: median / slowest | its search alone: median / slowest | median ratio: whole run / search |",
            "|---|---|---|---|---|---|"]  # fmt: skip
    for kind in ("mono", "dual", "trio"):
        of = [r for r in results if r.task_type == kind and r.ours is not None and not r.downward_timed_out]
        if not of:
            continue
        ours = [max(r.ours_ms / 1e3, 1e-6) for r in of]
        fd = [r.downward_s for r in of]
        search = [r.downward_search_s or 0.0 for r in of]
        whole = statistics.median(f / o for o, f in zip(ours, fd))
        alone = statistics.median(f / o for o, f in zip(ours, search))
        rows.append(
            f"| {kind} | {len(of)} | {statistics.median(ours) * 1e3:.1f} / {max(ours) * 1e3:.1f} ms | "
            f"{statistics.median(fd):.2f} / {max(fd):.2f} s | {statistics.median(search):.3f} / {max(search):.2f} s | "
            f"{whole:,.0f}x / {alone:,.0f}x |"
        )
    return "\n".join(rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("binary", help="the coherent executable")
    parser.add_argument("sources", nargs="+", help="task files or folders, one scene each")
    parser.add_argument("--out", type=Path, help="one JSON line per task")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds for one Fast Downward run")
    parser.add_argument("--search", default=SEARCH, help=f"Fast Downward's search, an optimal one (default {SEARCH})")
    parser.add_argument("--task", type=int, action="append", help="only this task id (repeatable)")
    args = parser.parse_args()

    results: list[Result] = []
    with tempfile.TemporaryDirectory() as tmp:
        for source in args.sources:
            for planned in our_plans(args.binary, source):
                if args.task and planned["task_id"] not in args.task:
                    continue
                work = Path(tmp) / f"{len(results)}"
                work.mkdir()
                r = check_task(args.binary, source, planned, work, args.timeout, args.search)
                results.append(r)
                print(f"{r.scene} {r.task_id} ({r.task_type}): ours {r.ours} in {r.ours_ms:.1f} ms; "
                      f"validator {r.validator}; Fast Downward {r.downward}{' (unsolvable)' if r.downward_unsolvable else ''} "
                      f"in {r.downward_s:.2f} s; read back {r.read_back}", file=sys.stderr, flush=True)  # fmt: skip
                if args.out:
                    with args.out.open("a") as f:
                        f.write(json.dumps(asdict(r)) + "\n")
    solvable = [r for r in results if r.ours is not None]
    agree = [r for r in solvable if not r.problems and not r.downward_timed_out]
    undecided = [r for r in results if r.downward_timed_out]
    unsolvable = [r for r in results if r.ours is None]
    print(f"{len(results)} tasks: {len(solvable)} solvable, {len(agree)} in full agreement "
          f"(our plan valid in PDDL, Fast Downward's as long and valid in our rules); "
          f"{sum(r.downward_unsolvable for r in unsolvable)} of {len(unsolvable)} unsolvable ones "
          f"unsolvable for Fast Downward too; {len(undecided)} where Fast Downward did not finish "
          f"in {args.timeout:.0f} s\n")  # fmt: skip
    print(table(results))
    for r in results:
        for p in r.problems:
            print(f"- {r.scene} task {r.task_id}: {p}")
    return 1 if any(r.problems for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
