"""The belief over time as a heat map (the paper's Fig. 7), readable in a report.

A *trace* is what one panel shows: a belief matrix (rows: intentions, or assembly states for the factored
model; columns: time, the initial belief first, then the belief after each step), the row followed by the
operator (the true intention in a simulation, the most probable one in a replayed session), and per step the
robot's action and the observation. The panel draws the belief on a log colour scale with a colour bar (low
probabilities stay visible; exact zeros are white), the followed row as steps (it changes between columns,
never inside one), and two strips above the time axis: the robot's actions (one triangle per action that is
not ``wait``) and the operator's observations (one dot per observation that is not ``blank``).

The drawing is split into small functions that return plain data (:func:`step_outline`, :func:`action_marks`,
:func:`observation_marks`, :func:`top_rows`) so tests check what is drawn, not pixels. Files: PNG at least
:data:`MIN_WIDTH_PX` wide and SVG, each written atomically; in the SVG the colour bar's axes has the id
``colorbar-P`` (panel P) and each robot action mark ``robot-action-P-K`` (step K), each observation mark
``observation-P-K``.

Cost: linear in rows x columns (one image per panel) plus the marks.
"""
from __future__ import annotations

import math
import os
import textwrap
from dataclasses import dataclass

import numpy as np

from ..errors import PlannerError
from ..files import save_figure

__all__ = ["LOG_FLOOR", "MAX_ROWS", "MIN_WIDTH_PX", "BeliefTrace", "action_marks", "belief_figure", "episode_trace",
           "observation_marks", "path_trace", "plot_beliefs", "short_action", "state_trace", "step_outline", "top_rows"]

MIN_WIDTH_PX = 1300  # the PNG's width: a report's full text width at 150 dpi and more
DPI = 100
LOG_FLOOR = 1e-4     # the colour scale's lower end; smaller non-zero probabilities take its colour
MAX_ROWS = 120       # rows drawn per panel; larger beliefs show the rows with the highest peaks
WAIT, BLANK = "wait", "blank"


@dataclass(frozen=True)
class BeliefTrace:
    """One panel: ``beliefs`` ``(rows, steps + 1)`` float (column 0 before the first step), ``line`` the row
    followed per column (``steps + 1`` ints, indices into the rows), ``actions`` and ``observations`` the
    names per step (``steps`` each), ``row_names`` the label of each row (``None``: its number)."""

    beliefs: np.ndarray
    line: list[int]
    actions: list[str]
    observations: list[str]
    title: str
    row_label: str = "intention"
    line_label: str = "true intention"
    note: str = ""
    row_names: list[str] | None = None


def step_outline(line: list[int]) -> tuple[list[float], list[float]]:
    """The followed row as a staircase: column ``k`` spans ``[k - 0.5, k + 0.5]`` at height ``line[k]`` and
    the row changes on the boundary between columns (a vertical segment), never diagonally. Returns the
    polyline's x and y; consecutive points share their x or their y. Cost: O(len(line))."""
    xs, ys = [], []
    for k, row in enumerate(line):
        xs += [k - 0.5, k + 0.5]
        ys += [float(row), float(row)]
    return xs, ys


def action_marks(trace: BeliefTrace) -> list[tuple[int, str]]:
    """``(column, action)`` for each step whose robot action is not ``wait``; the column is the one showing
    the belief after the step (step ``k`` -> column ``k``)."""
    return [(k, a) for k, a in enumerate(trace.actions, start=1) if a != WAIT]


def observation_marks(trace: BeliefTrace) -> list[tuple[int, str]]:
    """``(column, observation)`` for each step that observed something (not ``blank``)."""
    return [(k, z) for k, z in enumerate(trace.observations, start=1) if z != BLANK]


def top_rows(beliefs: np.ndarray, keep: int, always: list[int] = ()) -> np.ndarray:
    """The indices (sorted) of at most ``keep`` rows of ``beliefs``: those in ``always`` (the followed row),
    then the rows with the highest peak over time. Cost: O(rows x columns + rows log rows)."""
    peak = beliefs.max(axis=1)
    chosen = list(dict.fromkeys(int(r) for r in always))[:keep]
    for r in np.argsort(-peak, kind="stable"):
        if len(chosen) >= keep:
            break
        if int(r) not in chosen:
            chosen.append(int(r))
    return np.array(sorted(chosen), dtype=np.int64)


def _shrink(trace: BeliefTrace, keep: int, what: str) -> BeliefTrace:
    """``trace`` with at most ``keep`` rows (the followed ones and the highest peaks), saying so in its note."""
    n = trace.beliefs.shape[0]
    if n <= keep:
        return trace
    rows = top_rows(trace.beliefs, keep, trace.line)
    rest = np.delete(trace.beliefs, rows, axis=0)
    position = {int(r): k for k, r in enumerate(rows)}
    names = [trace.row_names[r] if trace.row_names else str(r) for r in rows]
    note = (f"{len(rows)} of {n:,} {what} shown (the followed one and the highest peaks); the others together "
            f"hold at most {float(rest.sum(axis=0).max()):.2g} at any step")
    return BeliefTrace(trace.beliefs[rows], [position[int(r)] for r in trace.line], trace.actions,
                       trace.observations, trace.title, trace.row_label, trace.line_label,
                       "; ".join(filter(None, [trace.note, note])), names)


def episode_trace(model, episode, title: str, line_label: str = "true intention") -> BeliefTrace:
    """The trace of an :class:`~planner.decision.simulate.Episode` (beliefs over intentions) on ``model`` (a
    ``POMDP`` or an ``IntentionModel``: anything with ``actions`` and ``observations`` names)."""
    return BeliefTrace(np.stack(episode.beliefs, axis=1), [episode.start] + [s.state for s in episode.steps],
                       [model.actions[s.action] for s in episode.steps],
                       [str(model.observations[s.observation]) for s in episode.steps], title,
                       line_label=line_label)


def state_trace(model, beliefs: list, line: list[int] | None, actions: list[int], observations: list[int],
                title: str) -> BeliefTrace:
    """The trace of beliefs over the factored model's classes, summed onto assembly states (a class is a
    state edge; its source is the current state, the final class the finished product): the figure a
    product with millions of intentions can show. ``line``: the true assembly state per column, or ``None``
    for the most probable one. Cost: O(classes) per column."""
    source = np.asarray(model.class_source).copy()
    source[model.final_class] = model.final_state
    n = model.plan.states.n_states
    grid = np.zeros((n, len(beliefs)))
    for k, belief in enumerate(beliefs):
        np.add.at(grid[:, k], source[belief.classes], belief.mass)
    followed = line if line is not None else [int(np.argmax(grid[:, k])) for k in range(grid.shape[1])]
    return BeliefTrace(grid, list(followed), [model.actions[a] for a in actions],
                       [str(model.observations[z]) for z in observations], title, row_label="assembly state",
                       line_label="true assembly state" if line is not None else "most probable assembly state",
                       note="belief summed over assembly states (the factored model: intentions are not "
                            "enumerated)")


def path_trace(model, episode, title: str) -> BeliefTrace:
    """The :func:`state_trace` of an :class:`~planner.decision.episode.Episode` on the factored model (its
    ``path``; the lumped model's policies too), the line following the true assembly state: the source of the
    path's class at each step's ``position``, the finished product after the last. Cost: O(classes) per step."""
    def state(position: int) -> int:
        path = episode.path
        return int(model.class_source[path[position]]) if position < len(path) else model.final_state

    return state_trace(model, episode.beliefs, [state(0)] + [state(s.position) for s in episode.steps],
                       [s.action for s in episode.steps], [s.observation for s in episode.steps], title)


def _colormap():
    import matplotlib

    return matplotlib.colormaps["viridis"].with_extremes(bad="white", under="#30123b")


def short_action(name: str) -> str:
    """The label of a robot action on the time axis: its number (``a1`` of ``a1:{ink}+{cap}``)."""
    return name.split(":", 1)[0]


def _ratios(note_lines: int) -> list[float]:
    """The heights of a panel's rows: robot strip, observation strip, heat map, notes."""
    return [0.45, 1.5, 5, 0.05 + 0.17 * note_lines]


def _note_lines(trace: BeliefTrace, width: int) -> list[str]:
    """The text under a panel: the key of the robot's actions, then the trace's note, wrapped."""
    key = dict(sorted({short_action(a): a for _, a in action_marks(trace)}.items()))
    under = ["robot actions: " + "; ".join(f"{k} = {v.split(':', 1)[-1]}" for k, v in key.items())] if key else []
    return [textwrap.fill(t, width) for t in under + ([trace.note] if trace.note else [])]


def _draw_panel(fig, spec, trace: BeliefTrace, panel: int, norm, cmap, width: int):
    """One panel in ``spec`` (a gridspec cell): the robot's actions and the observations in two strips on
    top, the heat map below, a key of the actions and the note under it; returns the image and its axes."""
    from matplotlib import patheffects
    from matplotlib.ticker import MaxNLocator

    under = _note_lines(trace, width)
    lines = sum(t.count("\n") + 1 for t in under)
    cells = spec.subgridspec(4, 1, height_ratios=_ratios(lines), hspace=0.04)
    robot_ax, seen_ax, ax = (fig.add_subplot(cells[k]) for k in range(3))
    robot_ax.sharex(ax)
    seen_ax.sharex(ax)
    note_ax = fig.add_subplot(cells[3])
    note_ax.axis("off")
    if under:
        note_ax.text(0.0, 0.0, "\n".join(under), transform=note_ax.transAxes, fontsize=7, va="bottom")
    columns = trace.beliefs.shape[1]
    image = ax.imshow(np.ma.masked_less_equal(trace.beliefs, 0), aspect="auto", cmap=cmap, norm=norm,
                      interpolation="nearest", origin="lower", extent=(-0.5, columns - 0.5, -0.5,
                                                                       trace.beliefs.shape[0] - 0.5))
    xs, ys = step_outline(trace.line)
    ax.plot(xs, ys, color="#ff3b30", linewidth=2.0, label=trace.line_label, solid_joinstyle="miter")
    actions = action_marks(trace)
    outline = [patheffects.withStroke(linewidth=2.2, foreground="black")]  # visible on light and dark cells
    for k, _ in actions:
        ax.axvline(k, color="white", linewidth=1.0, linestyle=(0, (3, 2)), path_effects=outline)
    ax.set_xlim(-0.5, columns - 0.5)
    ax.set_ylim(-0.5, trace.beliefs.shape[0] - 0.5)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("time step (0: before the first step; dashed: the robot acted)")
    ax.set_ylabel(trace.row_label)
    if trace.row_names:
        shown = range(0, len(trace.row_names), max(1, math.ceil(len(trace.row_names) / 30)))
        ax.set_yticks(list(shown), [trace.row_names[r] for r in shown], fontsize=7)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.85)
    _draw_strips(robot_ax, seen_ax, trace, actions, panel)
    robot_ax.set_title(textwrap.fill(trace.title, int(width * 0.85)), fontsize=9, loc="left")
    return image, ax


def _draw_strips(robot_ax, seen_ax, trace: BeliefTrace, actions: list[tuple[int, str]], panel: int) -> None:
    """The time axis' marks: a triangle per robot action (labelled with its number), a dot per observation
    (labelled upwards with its name)."""
    for ax, label in ((robot_ax, "robot acts"), (seen_ax, "observed")):
        ax.set_yticks([0], [label], fontsize=8)
        ax.tick_params(axis="x", labelbottom=False, bottom=False)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    robot_ax.set_ylim(-0.6, 1.0)
    seen_ax.set_ylim(-0.2, 1.0)
    for k, name in actions:
        robot_ax.plot([k], [0], marker="v", color="#d62728", markersize=8, linestyle="none",
                      gid=f"robot-action-{panel}-{k}")
        robot_ax.annotate(short_action(name), (k, 0), xytext=(5, -3), textcoords="offset points", fontsize=7,
                          color="#d62728")
    size = 7 if trace.beliefs.shape[1] <= 50 else 5
    for k, name in observation_marks(trace):
        seen_ax.plot([k], [0], marker="o", color="#1f77b4", markersize=5, linestyle="none",
                     gid=f"observation-{panel}-{k}")
        seen_ax.annotate(name, (k, 0), xytext=(0, 5), textcoords="offset points", fontsize=size, rotation=90,
                         ha="center", va="bottom", color="#1f4e79")


def belief_figure(traces: list[BeliefTrace], title: str = ""):
    """The matplotlib ``Figure`` of ``traces`` (one panel each, two per row) with one colour bar and the
    figure's ``title`` (the product's name); a trace with more than :data:`MAX_ROWS` rows shows the followed
    row and the highest peaks, and says so. :data:`MIN_WIDTH_PX` wide at :data:`DPI`."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure  # no pyplot: its backend and figures are process-wide state

    traces = [_shrink(t, MAX_ROWS, t.row_label + "s") for t in traces]
    columns = 1 if len(traces) == 1 else 2
    rows = math.ceil(len(traces) / columns)
    panel_height = max(6.0, 3.5 + 0.05 * max(t.beliefs.shape[0] for t in traces))
    fig = Figure(figsize=(MIN_WIDTH_PX / DPI, 0.6 + rows * panel_height), layout="constrained")
    norm, cmap = LogNorm(vmin=LOG_FLOOR, vmax=1.0, clip=False), _colormap()
    grid = fig.add_gridspec(rows, columns)
    width = 170 // columns  # characters per line of the notes under a panel
    drawn = [_draw_panel(fig, grid[k // columns, k % columns], trace, k, norm, cmap, width)
             for k, trace in enumerate(traces)]
    for k, (image, ax) in enumerate(drawn):
        # An inset beside each heat map: a bar taking space from the heat map would misalign it with the
        # strips above, and one bar for several gridspec cells collapses the layout when a row is not full.
        bar = fig.colorbar(image, cax=ax.inset_axes([1.015, 0.0, 0.018, 1.0]), extend="min", extendfrac=0.03)
        bar.set_label(f"belief, log scale (below {LOG_FLOOR:g}: lowest colour; zero: white)", fontsize=8)
        bar.ax.set_gid(f"colorbar-{k}")
    if title:
        fig.suptitle(title, fontsize=12)
    return fig


def plot_beliefs(traces: list[BeliefTrace], path_stem: str, title: str = "") -> list[str]:
    """:func:`belief_figure` written to ``path_stem.png`` and ``path_stem.svg``, each atomically, both or
    neither (a full disk or an interrupt between them removes the first); returns their paths."""
    if not traces:
        raise PlannerError("no episode to plot: play at least one sequence")
    fig = belief_figure(traces, title)
    written: list[str] = []
    try:
        for suffix in (".png", ".svg"):
            written.append(save_figure(fig, path_stem + suffix, dpi=DPI))
    except BaseException:
        for path in written:
            os.unlink(path)
        raise
    return written
