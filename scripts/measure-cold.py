#!/usr/bin/env python3
"""The README's two commands from a cold cache, timed, as a newcomer meets them.

Each command runs in a fresh clone of the given commit (an empty target folder), with the
compiler cache switched off (no RUSTC_WRAPPER, no sccache) and CARGO_HOME as it is (its
registry of downloaded sources, which the package registries would give anyway). The
clones sit beside a link named `shared` to the folder that holds coherent-original/, as
the tests expect (`../shared/coherent-original/env`).

    scripts/measure-cold.py --commit HEAD --shared ../shared --work /tmp/cold
    scripts/measure-cold.py --commit main --timings --skip test   # the ten costliest units

Writes one JSON object per command to `<work>/cold.jsonl` and a Markdown table to stdout:
wall time, CPU time, peak memory, exit status. `--timings` adds a cold
`cargo build --release -p coherent-py --timings` (the units the wheel compiles) and lists
its ten costliest units. Measure before and after a change in one session, on a machine
doing nothing else: the figures move with the machine's load.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def readme_commands(readme: Path) -> tuple[str, str]:
    """The README's opening commands: the install-and-run line and the test line."""
    text = readme.read_text()
    block = re.search(r"```sh\n(.*?)```", text, re.S)
    if block is None:
        raise SystemExit(f"{readme}: no ```sh block")
    lines = [line.strip() for line in block.group(1).splitlines() if line.strip() and not line.startswith("#")]
    if len(lines) != 2:
        raise SystemExit(f"{readme}: the first sh block holds {len(lines)} commands, not 2: {lines!r}")
    return lines[0], lines[1]


def cold_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("SCCACHE")}
    for name in ("RUSTC_WRAPPER", "CARGO_BUILD_RUSTC_WRAPPER", "CARGO_TARGET_DIR", "CARGO_BUILD_TARGET_DIR"):
        env.pop(name, None)
    return env


def clone(commit: str, work: Path, name: str) -> Path:
    dest = work / name
    if dest.exists():
        shutil.rmtree(dest)
    subprocess.run(["git", "clone", "--quiet", str(REPO), str(dest)], check=True)
    subprocess.run(["git", "-C", str(dest), "checkout", "--quiet", commit], check=True)
    return dest


def timed(command: str, cwd: Path, log: Path) -> dict:
    """`command` under /usr/bin/time -v; its output into `log`."""
    stats = log.with_suffix(".time")
    with log.open("w") as out:
        rc = subprocess.run(
            ["/usr/bin/time", "-v", "-o", str(stats), "bash", "-c", command],
            cwd=cwd, env=cold_env(), stdout=out, stderr=subprocess.STDOUT, check=False,
        ).returncode  # fmt: skip
    text = stats.read_text()

    def field(label: str) -> str:
        m = re.search(rf"{re.escape(label)}: (.+)", text)
        return m.group(1).strip() if m else ""

    wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss)")
    parts = [float(p) for p in wall.split(":")] if wall else [0.0]
    seconds = sum(p * 60**i for i, p in enumerate(reversed(parts)))
    return {
        "command": command,
        "exit": rc,
        "wall_s": round(seconds, 1),
        "cpu_s": round(float(field("User time (seconds)") or 0) + float(field("System time (seconds)") or 0), 1),
        "max_rss_mib": round(int(field("Maximum resident set size (kbytes)") or 0) / 1024),
        "log": str(log),
    }


def costliest_units(html: Path, n: int = 10) -> list[dict]:
    """The `n` units with the longest compile time in cargo's --timings report."""
    m = re.search(r"const UNIT_DATA = (\[.*?\]);\n", html.read_text(), re.S)
    if m is None:
        raise SystemExit(f"{html}: no UNIT_DATA (has cargo's --timings report changed?)")
    units = json.loads(m.group(1))
    units.sort(key=lambda u: u["duration"], reverse=True)
    return [
        {"unit": f"{u['name']} {u['version']}{' (' + u['target'].strip() + ')' if u['target'].strip() else ''}",
         "seconds": round(u["duration"], 1)}
        for u in units[:n]
    ]  # fmt: skip


def minutes(seconds: float) -> str:
    return f"{int(seconds // 60)} min {seconds % 60:04.1f} s"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commit", default="HEAD", help="what to clone and measure (default HEAD)")
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared",
                        help="the folder holding coherent-original/ (default ../shared)")  # fmt: skip
    parser.add_argument("--work", type=Path, required=True, help="where the clones go (emptied first)")
    parser.add_argument("--skip", action="append", choices=["install", "test"], default=[], help="a command not to run")
    parser.add_argument("--timings", action="store_true", help="also a cold release build of the wheel's units, timed per unit")
    args = parser.parse_args()

    if not (args.shared / "coherent-original").is_dir():
        raise SystemExit(f"{args.shared}: no coherent-original/ in it (--shared)")
    args.work.mkdir(parents=True, exist_ok=True)
    link = args.work / "shared"
    if not link.exists():
        link.symlink_to(args.shared.resolve())
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", args.commit], capture_output=True, text=True, check=True).stdout.strip()

    results = []
    for i, name in enumerate(("install", "test")):
        if name in args.skip:
            continue
        # The command as the measured commit's README says it.
        here = clone(commit, args.work, f"clone-{name}")
        command = readme_commands(here / "README.md")[i]
        r = {"step": name, "commit": commit, **timed(command, here, args.work / f"{name}.log")}
        results.append(r)
        print(f"{name}: {minutes(r['wall_s'])} (exit {r['exit']})", file=sys.stderr, flush=True)
    if args.timings:
        here = clone(commit, args.work, "clone-timings")
        r = {"step": "timings", "commit": commit,
             **timed("cargo build --release -p coherent-py --timings", here, args.work / "timings.log")}  # fmt: skip
        r["units"] = costliest_units(here / "target" / "cargo-timings" / "cargo-timing.html")
        results.append(r)

    with (args.work / "cold.jsonl").open("a") as f:
        for r in results:
            f.write(json.dumps(r) + "\n")
    print(f"Commit {commit[:12]}, cold cache.\n")
    print("| step | command | wall | CPU | peak memory | exit |\n|---|---|---|---|---|---|")
    for r in results:
        print(f"| {r['step']} | `{r['command']}` | {minutes(r['wall_s'])} | {r['cpu_s']:.0f} s | {r['max_rss_mib']} MiB | {r['exit']} |")
    for r in results:
        if "units" in r:
            print("\nThe ten costliest units of the wheel's release build:\n\n| unit | seconds |\n|---|---|")
            for u in r["units"]:
                print(f"| {u['unit']} | {u['seconds']} |")
    return 0 if all(r["exit"] == 0 for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
