#!/usr/bin/env python3
"""Throughput of coherent.bench against a model server that answers after a fixed delay
(scripts/stub-openai.py), on the local executor and on a local Ray cluster: episodes and
model calls per second for each --concurrency, and the CPU the harness and the server
spent per call. The figures in docs/scale.md come from it.

    RAY_AUTH_MODE=token RAY_AUTH_TOKEN=$(openssl rand -hex 16) \\
        .venv/bin/python scripts/measure-scale.py --tasks ../shared/coherent-original/env

PEFA on the released tasks whose ground truth is 12 steps: every episode runs its whole
budget of 24 rounds (48 calls; the stub's answers keep the loop going but never reach a
goal), so that episodes started together end together and a run's calls per second is
its steady rate. Three waves of `concurrency` episodes each (at least 3 episodes).
`ideal` is the calls per second of `concurrency` requests always in flight. Prints a
Markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import coherent

HERE = Path(__file__).resolve().parent
TICK = os.sysconf("SC_CLK_TCK")


def start_stub(delay: float, slots: int) -> tuple[subprocess.Popen[str], str]:
    stub = subprocess.Popen(
        [sys.executable, str(HERE / "stub-openai.py"), "--port", "0", "--delay", str(delay), "--slots", str(slots)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert stub.stdout is not None
    line = stub.stdout.readline()
    match = re.search(r"(http://\S+)", line)
    if match is None:
        stub.kill()
        raise RuntimeError(f"the stub did not start: {line!r}")
    return stub, match.group(1)


def stop_stub(stub: subprocess.Popen[str]) -> dict[str, float]:
    stub.terminate()
    out, _ = stub.communicate(timeout=60)
    return json.loads(out.strip().splitlines()[-1])


class RunnerCpu:
    """CPU seconds of the Ray actors running episodes (processes titled
    `ray::EpisodeRunner` below this one), sampled until stopped: they end with the run."""

    def __init__(self) -> None:
        self.seconds: dict[int, float] = {}
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._sample, daemon=True)
        self.thread.start()

    def _sample(self) -> None:
        while not self.stop.wait(0.2):
            for pid in os.listdir("/proc"):
                if not pid.isdigit():
                    continue
                try:
                    if not Path(f"/proc/{pid}/cmdline").read_bytes().startswith(b"ray::EpisodeRunner"):
                        continue
                    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
                except OSError:
                    continue
                self.seconds[int(pid)] = (int(fields[11]) + int(fields[12])) / TICK

    def total(self) -> float:
        self.stop.set()
        self.thread.join()
        return sum(self.seconds.values())


def measure(tasks: list[coherent.Task], ray: bool, concurrency: int, delay: float, slots: int, folder: Path) -> dict[str, float]:
    episodes = 3 * concurrency
    seeds = -(-episodes // len(tasks))
    chosen = tasks[: min(len(tasks), episodes)]
    stub, url = start_stub(delay, slots)
    executor: str | coherent.RayExecutor = coherent.RayExecutor() if ray else "local"
    try:
        llm = coherent.LLM(base_url=url, model="stub", concurrency=concurrency)
        out = folder / f"{'ray' if ray else 'local'}-{concurrency}.jsonl"
        sampler = RunnerCpu() if ray else None
        before = resource.getrusage(resource.RUSAGE_SELF)
        start = time.perf_counter()
        frame = coherent.bench(chosen, ["pefa"], backend=llm, seeds=seeds, concurrency=concurrency, out=out, executor=executor)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_SELF)
        harness = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        if sampler is not None:
            harness += sampler.total()
    finally:
        served = stop_stub(stub)
    assert set(frame["status"]) <= {"success", "failure"}, set(frame["status"])
    calls = int(frame["llm_calls"].sum())
    return {
        "episodes": len(frame),
        "calls": calls,
        "wall_s": wall,
        "episodes_per_s": len(frame) / wall,
        "calls_per_s": calls / wall,
        "ideal_calls_per_s": min(concurrency, slots) / delay,
        "harness_cpu_ms_per_call": 1e3 * harness / calls,
        "server_cpu_ms_per_call": 1e3 * served["cpu_seconds"] / max(1, served["requests"]),
        "most_in_flight": served["most_in_flight"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tasks", default="../shared/coherent-original/env")
    parser.add_argument("--delay", type=float, default=0.2)
    parser.add_argument("--slots", type=int, default=4096, help="requests the stub serves at once")
    parser.add_argument("--concurrency", default="1,4,16,64")
    parser.add_argument("--executors", default="local,ray")
    parser.add_argument("--ray-cpus", type=int, default=2)
    args = parser.parse_args()
    all_tasks, _ = coherent.read_tasks(args.tasks)
    tasks = [t for t in all_tasks if t.gt == 12]
    levels = [int(c) for c in args.concurrency.split(",")]
    rows = []
    with tempfile.TemporaryDirectory(prefix="coherent-scale-") as tmp:
        for name in args.executors.split(","):
            if name == "ray":
                import ray

                ray.init(num_cpus=args.ray_cpus, include_dashboard=False, log_to_driver=False)
            for c in levels:
                r = measure(tasks, name == "ray", c, args.delay, args.slots, Path(tmp))
                rows.append((name, c, r))
                print(f"{name} concurrency {c}: {json.dumps(r)}", file=sys.stderr, flush=True)
    print(f"{time.strftime('%Y-%m-%d')}, {platform.machine()}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    print(
        "| executor | concurrency | episodes | calls | seconds | episodes/s | calls/s | ideal calls/s "
        "| harness CPU ms/call | server CPU ms/call |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, c, r in rows:
        print(
            f"| {name} | {c} | {r['episodes']} | {r['calls']} | {r['wall_s']:.1f} | {r['episodes_per_s']:.2f} | "
            f"{r['calls_per_s']:.1f} | {r['ideal_calls_per_s']:.0f} | {r['harness_cpu_ms_per_call']:.2f} | "
            f"{r['server_cpu_ms_per_call']:.2f} |"
        )


if __name__ == "__main__":
    main()
