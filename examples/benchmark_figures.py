"""Runs a 40-task subset with the built-in and the simulated backends and writes the
paper's figures as PNG files (``pip install '.[analysis]'`` brings matplotlib).

    python examples/benchmark_figures.py                    # the project's benchmark, 40 tasks
    python examples/benchmark_figures.py --tasks ../shared/coherent-original/env --subset paper40

Figures, in --out (default ``figures/``):

- ``<backend>-by-type.png`` and ``<backend>-by-scene.png``: success rate and average
  steps per method (the paper's Tables I and II), for ``builtin`` and ``simulated``;
- ``timeline.png``, ``tokens.png``, ``scene.png``: one simulated PEFA episode with
  mistakes in it: who acted at each step, the model calls and tokens per step, and the
  robots' paths in physics. With --base-url and --model, ``tokens.png`` is a short
  episode (--llm-steps) of that language model on the same task instead: the built-in
  and simulated backends report no tokens.
- ``storeys.png``, when a scene of the tasks has several storeys: the robots' paths in
  physics along the optimal plan of its task with the longest ground truth, a panel per
  storey.

The results files (``<backend>.jsonl`` in --out) are resumable: an interrupted run goes
on where it stopped, and a finished one only redraws the figures.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

import coherent  # noqa: E402
from coherent import plot  # noqa: E402

# The paper's rows: PEFA, its ablation, the baselines (the ground truth is a row of its own).
METHODS = "pefa,pefa-no-history,cmrs,dmrs-1d,dmrs-2d,mcts,llm-mcts"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", type=Path, help="task files or a folder (default: the project's benchmark)")
    parser.add_argument("--subset", default="paper40", help="with --tasks: all, paper40 or a file of `scene task_id` lines")
    parser.add_argument("--methods", default=METHODS, help="comma-separated methods")
    parser.add_argument("--sim-errors", default="all=0.1", help="the simulated backend's error rates")
    parser.add_argument("--seeds", type=int, default=3, help="seeds of the simulated backend")
    parser.add_argument("--concurrency", type=int, default=4)
    parser.add_argument("--out", type=Path, default=Path("figures"))
    parser.add_argument("--base-url", help="an OpenAI-compatible endpoint for tokens.png")
    parser.add_argument("--model", help="the model at --base-url")
    parser.add_argument("--llm-steps", type=int, default=8, help="step budget of the model's episode")
    args = parser.parse_args()

    if args.tasks is None:
        tasks = coherent.benchmark.tasks(subset="40")
    else:
        read, malformed = coherent.read_tasks(args.tasks)
        tasks, missing = coherent.select(read, args.subset)
        for error in malformed:
            print(f"skipped a malformed task: {error}")
        if missing:
            print(f"{len(missing)} tasks of the subset are not in {args.tasks}: {missing}")
    methods = args.methods.split(",")
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"{len(tasks)} tasks, methods {', '.join(methods)}")

    runs = {
        "builtin": coherent.bench(
            tasks, methods, backend="builtin", concurrency=args.concurrency, out=args.out / "builtin.jsonl", progress=True
        ),
        "simulated": coherent.bench(
            tasks,
            methods,
            backend="simulated",
            sim_errors=args.sim_errors,
            seeds=args.seeds,
            concurrency=args.concurrency,
            out=args.out / "simulated.jsonl",
            progress=True,
        ),
    }
    for backend, results in runs.items():
        report = coherent.report(results)
        print(report.markdown())
        for by in ("type", "scene"):
            fig = plot.table(report, by=by, title=f"{backend} backend, {'by task type' if by == 'type' else 'by scene'}")
            save(fig, args.out / f"{backend}-by-{by}.png")

    episode = telling_episode(runs["simulated"])
    fig, ax = plt.subplots(figsize=(10, 3.2), layout="constrained")
    save(plot.timeline(episode, ax=ax).figure, args.out / "timeline.png")
    if args.base_url:
        llm = coherent.LLM(base_url=args.base_url, model=args.model)
        tokens_of = coherent.run(episode.task, llm=llm, max_steps=args.llm_steps, out=args.out / "runs")
    else:
        tokens_of = episode
    fig, ax = plt.subplots(figsize=(10, 3.4), layout="constrained")
    save(plot.tokens(tokens_of, ax=ax).figure, args.out / "tokens.png")
    save(plot.scene(episode)[0].figure, args.out / "scene.png")
    storeyed = [t for t in tasks if len({room["level"] for room in coherent.scene_layout(t)["rooms"]}) > 1]
    if storeyed:
        longest = max(storeyed, key=lambda t: t.gt or 0)
        save(plot.scene(longest)[0].figure, args.out / "storeys.png")


def telling_episode(results: pd.DataFrame) -> coherent.Episode:
    """The successful PEFA episode of a trio task (else of any) that took the most steps
    beyond the ground truth: it shows the most in a timeline."""
    pefa = results[(results["method"] == "pefa") & results["success"]]
    trio = pefa[pefa["task_type"] == "trio"]
    chosen = trio if len(trio) else pefa
    best = chosen.assign(extra=chosen["steps"] - chosen["gt_steps"]).sort_values(["extra", "steps"]).iloc[-1]
    return coherent.load_episode(best["transcript"])


def save(fig: plt.Figure, path: Path) -> None:
    fig.savefig(path, dpi=130)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
