"""The figures people put in papers, one call each (matplotlib; ``pip install
coherent[plot]``):

- :func:`table`: the paper's Table I (by task type) or Table II (by scene) as a
  figure: success rate and average steps per method, with 95% intervals over seeds and
  the ground truth;
- :func:`timeline`: which robot acted at each step of an episode, failed steps marked,
  subtask boundaries;
- :func:`tokens`: prompt and completion tokens (and model calls) per step;
- :func:`scene`: the scene from above with the robots' paths.

Each returns the matplotlib ``Figure`` (:func:`table`) or ``Axes`` (the others, drawn
into ``ax`` when given), to save with ``savefig`` or adjust further.
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING, Literal, Union

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator
from matplotlib.patches import Rectangle

from . import _coherent
from ._coherent import METHODS, Episode, Task
from .analysis import Report, Results, report

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ReportLike = Union[Report, Results]

_COLUMN_NAMES = {"mono": "Mono", "dual": "Dual", "trio": "Trio", "Avg": "Average"}
_ROBOT_MARKERS = {"quadrotor": "^", "robot dog": "s", "robot arm": "o"}
_FAILED = "#d62728"


def _method_color(method: str) -> str:
    # Fixed per method, so that figures of different runs agree.
    palette = plt.get_cmap("tab10").colors
    at = METHODS.index(method) if method in METHODS else len(METHODS)
    return palette[at % len(palette)]


def table(results: ReportLike, by: Literal["type", "scene"] = "type", *, title: str | None = None) -> Figure:
    """Success rate (left) and average steps (right) per method, by task type (Table I)
    or by scene (Table II), as grouped bars with the 95% interval over seeds as error
    bars (none with one seed); dashes mark the ground truth's average steps."""
    if by not in ("type", "scene"):
        raise ValueError(f'by={by!r}: expected "type" or "scene"')
    rep = results if isinstance(results, Report) else report(results)
    t = rep.table1 if by == "type" else rep.table2
    methods = [m for m in t.index if m != "ground truth"]
    columns = list(dict.fromkeys(t.columns.get_level_values("column")))
    tasks = t.attrs["tasks"]
    labels = [f"{_COLUMN_NAMES.get(c, c)}\n(n={tasks[c]})" for c in columns]
    x = np.arange(len(columns), dtype=float)
    width = 0.8 / max(len(methods), 1)
    fig, (ax_sr, ax_as) = plt.subplots(1, 2, figsize=(max(9.0, 2.4 * len(columns) + 3), 4.6), layout="constrained")
    for ax, stat in ((ax_sr, "SR"), (ax_as, "AS")):
        for i, method in enumerate(methods):
            means = t.loc[method, [(c, stat) for c in columns]].to_numpy(dtype=float)
            cis = t.loc[method, [(c, f"{stat} ci95") for c in columns]].to_numpy(dtype=float)
            at = x - 0.4 + width * (i + 0.5)
            shown = ~np.isnan(means)
            yerr = None
            if not np.isnan(cis).all():
                # Intervals are clipped to what the quantity can be: SR in [0, 1], AS >= 0.
                half = np.where(np.isnan(cis), 0.0, cis)
                top = 1.0 if stat == "SR" else np.inf
                yerr = np.array([np.minimum(half, means), np.minimum(half, top - means)])[:, shown]
            ax.bar(
                at[shown],
                means[shown],
                width * 0.92,
                yerr=yerr,
                capsize=2.5,
                color=_method_color(method),
                label=method,
                error_kw={"elinewidth": 0.9},
            )
        ax.set_xticks(x, labels)
        ax.grid(axis="y", alpha=0.3)
        ax.set_axisbelow(True)
    gt = t.loc["ground truth", [(c, "AS") for c in columns]].to_numpy(dtype=float)
    ax_as.hlines(gt, x - 0.42, x + 0.42, colors="black", linestyles="--", linewidth=1.2, label="ground truth")
    ax_sr.set_ylim(0, 1.05)
    ax_sr.set_ylabel("success rate (SR)")
    ax_sr.set_title("Success rate (higher is better)")
    ax_as.set_ylabel("average steps (AS)")
    ax_as.set_title("Average steps (lower is better; a failure counts 2 x GT + 1)")
    ax_as.title.set_fontsize(10)
    ax_sr.title.set_fontsize(10)
    handles, names = ax_as.get_legend_handles_labels()
    fig.legend(handles, names, loc="outside right center", frameon=False)
    seeds = len(rep.seeds)
    note = f"{seeds} seeds; error bars: 95% intervals over seeds" if seeds > 1 else "1 seed"
    backend = "; ".join(rep.backends) or "none (no method here asks a model)"
    heading = title or ("Table I: by task type" if by == "type" else "Table II: by scene")
    fig.suptitle(f"{heading}\n{note}; backend: {textwrap.shorten(backend, 110)}", fontsize=10)
    return fig


def _robot_label(task: Task, robot: int) -> str:
    return f"{task.robot_types[robot]} ({robot})"


def timeline(episode: Episode, ax: Axes | None = None) -> Axes:
    """Which robot the assigner chose at each step: a dot where its action ran, a red
    cross where it did not (infeasible, declined, or no usable answer; a step without
    a usable proposal sits on its own row), a star where the goal was reached, and
    thin lines between subtasks."""
    frame = episode.to_dataframe()
    task = episode.task
    robots = task.robots
    rows = {robot: i for i, robot in enumerate(robots)}
    none_row = len(robots)
    has_none = frame["robot"].isna().any()
    if ax is None:
        _, ax = plt.subplots(figsize=(max(6.0, 0.32 * len(frame) + 3), 0.55 * (len(robots) + has_none) + 1.8), layout="constrained")
    previous = None
    for step, robot, subtask, outcome, done in zip(
        frame["step"], frame["robot"].astype(object), frame["subtask"], frame["outcome"], frame["done"]
    ):
        robot = None if robot is None or robot is pd.NA else int(robot)
        if previous is not None and (robot, subtask) != previous:
            ax.axvline(step - 0.5, color="0.8", linewidth=0.8, zorder=0)
        previous = (robot, subtask)
        y = none_row if robot is None else rows[robot]
        if outcome == "executed":
            color = plt.get_cmap("tab10").colors[y % 10]
            ax.plot(step, y, "*" if done else "o", color=color, markersize=13 if done else 7, zorder=3)
        else:
            ax.plot(step, y, "x", color=_FAILED, markersize=8, markeredgewidth=2, zorder=3)
    names = [_robot_label(task, robot) for robot in robots] + (["no proposal"] if has_none else [])
    ax.set_yticks(range(len(names)), names)
    ax.set_ylim(-0.6, len(names) - 0.4)
    ax.invert_yaxis()
    if len(frame):
        ax.set_xlim(0.4, frame["step"].max() + 0.6)
    ax.set_xlabel("step")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(axis="y", alpha=0.25)
    legend = [
        Line2D([], [], marker="o", color="0.35", linestyle="", label="action ran"),
        Line2D([], [], marker="x", color=_FAILED, markeredgewidth=2, linestyle="", label="step failed"),
        Line2D([], [], marker="*", color="0.35", markersize=12, linestyle="", label="goal reached"),
        Line2D([], [], color="0.8", label="new subtask"),
    ]
    ax.legend(handles=legend, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=8)
    gt = "-" if episode.gt_steps is None else episode.gt_steps
    ax.set_title(
        f"{task.scene} task {task.task_id}, {episode.method}: {episode.status} in {episode.steps} steps (GT {gt})",
        fontsize=10,
    )
    return ax


def tokens(episode: Episode, ax: Axes | None = None) -> Axes:
    """Prompt and completion tokens per step (stacked bars), and the model calls per
    step (line, right axis). Backends that are not language models report no tokens."""
    frame = episode.to_dataframe()
    if ax is None:
        _, ax = plt.subplots(figsize=(max(6.0, 0.3 * len(frame) + 3), 3.6), layout="constrained")
    steps = frame["step"].to_numpy()
    prompt = frame["prompt_tokens"].to_numpy()
    completion = frame["completion_tokens"].to_numpy()
    ax.bar(steps, prompt, 0.7, color="#4c72b0", label="prompt tokens")
    ax.bar(steps, completion, 0.7, bottom=prompt, color="#dd8452", label="completion tokens")
    ax.set_xlabel("step")
    ax.set_ylabel("tokens")
    calls = ax.twinx()
    calls.plot(steps, frame["llm_calls"].to_numpy(), "o-", color="0.25", markersize=4, linewidth=1, label="model calls")
    calls.set_ylabel("model calls")
    calls.set_ylim(0, max(int(frame["llm_calls"].max()) if len(frame) else 1, 1) * 1.25)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    calls.yaxis.set_major_locator(MaxNLocator(integer=True))
    handles = ax.get_legend_handles_labels()[0] + calls.get_legend_handles_labels()[0]
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize=8, frameon=False)
    if len(frame) and not (prompt.sum() + completion.sum()):
        ax.text(0.5, 0.5, "this backend reports no tokens", transform=ax.transAxes, ha="center", color="0.4")
        ax.set_ylim(0, 1)
    model = episode.backend["model"] or episode.backend["kind"]
    ax.set_title(
        f"{episode.task.scene} task {episode.task.task_id}, {episode.method} ({textwrap.shorten(model, 40)}): "
        f"{episode.tokens} tokens in {episode.llm_calls} calls",
        fontsize=10,
    )
    return ax


def scene(source: Task | Episode, ax: Axes | None = None, *, paths: bool = True) -> Axes:
    """The scene from above: rooms, doors, furniture (grey, with names), objects (small
    orange squares), robots where they start; with ``paths``, each mobile robot's path
    in physics along the task's optimal plan or the episode's executed actions."""
    task = source.task if isinstance(source, Episode) else source
    layout = _coherent.scene_layout(task)
    nodes = {n["id"]: n for n in task.to_native()["graph"]["nodes"]}
    tracks = _coherent.robot_paths(source) if paths else {}
    lo = np.min([r["min"] for r in layout["rooms"]], axis=0)
    hi = np.max([r["max"] for r in layout["rooms"]], axis=0)
    if ax is None:
        span = hi - lo
        height = min(max(8.0 * span[1] / max(span[0], 1e-6), 3.5), 10.0)
        _, ax = plt.subplots(figsize=(9.0, height + 2.0), layout="constrained")
    for room in layout["rooms"]:
        (x0, z0), (x1, z1) = room["min"], room["max"]
        ax.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, facecolor="#f4f1ea", edgecolor="0.3", linewidth=1.5, zorder=0))
        name = nodes[room["id"]]["class_name"]
        ax.text(x0 + 0.12, z1 - 0.12, name, ha="left", va="top", fontsize=9, fontweight="bold", color="0.25")
    for door in layout["doors"]:
        (cx, cz), half = door["center"], door["width"] / 2
        xs, zs = ([cx - half, cx + half], [cz, cz]) if door["along_x"] else ([cx, cx], [cz - half, cz + half])
        ax.plot(xs, zs, color="#8c564b", linewidth=5, solid_capstyle="butt", zorder=1)

    def inside(x: float, z: float) -> bool:
        return bool(lo[0] <= x <= hi[0] and lo[1] <= z <= hi[1])

    # The goal's objects are named; other objects are only drawn, to keep labels apart.
    goal = {g["subject"] for g in task.to_native()["goal"]}
    named: list[tuple[float, float]] = []
    for item in sorted(layout["items"], key=lambda i: i["dynamic"]):
        x, _, z = item["pos"]
        w, _, d = item["size"]
        node = nodes.get(item["id"])
        if node is None or not inside(x, z) or node["category"] == "Floor":
            continue
        if item["dynamic"]:
            in_goal = item["id"] in goal
            ax.add_patch(
                Rectangle(
                    (x - w / 2, z - d / 2), w, d,
                    facecolor="#e4572e" if in_goal else "#ffb45c", edgecolor="#7a2a00", zorder=3,
                )
            )  # fmt: skip
            if in_goal:
                near = sum(1 for (a, b) in named if abs(a - x) < 1.2 and abs(b - z) < 0.4)
                named.append((x, z))
                ax.annotate(
                    node["class_name"], (x, z), xytext=(0, -5 - 9 * near), textcoords="offset points",
                    ha="center", va="top", fontsize=7, color="#7a2a00", fontweight="bold", zorder=7,
                    bbox={"boxstyle": "round,pad=0.1", "facecolor": "white", "edgecolor": "none", "alpha": 0.7},
                )  # fmt: skip
        else:
            ax.add_patch(Rectangle((x - w / 2, z - d / 2), w, d, facecolor="0.82", edgecolor="0.45", linewidth=0.8, zorder=2))
            ax.text(x, z + d / 2 - 0.05, node["class_name"], ha="center", va="top", fontsize=6.5, color="0.2", zorder=4)
    colors = plt.get_cmap("tab10").colors
    for i, robot in enumerate(task.robots):
        color = colors[i % len(colors)]
        kind = task.robot_types[robot]
        track = tracks.get(robot)
        if track:
            xs, zs = zip(*track)
            ax.plot(xs, zs, color=color, linewidth=2, alpha=0.85, zorder=5, gid=f"path {robot}")
            ax.plot(xs[-1], zs[-1], marker=_ROBOT_MARKERS[kind], color=color, markersize=9, markerfacecolor="white", markeredgewidth=2, zorder=6)
        start = next(r["pos"] for r in layout["robots"] if r["id"] == robot)
        ax.plot(start[0], start[2], marker=_ROBOT_MARKERS[kind], color=color, markersize=10, markeredgecolor="black", linestyle="", zorder=6, label=_robot_label(task, robot))
    ax.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
    ax.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    handles, names = ax.get_legend_handles_labels()
    if tracks:
        handles.append(Line2D([], [], color="0.3", linewidth=2, label="path (hollow: where it ends)"))
    handles.append(Rectangle((0, 0), 1, 1, facecolor="#e4572e", edgecolor="#7a2a00", label="object of the goal"))
    handles.append(Rectangle((0, 0), 1, 1, facecolor="#ffb45c", edgecolor="#7a2a00", label="other object"))
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=4, frameon=False, fontsize=8)
    what = "" if not paths else (" - paths of the episode" if isinstance(source, Episode) else " - paths of the optimal plan")
    ax.set_title("\n".join(textwrap.wrap(f"{task.scene} task {task.task_id}{what}: {task.instruction}", 90)), fontsize=10)
    return ax
