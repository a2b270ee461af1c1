"""The Fig. 7 belief heat map (planner.decision.belief_plot): what it draws, checked as data, and its files."""
from __future__ import annotations

import io
import re
import struct
import subprocess
import sys
import warnings

import numpy as np
import pytest
from figure_support import pyplot_untouched

from planner import make_plan
from planner.decision import intention_model
from planner.decision.belief_plot import (
    LOG_FLOOR,
    MAX_ROWS,
    MIN_WIDTH_PX,
    BeliefTrace,
    action_marks,
    belief_figure,
    episode_trace,
    observation_marks,
    plot_beliefs,
    state_trace,
    step_outline,
    top_rows,
)
from planner.decision.factored_model import factored_model
from planner.decision.factored_simulate import PathWorld
from planner.decision.online import OnlinePlanner
from planner.decision.policy import AlphaVectorPolicy
from planner.decision.simulate import IntentionWorld, simulate_episode
from planner.errors import PlannerError


@pytest.fixture(scope="module")
def decision(pen):
    return intention_model(make_plan(pen))


@pytest.fixture(scope="module")
def episode(decision):
    """Sequence 57 of the pen against a policy written by hand: wait, except the cap's operation (a1) once the
    belief puts any mass on intention 2 (the one whose next step it is); the operator takes turns."""
    model = decision.pomdp
    a1 = next(k for k, name in enumerate(model.actions) if name.startswith("a1:"))
    alphas = np.zeros((2, model.n_states))
    alphas[1, 2] = 1.0
    policy = AlphaVectorPolicy(alphas, np.array([model.actions.index("wait"), a1]))
    return simulate_episode(IntentionWorld(model, 57, decision.graph.successor, decision.final_state), policy,
                            np.random.default_rng(0), operator="turns")


def _png_size(path) -> tuple[int, int]:
    with open(path, "rb") as handle:
        data = handle.read(24)
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_the_true_intention_is_drawn_as_steps():
    line = [57, 57, 33, 15, 15, 6, 0]
    xs, ys = step_outline(line)
    assert len(xs) == 2 * len(line)
    for (x0, y0), (x1, y1) in zip(zip(xs, ys), zip(xs[1:], ys[1:])):
        assert x0 == x1 or y0 == y1  # horizontal or vertical: never a diagonal
    assert xs[0] == -0.5 and xs[-1] == len(line) - 0.5  # the first and last columns whole
    for k, row in enumerate(line):  # column k spans [k - 0.5, k + 0.5] at its row
        assert (xs[2 * k], xs[2 * k + 1], ys[2 * k], ys[2 * k + 1]) == (k - 0.5, k + 0.5, row, row)


def test_marks_on_the_time_axis():
    trace = BeliefTrace(np.full((3, 5), 1 / 3), [0, 0, 1, 2, 2], ["wait", "a1:{x}+{y}", "wait", "a0:{x,y}+{z}"],
                        ["blank", "x", "blank", "z+[hammer]"], "t")
    assert action_marks(trace) == [(2, "a1:{x}+{y}"), (4, "a0:{x,y}+{z}")]  # step k -> column k
    assert observation_marks(trace) == [(2, "x"), (4, "z+[hammer]")]


def test_top_rows_keep_the_followed_row_and_the_highest_peaks():
    rng = np.random.default_rng(3)
    beliefs = rng.random((40, 6))
    kept = top_rows(beliefs, 10, [7])
    peaks = beliefs.max(axis=1)
    others = sorted(set(range(40)) - {7}, key=lambda r: -peaks[r])[:9]  # brute force
    assert kept.tolist() == sorted({7, *others})


def test_the_pen_figure(tmp_path, decision, episode, monkeypatch):
    trace = episode_trace(decision, episode, "sequence 57")
    assert trace.beliefs.shape == (decision.pomdp.n_states, len(episode.steps) + 1)
    assert trace.line[0] == 57 and trace.line[-1] == decision.final_state
    robot = [s for s in episode.steps if decision.actions[s.action] != "wait"]
    assert robot and len(action_marks(trace)) == len(robot)
    with pyplot_untouched(monkeypatch):
        fig = belief_figure([trace], "Bourjault ballpoint pen")
        heat = [ax for ax in fig.axes if ax.images and ax.get_label() != "<colorbar>"]
        assert len(heat) == 1
        assert heat[0].get_xlim() == (-0.5, len(episode.steps) + 0.5)  # the last column is not clipped
        assert heat[0].images[0].norm.vmin == LOG_FLOOR  # the log scale
        written = plot_beliefs([trace], str(tmp_path / "fig7"), "Bourjault ballpoint pen")
    assert written == [str(tmp_path / "fig7.png"), str(tmp_path / "fig7.svg")]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig7.png", "fig7.svg"]  # no temporary file left
    width, height = _png_size(tmp_path / "fig7.png")
    assert width >= 1200 and width == MIN_WIDTH_PX and height > 500
    svg = (tmp_path / "fig7.svg").read_text()
    assert 'id="colorbar-0"' in svg
    assert len(re.findall(r'id="robot-action-0-\d+"', svg)) == len(robot)  # one mark per robot action
    observed = [s for s in episode.steps if decision.observations[s.observation] != "blank"]
    assert len(re.findall(r'id="observation-0-\d+"', svg)) == len(observed)
    assert "Bourjault ballpoint pen" in svg and "sequence 57" in svg


def test_many_rows_are_summarised_and_the_figure_says_so(tmp_path):
    n, columns = 3 * MAX_ROWS, 4
    beliefs = np.full((n, columns), 1.0 / n)
    beliefs[5] = [0.5, 0.6, 0.7, 0.8]
    trace = BeliefTrace(beliefs, [5, 5, 5, 5], ["wait"] * 3, ["blank"] * 3, "big", row_label="intention")
    fig = belief_figure([trace] * 3, "big")  # two per row, the last row not full
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # constrained layout warns when it gives up (axes collapsed)
        fig.savefig(io.BytesIO(), format="png")
    heat = [ax for ax in fig.axes if ax.images and ax.get_label() != "<colorbar>"]
    assert len(heat) == 3 and all(ax.images[0].get_array().shape == (MAX_ROWS, columns) for ax in heat)
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any(f"{MAX_ROWS} of {n} intentions shown" in t for t in texts)
    with pytest.raises(PlannerError, match="no episode"):
        plot_beliefs([], str(tmp_path / "none"))


def test_the_factored_figure_is_over_assembly_states(pen):
    model = factored_model(make_plan(pen))
    path = model.sequence(3)
    episode = simulate_episode(PathWorld(model, path), OnlinePlanner(model, expansions=20), np.random.default_rng(0),
                               operator="turns")
    assert len(episode.beliefs) == len(episode.steps) + 1
    truth = [int(model.class_source[path[0]])] + [
        int(model.class_source[path[s.position]]) if s.position < len(path) else model.final_state
        for s in episode.steps]
    trace = state_trace(model, episode.beliefs, truth, [s.action for s in episode.steps],
                        [s.observation for s in episode.steps], "sequence 3")
    assert trace.beliefs.shape == (model.plan.states.n_states, len(episode.steps) + 1)
    assert np.allclose(trace.beliefs.sum(axis=0), 1.0)  # a distribution over states at every step
    assert trace.line[-1] == model.final_state
    # Only the final class sits on the finished product, and it holds one intention: its mass is the flat
    # belief on the true (final) intention the episode recorded.
    assert trace.beliefs[model.final_state, -1] == pytest.approx(episode.steps[-1].p_true)
    assert "assembly states" in trace.note and trace.row_label == "assembly state"


def test_cli_plot_of_the_online_planner(tmp_path):
    stem = tmp_path / "online"
    done = subprocess.run([sys.executable, "-m", "planner", "simulate", "pen", "--planner", "online",
                           "--expansions", "20", "--sequence", "3", "--plot", str(stem)], capture_output=True,
                          text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "sampled from the model" in done.stdout  # the observations are said to be the model's
    assert _png_size(str(stem) + ".png")[0] >= 1200
    assert "assembly state" in (tmp_path / "online.svg").read_text()
