"""The figures people put in papers, one call each (matplotlib; ``pip install
'.[analysis]'`` from a checkout brings it):

- :func:`table`: the paper's Table I (by task type) or Table II (by scene) as a
  figure: success rate and average steps per method, with 95% intervals over seeds and
  the ground truth;
- :func:`timeline`: which robot acted at each step of an episode, failed steps marked,
  subtask boundaries, events (docs/dynamic.md) where they happened;
- :func:`tokens`: prompt and completion tokens (and model calls) per step;
- :func:`pareto`: success rate against cost per task, a point per method and model, the
  Pareto front drawn through the points no other beats on both;
- :func:`scene`: the scene from above, a panel per storey, with the robots' paths;
- :func:`recovery`: per kind of event and method, the success rate, the steps over the
  reference and how quickly the team recovered (the events table as a figure).

Each returns the matplotlib ``Figure`` (:func:`table`, :func:`recovery`), ``Axes``
(:func:`timeline`, :func:`tokens`, :func:`pareto`) or list of ``Axes``, one per storey
(:func:`scene`), drawn into ``ax`` when given, to save with ``savefig`` or adjust further.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from itertools import groupby
from typing import TYPE_CHECKING, Any, Literal, Union

from . import _coherent
from ._coherent import METHODS, ArgumentError, Episode, Task
from ._extras import needs
from .analysis import _FINAL, Report, Results, _frame, _lines, events_table, report

with needs("coherent.plot", "analysis"):
    import matplotlib.pyplot as plt
    import numpy as np
    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator
    from matplotlib.patches import Rectangle

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure
    from matplotlib.text import Text

ReportLike = Union[Report, Results]

_COLUMN_NAMES = {"mono": "Mono", "dual": "Dual", "trio": "Trio", "Avg": "Average"}
_ROBOT_MARKERS = {"quadrotor": "^", "robot dog": "s", "robot arm": "o"}
_FAILED = "#d62728"
_EVENT = "#9467bd"
# A white box behind a label that crosses lines and boxes.
_HALO = {"boxstyle": "round,pad=0.1", "facecolor": "white", "edgecolor": "none", "alpha": 0.7}


def _method_color(method: str) -> str:
    # Fixed per method, so that figures of different runs agree.
    palette = plt.get_cmap("tab10").colors
    at = METHODS.index(method) if method in METHODS else len(METHODS)
    return palette[at % len(palette)]


def table(results: ReportLike, by: Literal["type", "scene"] = "type", *, title: str | None = None) -> Figure:
    """Success rate (left, or above with more than four columns) and average steps per
    method, by task type (Table I) or by scene (Table II), as grouped bars with the 95%
    interval over seeds as error bars (none with one seed); dashes mark the ground
    truth's average steps."""
    if by not in ("type", "scene"):
        raise ArgumentError(f'by={by!r}: expected "type" or "scene"')
    rep = results if isinstance(results, Report) else report(results)
    t = rep.table1 if by == "type" else rep.table2
    methods = [m for m in t.index if m != "ground truth"]
    columns = list(dict.fromkeys(t.columns.get_level_values("column")))
    tasks = t.attrs["tasks"]
    labels = [f"{_COLUMN_NAMES.get(c, c)}\n(n={tasks[c]})" for c in columns]
    x = np.arange(len(columns), dtype=float)
    width = 0.8 / max(len(methods), 1)
    # Side by side; one above the other when there are many columns (scenes), to stay readable at page width.
    if len(columns) > 4:
        fig, (ax_sr, ax_as) = plt.subplots(2, 1, figsize=(max(9.0, 1.5 * len(columns) + 3), 7.8), layout="constrained")
    else:
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
    thin lines between subtasks. In an episode with events (docs/dynamic.md), a dashed
    line before the step each happened before, with its kind (``ends`` at the end of
    its span)."""
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
    if _mark_events(ax, episode):
        legend.append(Line2D([], [], color=_EVENT, linestyle="--", label="event"))
    ax.legend(handles=legend, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=8)
    gt = "-" if episode.gt_steps is None else episode.gt_steps
    ax.set_title(
        f"{task.scene} task {task.task_id}, {episode.method}: {episode.status} in {episode.steps} steps (GT {gt})",
        fontsize=10,
    )
    return ax


def _event_name(happened: dict[str, Any]) -> str:
    if happened.get("ended"):
        return f"{happened['kind']} ends"
    return f"{happened['kind']} (void)" if happened.get("void") else happened["kind"]


def _mark_events(ax: Axes, episode: Episode) -> int:
    """A dashed line before each step some event happened before (after the last one
    for those that left the goal holding, the summary's ``reference.closing``), named
    along it; returns how many lines."""
    at: dict[int, list[str]] = {}
    for r in episode.transcript:
        for happened in r.get("events", []):
            at.setdefault(r["step"], []).append(_event_name(happened))
    closing = (episode.summary.get("reference") or {}).get("closing", [])
    if closing:
        at.setdefault(episode.steps + 1, []).extend(_event_name(h) for h in closing)
    for step, names in at.items():
        ax.axvline(step - 0.5, color=_EVENT, linestyle="--", linewidth=1.2, zorder=1, gid=f"event {step}")
        ax.text(
            step - 0.45, 0.98, ", ".join(names), transform=ax.get_xaxis_transform(), rotation=90,
            ha="left", va="top", fontsize=7, color=_EVENT, zorder=4, bbox=_HALO,
        )  # fmt: skip
    return len(at)


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


def _cost_points(results: Results) -> tuple[pd.DataFrame, list[str]]:
    """One row per method, model and execution of the final results lines: ``label``,
    ``episodes``, ``success_rate``, ``cost_per_task`` (mean ``cost_usd``); and the labels
    of the groups left out because a line of theirs has no cost (its model has no
    price). The execution is in a label only when the results hold more than one."""
    columns = ["method", "model", "execution", "label", "episodes", "success_rate", "cost_per_task"]
    frame = _frame(pd, _lines(results))
    if frame.empty:
        return pd.DataFrame(columns=columns), []
    # A method that asks no model has no model to tell apart.
    model = frame["backend_model"].where(frame["uses_model"].astype(bool), "")
    execution = frame["execution"].fillna("sequential") if "execution" in frame else "sequential"
    frame = frame.assign(model=model.fillna(""), execution=execution)
    # As the report counts them: the last final line of each episode (conceding a goal
    # put out of reach counts as right), an episode being one per model and execution
    # too (results of several may sit in one frame).
    final = frame[frame["status"].isin(_FINAL)]
    final = final.drop_duplicates(["method", "model", "execution", "scene", "task_id", "seed"], keep="last")
    several = final["execution"].nunique() > 1
    rows, unpriced = [], []
    for (method, model, execution), group in final.groupby(["method", "model", "execution"], sort=False):
        words = [w for w in (model, execution if several else "") if w]
        label = f"{method} ({', '.join(words)})" if words else method
        costs = pd.to_numeric(group["cost_usd"], errors="coerce")
        if costs.isna().any():
            unpriced.append(label)
            continue
        rows.append(
            {
                "method": method,
                "model": model,
                "execution": execution,
                "label": label,
                "episodes": len(group),
                "success_rate": float(group["success"].astype(bool).mean()),
                "cost_per_task": float(costs.mean()),
            }
        )
    return pd.DataFrame(rows, columns=columns), unpriced


def pareto(results: Results, ax: Axes | None = None) -> Axes:
    """Success rate against cost per task (mean ``cost_usd`` per episode, USD), one point
    per method and model of ``results`` (a DataFrame of :func:`coherent.bench` or
    :func:`coherent.results`, a results file, or its lines), labelled; a step line joins
    the Pareto front, the points no other beats on both cost and success. Results lines
    get their cost from the price table given to ``bench`` (``prices=``); a method and
    model with a line that has none (a model without a price) is left out and named
    below the axes. Raises ``ValueError`` when no point is left."""
    points, unpriced = _cost_points(results)
    if points.empty:
        why = f" (no price for: {', '.join(unpriced)})" if unpriced else ""
        raise ValueError(f"no results line with a cost_usd to plot{why}: pass prices= to coherent.bench")
    if ax is None:
        _, ax = plt.subplots(figsize=(7.0, 4.8), layout="constrained")
    for row in points.itertuples():
        ax.scatter(row.cost_per_task, row.success_rate, s=50, color=_method_color(row.method), zorder=3)
        ax.annotate(row.label, (row.cost_per_task, row.success_rate), xytext=(5, 4), textcoords="offset points", fontsize=8)
    # The front: cheapest first, each point that succeeds more than every cheaper one.
    front, best = [], -1.0
    for row in points.sort_values(["cost_per_task", "success_rate"], ascending=[True, False]).itertuples():
        if row.success_rate > best:
            front.append((row.cost_per_task, row.success_rate))
            best = row.success_rate
    xs, ys = zip(*front)
    ax.step(xs, ys, where="post", color="0.5", linestyle="--", linewidth=1, zorder=2, label="Pareto front")
    ax.set_xlabel("cost per task (USD)")
    ax.set_ylabel("success rate")
    ax.set_ylim(-0.05, 1.08)
    ax.set_xlim(left=min(0.0, min(xs)))
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", frameon=False, fontsize=8)
    ax.set_title("Success rate against cost per task", fontsize=10)
    if unpriced:
        ax.text(
            0.0,
            -0.16,
            textwrap.shorten("no price, left out: " + ", ".join(unpriced), 120),
            transform=ax.transAxes,
            fontsize=8,
            color="0.4",
        )
    return ax


# The events table's columns `recovery` draws: the axis label and the panel's title.
_RECOVERY_STATS = {
    "sr": ("success rate", "Success rate (conceding counts; higher is better)"),
    "over_reference": ("steps over the reference", "Steps over the reference, successful episodes"),
    "recovery_rounds": ("rounds", "Rounds to recover, per event recovered from"),
    "wasted": ("wasted actions", "Actions wasted per event before recovering"),
    "recovery_calls": ("model calls", "Model calls per event spent recovering"),
}


def _bar_style(method: str, execution: str) -> dict[str, Any]:
    """A method's bars: its colour, hatched for its parallel episodes, and its row's name."""
    if execution == "parallel":
        return {"facecolor": _method_color(method), "hatch": "//", "edgecolor": "white", "label": f"{method} (parallel)"}
    return {"facecolor": _method_color(method), "label": method}


def recovery(
    results: ReportLike,
    stats: Sequence[str] = ("sr", "over_reference", "recovery_rounds", "wasted"),
    *,
    title: str | None = None,
) -> Figure:
    """The events table (:func:`coherent.analysis.events_table`, or a report's
    ``events``) as a figure: a panel per column of ``stats`` (of ``sr``,
    ``over_reference``, ``recovery_rounds``, ``wasted``, ``recovery_calls``), grouped
    bars by kind of event, a bar per method (a method's parallel episodes hatched); no
    bar where there is nothing to average (steps over the reference where every episode
    conceded). Raises ``ValueError`` when no results line has a reference (no task with
    events)."""
    unknown = [s for s in stats if s not in _RECOVERY_STATS]
    if unknown or not stats:
        raise ArgumentError(f"stats={list(stats)!r}: expected some of {', '.join(_RECOVERY_STATS)}")
    t = results.events if isinstance(results, Report) else events_table(results)
    if t.empty:
        raise ValueError("no results line with a reference to plot: run tasks with events (docs/dynamic.md)")
    rows = list(dict.fromkeys((method, execution) for method, execution, _ in t.index))
    kinds = sorted({kind for _, _, kind in t.index})
    x = np.arange(len(kinds), dtype=float)
    width = 0.8 / len(rows)
    labels = []
    for kind in kinds:
        # The episodes of the kind, when every method ran as many.
        counts = set(t.xs(kind, level="kind")["episodes"])
        labels.append(f"{kind}\n(n={counts.pop()})" if len(counts) == 1 else kind)
    across = len(stats) if len(stats) <= 2 else 2
    down = -(-len(stats) // across)
    wide = min(max(4.5, 0.16 * len(kinds) * len(rows) + 1.5), 9.0)
    size = (wide * across + 1.8, 3.3 * down + 0.9)
    fig, grid = plt.subplots(down, across, figsize=size, layout="constrained", squeeze=False)
    axes = list(grid.flat)
    for ax, stat in zip(axes, stats):
        for i, (method, execution) in enumerate(rows):
            values = np.array(
                [t.loc[(method, execution, k), stat] if (method, execution, k) in t.index else np.nan for k in kinds],
                dtype=float,
            )
            shown = ~np.isnan(values)
            at = x - 0.4 + width * (i + 0.5)
            ax.bar(at[shown], values[shown], width * 0.92, **_bar_style(method, execution))
            # A bar of 0 (the oracle's steps over the reference) is a line, not nothing.
            zero = values == 0
            left, right = (at - width * 0.46)[zero], (at + width * 0.46)[zero]
            ax.hlines(np.zeros(zero.sum()), left, right, colors=[_method_color(method)], linewidth=2.5)
        ylabel, heading = _RECOVERY_STATS[stat]
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_ylabel(ylabel)
        ax.set_title(heading, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
        ax.set_axisbelow(True)
        ax.axhline(0, color="0.3", linewidth=0.8, zorder=0)
        if stat == "sr":
            ax.set_ylim(0, 1.05)
    for ax in axes[len(stats) :]:
        ax.set_visible(False)
    # Drawn apart: a method may have no bar in the first panel.
    handles = [Rectangle((0, 0), 1, 1, **_bar_style(method, execution)) for method, execution in rows]
    fig.legend(handles=handles, loc="outside right center", frameon=False)
    note = "recovering: until the team's first action that brings the goal nearer (docs/dynamic.md)"
    fig.suptitle(f"{title or 'Events: success and recovery'}\n{note}", fontsize=10)
    return fig


def _level_at(rooms: list[dict[str, Any]], point: Sequence[float]) -> float | None:
    """The floor level of the storey ``point`` ``(x, y, z)`` is on, as ``coherent render``
    finds it: the highest room whose footprint holds the point and whose floor is not
    above it (by more than 5 cm); None outside every room."""
    x, y, z = point
    under = [
        r["level"]
        for r in rooms
        if r["min"][0] <= x <= r["max"][0] and r["min"][1] <= z <= r["max"][1] and r["level"] <= y + 0.05
    ]
    return max(under, default=None)


def scene(source: Task | Episode, ax: Axes | Sequence[Axes] | None = None, *, paths: bool = True) -> list[Axes]:
    """The scene from above, one panel per storey, lowest first (``coherent render``'s
    panels): rooms, doors, stairs, furniture (grey, with names), objects (small orange
    squares), robots where they start; with ``paths``, each mobile robot's path in
    physics along the task's optimal plan or the episode's executed actions, each stretch
    on the panel of the storey it is on. ``ax`` is one Axes per storey (a single Axes for
    a scene of one storey); returns the panels."""
    task = source.task if isinstance(source, Episode) else source
    layout = _coherent.scene_layout(task)
    nodes = {n["id"]: n for n in task.to_native()["graph"]["nodes"]}
    tracks = _coherent.robot_paths(source) if paths else {}
    rooms = layout["rooms"]
    levels = sorted({r["level"] for r in rooms})
    room_level = {r["id"]: r["level"] for r in rooms}
    lo = np.min([r["min"] for r in rooms], axis=0)
    hi = np.max([r["max"] for r in rooms], axis=0)
    if ax is None:
        span = hi - lo
        height = min(max(8.0 * span[1] / max(span[0], 1e-6), 3.5), 10.0)
        width = 9.0 if len(levels) == 1 else 8.0 * len(levels)
        _, grid = plt.subplots(1, len(levels), figsize=(width, height + 2.0), layout="constrained", squeeze=False)
        axes = list(grid[0])
    else:
        axes = [ax] if isinstance(ax, Axes) else list(ax)
        if len(axes) != len(levels):
            raise ArgumentError(f"{task.scene}: ax must be one Axes per storey ({len(levels)}), not {len(axes)}")

    def panel(level: float | None) -> int:
        # Outside every room (or on no storey) is the lowest storey's, as in `coherent render`.
        return levels.index(level) if level in levels else 0

    # Labels stay where they are drawn (`fixed`) or take the first free spot of theirs.
    fixed: list[Artist] = []
    movable: list[tuple[Text, list[tuple[float, float, str]]]] = []
    for room in rooms:
        (x0, z0), (x1, z1) = room["min"], room["max"]
        at = axes[panel(room["level"])]
        at.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, facecolor="#f4f1ea", edgecolor="0.3", linewidth=1.5, zorder=0))
        name = nodes[room["id"]]["class_name"]
        fixed.append(at.text(x0 + 0.12, z1 - 0.12, name, ha="left", va="top", fontsize=9, fontweight="bold", color="0.25"))
    for door in layout["doors"]:
        (cx, cz), half = door["center"], door["width"] / 2
        xs, zs = ([cx - half, cx + half], [cz, cz]) if door["along_x"] else ([cx, cx], [cz - half, cz + half])
        at = axes[panel(room_level.get(door["rooms"][0]))]
        at.plot(xs, zs, color="#8c564b", linewidth=5, solid_capstyle="butt", zorder=1)
    # A flight of stairs: its steps and an arrow up on the lower storey, the stairwell
    # dashed on the upper one; named beside it.
    for flight in layout.get("stairs", []):
        (fx, fz), (hx, hz), half = flight["foot"], flight["head"], flight["width"] / 2
        along_x = fx != hx
        x0, x1 = sorted((fx, hx)) if along_x else (fx - half, fx + half)
        z0, z1 = (fz - half, fz + half) if along_x else sorted((fz, hz))
        lower, upper = (room_level[r] for r in flight["rooms"])
        name = nodes[flight["id"]]["class_name"] if flight["id"] in nodes else "stairs"
        beside: dict[str, Any] = (
            {"x": (x0 + x1) / 2, "y": z1 + 0.1, "ha": "center", "va": "bottom"}
            if along_x
            else {"x": x1 + 0.1, "y": (z0 + z1) / 2, "ha": "left", "va": "center", "rotation": 90}
        )
        down, up = axes[panel(lower)], axes[panel(upper)]
        steps = "|" if along_x else "-"
        down.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, facecolor="0.88", edgecolor="0.3", hatch=steps, zorder=1))
        down.annotate("", (hx, hz), xytext=(fx, fz), arrowprops={"arrowstyle": "-|>", "color": "0.3"}, zorder=2)
        fixed.append(down.text(s=f"{name} up to {upper:.2f} m", fontsize=7, color="0.2", zorder=7, bbox=_HALO, **beside))
        up.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, fill=False, edgecolor="0.3", linestyle="--", zorder=1))
        fixed.append(up.text(s=f"{name} down to {lower:.2f} m", fontsize=7, color="0.2", zorder=7, bbox=_HALO, **beside))

    def inside(x: float, z: float) -> bool:
        return bool(lo[0] <= x <= hi[0] and lo[1] <= z <= hi[1])

    # The goal's objects are named; other objects are only drawn, to keep labels apart.
    goal = {g["subject"] for g in task.to_native()["goal"]}
    named: list[tuple[int, float, float]] = []
    for item in sorted(layout["items"], key=lambda i: i["dynamic"]):
        x, _, z = item["pos"]
        w, _, d = item["size"]
        node = nodes.get(item["id"])
        if node is None or not inside(x, z) or node["category"] == "Floor":
            continue
        k = panel(_level_at(rooms, item["pos"]))
        if item["dynamic"]:
            in_goal = item["id"] in goal
            fixed.append(axes[k].add_patch(
                Rectangle(
                    (x - w / 2, z - d / 2), w, d,
                    facecolor="#e4572e" if in_goal else "#ffb45c", edgecolor="#7a2a00", zorder=3,
                )
            ))  # fmt: skip
            if in_goal:
                near = sum(1 for (j, a, b) in named if j == k and abs(a - x) < 1.2 and abs(b - z) < 0.4)
                named.append((k, x, z))
                fixed.append(axes[k].annotate(
                    node["class_name"], (x, z), xytext=(0, -5 - 9 * near), textcoords="offset points",
                    ha="center", va="top", fontsize=7, color="#7a2a00", fontweight="bold", zorder=7, bbox=_HALO,
                ))  # fmt: skip
        else:
            axes[k].add_patch(Rectangle((x - w / 2, z - d / 2), w, d, facecolor="0.82", edgecolor="0.45", linewidth=0.8, zorder=2))
            # Inside the box at its top or bottom, or just outside it.
            label = axes[k].text(x, z, node["class_name"], ha="center", fontsize=6.5, color="0.2", zorder=7, bbox=_HALO)
            top, bottom = z + d / 2, z - d / 2
            spots = [(x, top - 0.05, "top"), (x, bottom + 0.05, "bottom"), (x, bottom - 0.05, "top"), (x, top + 0.05, "bottom")]
            movable.append((label, spots))
    colors = plt.get_cmap("tab10").colors
    legend: dict[str, Artist] = {}
    for i, robot in enumerate(task.robots):
        color = colors[i % len(colors)]
        kind = task.robot_types[robot]
        marker = _ROBOT_MARKERS[kind]
        # One line per stretch on a storey; the hollow marker where the last one ends.
        track = tracks.get(robot, [])
        stretches = [(k, list(points)) for k, points in groupby(track, key=lambda p: panel(_level_at(rooms, p)))]
        for k, points in stretches:
            xs, zs = [p[0] for p in points], [p[2] for p in points]
            axes[k].plot(xs, zs, color=color, linewidth=2, alpha=0.85, zorder=5, gid=f"path {robot}")
        if stretches:
            k, points = stretches[-1]
            x, _, z = points[-1]
            fixed += axes[k].plot(
                x, z, marker=marker, color=color, markersize=9, markerfacecolor="white", markeredgewidth=2, zorder=6
            )
        start = next(r["pos"] for r in layout["robots"] if r["id"] == robot)
        (mark,) = axes[panel(_level_at(rooms, start))].plot(
            start[0], start[2], marker=marker, color=color, markersize=10, markeredgecolor="black", linestyle="", zorder=6
        )
        legend[_robot_label(task, robot)] = mark
        fixed.append(mark)
    if tracks:
        legend["path (hollow: where it ends)"] = Line2D([], [], color="0.3", linewidth=2)
    legend["object of the goal"] = Rectangle((0, 0), 1, 1, facecolor="#e4572e", edgecolor="#7a2a00")
    legend["other object"] = Rectangle((0, 0), 1, 1, facecolor="#ffb45c", edgecolor="#7a2a00")
    for at in axes:
        at.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
        at.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
        at.set_aspect("equal")
        at.set_xlabel("x (m)")
        at.set_ylabel("z (m)")
    what = "" if not paths else (" - paths of the episode" if isinstance(source, Episode) else " - paths of the optimal plan")
    heading = f"{task.scene} task {task.task_id}{what}: {task.instruction}"
    key = {"handles": list(legend.values()), "labels": list(legend), "ncol": 4, "frameon": False, "fontsize": 8}
    if len(axes) == 1:
        axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.07), **key)
        axes[0].set_title("\n".join(textwrap.wrap(heading, 90)), fontsize=10)
    else:
        fig = axes[0].figure
        fig.legend(loc="outside lower center", **key)
        fig.suptitle("\n".join(textwrap.wrap(heading, 45 * len(axes))), fontsize=10)
        for at, level in zip(axes, levels):
            at.set_title(f"level {level:.2f} m", fontsize=10)
    _place_labels(axes[0].figure, fixed, movable)
    return axes


def _place_labels(fig: Figure, fixed: list[Artist], movable: list[tuple[Text, list[tuple[float, float, str]]]]) -> None:
    """Moves each label of ``movable`` to the first of its spots (x, y and vertical
    alignment, in its axes' data) where it overlaps neither the ``fixed`` artists nor
    the labels placed before it; to its first spot when none is free. Measured on the
    figure as it is laid out now."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    taken = [artist.get_window_extent(renderer) for artist in fixed]
    for label, spots in movable:
        for x, y, va in [*spots, spots[0]]:
            label.set_position((x, y))
            label.set_verticalalignment(va)
            box = label.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in taken):
                break
        taken.append(box)
