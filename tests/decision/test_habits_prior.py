"""The habits' prior spread per state, the robot's eagerness as a confidence, and the ``--model`` presets
(issue 23, docs/habits.md): the choice probabilities against a closed form computed here (path counts by a
depth-first count, not the planner's dynamic programme), old habits files read as they did, the act
confidence's reward mapping and its bad input (a usage error, exit 2, nothing written), and the ``confident``
preset equal to its parts given one by one."""
from __future__ import annotations

import json
from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest

from aplan_runner import run_aplan
from planner.assembly import make_plan
from planner.decision.habits import (Habits, HabitsError, choice_probabilities, habit_weights, habits_from_counts,
                                     prior_pseudo_counts)
from planner.decision.intention_model import Rewards
from planner.decision.io.habits_file import habits_from_dict, habits_to_dict
from planner.decision.projected import PROJECTED_CONFIDENCE
from planner.decision.presets import (CONFIDENT, HELPFUL, PRESETS, act_confidence_of, preset_habits, preset_rewards,
                                      wrong_for_confidence)
from planner.errors import UsageError


def _completions(plan):
    """N(s), the paths from each state to the finished product, by a depth-first count over the state edges."""
    states = plan.states
    out = {}
    for s, t in zip(states.edge_source.tolist(), states.edge_target.tolist()):
        out.setdefault(s, []).append(t)

    @lru_cache(maxsize=None)
    def count(s: int) -> int:
        return 1 if s == states.final else sum(count(t) for t in out[s])
    return count


@pytest.mark.parametrize("prior_per", ["edge", "state"])
def test_choice_is_the_posterior_mean_of_its_prior(pen, prior_per):
    """Closed form at every state with counts: p(e|s) = (n(s,e) + a(s) N(t)/N(s)) / (n(s) + a(s)), a(s) =
    alpha deg(s) per edge, alpha per state; the choices at each state sum to 1."""
    plan = make_plan(pen)
    states = plan.states
    rng = np.random.default_rng(3)
    counts = rng.integers(0, 9, states.n_edges) * (rng.random(states.n_edges) < 0.6).astype(float)
    alpha = 0.7
    N = _completions(plan)
    p = choice_probabilities(plan, counts, alpha, prior_per)
    source, target = states.edge_source.tolist(), states.edge_target.tolist()
    for e in range(states.n_edges):
        out = [k for k in range(states.n_edges) if source[k] == source[e]]
        a = alpha * len(out) if prior_per == "edge" else alpha
        expected = (counts[e] + a * N(target[e]) / N(source[e])) / (counts[out].sum() + a)
        assert p[e] == pytest.approx(expected, rel=1e-12) and p[e] > 0
    assert np.allclose(np.bincount(states.edge_source, weights=p)[np.unique(states.edge_source)], 1.0, atol=1e-12)


def test_sixteen_of_twenty_at_the_first_state(pen):
    """The bench's case: 16 of 20 sessions took one first operation, 4 another. Per state (alpha 1) the favourite
    is (16 + p0) / 21; per edge (alpha 1, d operations) (16 + d p0) / (20 + d): the state of many operations
    swamps the data only in the second."""
    plan = make_plan(pen)
    states = plan.states
    first = np.flatnonzero(states.edge_source == states.initial)
    counts = np.zeros(states.n_edges)
    counts[first[0]], counts[first[1]] = 16, 4
    N = _completions(plan)
    p0 = N(int(states.edge_target[first[0]])) / N(states.initial)
    d = first.size
    assert choice_probabilities(plan, counts, 1.0, "state")[first[0]] == pytest.approx((16 + p0) / 21, rel=1e-12)
    assert choice_probabilities(plan, counts, 1.0, "edge")[first[0]] == pytest.approx((16 + d * p0) / (20 + d),
                                                                                      rel=1e-12)
    assert np.array_equal(prior_pseudo_counts(plan, 1.0, "state"), np.ones(states.n_edges))


def test_old_files_read_as_alpha_per_edge(pen):
    """A file written before the choice (version 1, no prior_per) reads as alpha per edge, with the same weights;
    one per state is written as version 2 and read back; version 1 claiming per state, or another spread, is
    refused."""
    plan = make_plan(pen)
    counts = np.zeros(plan.states.n_edges)
    counts[np.flatnonzero(plan.states.edge_source == plan.states.initial)[:3]] = [5, 2, 1]
    habits = habits_from_counts(plan, counts, 2.0)
    old = habits_to_dict(habits)
    assert old["version"] == 1
    del old["prior_per"]
    read = habits_from_dict(old, "old.json")
    assert read.prior_per == "edge" and np.array_equal(habit_weights(plan, read), habit_weights(plan, habits))
    state = habits_from_counts(plan, counts, 2.0, prior_per="state")
    data = habits_to_dict(state)
    assert data["version"] == 2 and data["prior_per"] == "state"
    assert habits_from_dict(json.loads(json.dumps(data)), "new.json").prior_per == "state"
    assert not np.array_equal(habit_weights(plan, state), habit_weights(plan, habits))
    with pytest.raises(HabitsError, match="needs version 2"):
        habits_from_dict({**data, "version": 1}, "bad.json")
    with pytest.raises(HabitsError, match=r"bad.json: the prior's spread .* got 'path'"):
        habits_from_dict({**data, "prior_per": "path"}, "bad.json")


def test_act_confidence_sets_the_wrong_reward():
    """w = (wait - C right) / (1 - C): the paper's -50 is C = 5/6, 0.98 is -490; the bet breaks even at C."""
    assert act_confidence_of(Rewards()) == pytest.approx(5 / 6, rel=1e-12)
    assert wrong_for_confidence(5 / 6) == pytest.approx(-50, rel=1e-12)
    assert wrong_for_confidence(0.98) == pytest.approx(-490, rel=1e-12)
    assert wrong_for_confidence(0.5, 4.0, 1.0) == pytest.approx(-2.0, rel=1e-12)
    for c in (0.3, 0.9, 0.99):
        w = wrong_for_confidence(c, 10.0, 0.0)
        assert c * 10 + (1 - c) * w == pytest.approx(0.0, abs=1e-9)
        assert act_confidence_of(Rewards(wrong=w)) == pytest.approx(c, rel=1e-12)


@pytest.mark.parametrize("bad", [0, 1, -0.1, 1.5, float("nan"), float("inf"), True, "0.9"])
def test_act_confidence_out_of_range_is_refused(bad):
    with pytest.raises(UsageError, match="--act-confidence must be a number above 0 and below 1"):
        wrong_for_confidence(bad)


def test_act_confidence_needs_a_paying_operation():
    with pytest.raises(UsageError, match="--reward-unfavorable 0 is not above --reward-wait 0"):
        wrong_for_confidence(0.9, 0.0, 0.0)


def test_presets():
    """paper: no habits, the paper's rewards; habits: the file's prior; confident: alpha 1 per state and its C
    (w = -10 C / (1 - C)) unless the user gives the wrong reward or a confidence."""
    assert set(PRESETS) == {"paper", "habits", "confident", "orders", "helpful", "camera"}
    camera, helpful = PRESETS["camera"], PRESETS["helpful"]  # helpful with a camera's observations, nothing else
    assert (camera.observe, helpful.observe) == ("step", "state")
    assert replace(camera, name="helpful", observe="state") == helpful
    assert preset_rewards(PRESETS["paper"], 10, -2, 0, None, None) == Rewards()
    assert preset_rewards(None, 10, -2, 0, None, None) == Rewards()
    c = CONFIDENT.act_confidence
    assert 5 / 6 < c < 1
    assert preset_rewards(CONFIDENT, 10, -2, 0, None, None).wrong == pytest.approx(-10 * c / (1 - c), rel=1e-12)
    assert preset_rewards(CONFIDENT, 10, -2, 0, -70.0, None).wrong == -70.0
    assert preset_rewards(CONFIDENT, 10, -2, 0, None, 0.9).wrong == pytest.approx(-90, rel=1e-12)
    # a model's own default confidence (--projected: 0.98): the more careful of it and the preset's; the user's wins
    own = ("--projected", 0.98)
    assert preset_rewards(None, 10, -2, 0, None, None, own).wrong == pytest.approx(-490, rel=1e-12)
    assert preset_rewards(CONFIDENT, 10, -2, 0, None, None, own).wrong == pytest.approx(-490, rel=1e-12)
    assert preset_rewards(CONFIDENT, 10, -2, 0, None, None, ("--projected", 0.9)).wrong == \
        pytest.approx(-10 * c / (1 - c), rel=1e-12)
    assert preset_rewards(None, 10, -2, 0, -70.0, None, own).wrong == -70.0
    assert preset_rewards(None, 10, -2, 0, None, 0.9, own).wrong == pytest.approx(-90, rel=1e-12)
    with pytest.raises(UsageError, match="--projected sets --act-confidence 0.98"):
        preset_rewards(None, 0, -2, 0, None, None, own)
    h = Habits("pen", "0" * 16, 3.0, (("s", "o", 2.0),))
    assert preset_habits(PRESETS["paper"], h) is None
    assert preset_habits(PRESETS["habits"], h) is h
    assert preset_habits(None, h) is h
    c = preset_habits(CONFIDENT, h)
    assert (c.prior, c.prior_per, c.counts) == (1.0, "state", h.counts)
    # helpful: confident's habits, the joins model, at the more careful of its 0.98 and the joins model's own
    assert preset_habits(HELPFUL, h) == c and HELPFUL.parallel == "joins" and not CONFIDENT.parallel
    assert preset_rewards(HELPFUL, 10, -2, 0, None, None, ("--joins", PROJECTED_CONFIDENCE)).wrong == \
        pytest.approx(wrong_for_confidence(PROJECTED_CONFIDENCE), rel=1e-12)
    with pytest.raises(HabitsError, match="--model orders needs the recorded orders"):
        preset_habits(PRESETS["orders"], h)  # a file without orders (version 1 or 2)
    ordered = replace(h, orders=(((("s", "o"),), 3.0),))
    o = preset_habits(PRESETS["orders"], ordered)
    assert o.prior_model == "orders" and preset_habits(PRESETS["habits"], o).prior_model == "counts"
    assert preset_rewards(PRESETS["orders"], 10, -2, 0, None, None).wrong == pytest.approx(
        wrong_for_confidence(PRESETS["orders"].act_confidence), rel=1e-12)


# The command line: a usage error (exit 2) writes nothing; the preset is its parts given one by one.

@pytest.fixture(scope="module")
def habits_files(pen, tmp_path_factory):
    """Habits of the pen from two logged sessions, per edge (the default) and per state (alpha 1)."""
    from planner.assembly.explode import sequence_at
    from planner.decision.intention_model import intention_model
    from planner.runtime.log import EventLog
    from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
    from planner.runtime.session import run_session

    folder = tmp_path_factory.mktemp("habits-prior")
    model = intention_model(make_plan(pen))

    class Wait:
        wait = len(model.actions) - 1

        def action(self, belief):
            return self.wait

    logs = []
    for k, rank in enumerate([5, 5, 11]):
        path = folder / f"s{k}.jsonl"
        done = run_session(model, Wait(), ScriptedOperator(model.plan, sequence_at(model.plan, rank)),
                           ScriptedRobot(), EventLog(path))
        assert done.assembled
        logs.append(path)
    edge, state = folder / "edge.json", folder / "state.json"
    assert run_aplan("habits", *logs, "-o", edge).returncode == 0
    done = run_aplan("habits", *logs, "-o", state, "--prior-per", "state", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["prior_per"] == "state"
    return edge, state


@pytest.mark.parametrize("bad", ["0", "1", "-0.5", "1.5", "nan", "inf", "much"])
def test_a_bad_act_confidence_is_a_usage_error(tmp_path, bad):
    out = tmp_path / "m.pomdp"
    done = run_aplan("pomdp", "pen", "-o", out, "--act-confidence", bad)
    assert done.returncode == 2 and "--act-confidence" in done.stderr and not out.exists(), done.stderr


def test_act_confidence_and_reward_wrong_do_not_go_together(tmp_path):
    out = tmp_path / "m.pomdp"
    done = run_aplan("pomdp", "pen", "-o", out, "--act-confidence", "0.9", "--reward-wrong", "-3")
    assert done.returncode == 2 and "not allowed with" in done.stderr and not out.exists()


def test_the_default_is_the_papers_model_and_the_preset_its_parts(habits_files, tmp_path):
    """No option, --model paper and --reward-wrong -50 write the same model file; --act-confidence 0.98 the
    one of --reward-wrong w(0.98); --model confident with the per-edge habits the one of the per-state habits
    with the preset's --act-confidence."""
    edge, state = habits_files

    def model(*options) -> bytes:
        out = tmp_path / f"m{len(list(tmp_path.iterdir()))}.pomdp"
        done = run_aplan("pomdp", "pen", "-o", out, *options)
        assert done.returncode == 0, done.stderr
        return out.read_bytes()

    paper = model()
    assert model("--model", "paper") == paper == model("--reward-wrong", "-50")
    eager = model("--act-confidence", "0.98")
    assert eager == model("--reward-wrong", repr(wrong_for_confidence(0.98))) and eager != paper
    confident = model("--habits", edge, "--model", "confident")
    c = repr(CONFIDENT.act_confidence)
    assert confident == model("--habits", state, "--act-confidence", c)
    assert confident != model("--habits", edge, "--act-confidence", c)  # the preset's prior is used
    helpful = model("--habits", edge, "--model", "helpful")  # the joins model: written from the lumped model
    assert helpful == model("--habits", state, "--joins", "--act-confidence", repr(PROJECTED_CONFIDENCE))
    assert helpful == model("--habits", edge, "--model", "confident", "--joins") != confident
    done = run_aplan("pomdp", "pen", "-o", tmp_path / "x.pomdp", "--model", "confident")
    assert done.returncode != 0 and "--model confident needs the habits" in done.stderr
    assert not (tmp_path / "x.pomdp").exists()


def test_a_confident_session_logs_its_prior_replays_and_keeps_the_files(habits_files, pen, tmp_path):
    """A keyboard session with --model confident records the habits with the preset's prior (alpha 1 per state)
    and replays to the same beliefs; --habits-out adds its steps to the file's counts with the file's own prior
    (per edge here; per state kept for a per-state file)."""
    from planner.assembly.explode import sequence_at

    edge, state = habits_files
    plan = make_plan(pen)
    picks = []
    for op in sequence_at(plan, 5):
        seen = plan.observations[int(plan.operation_observation[op])]
        picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    never = ["--reward-unfavorable", "-1000", "--reward-favorable", "-1000"]  # the robot never acts
    log, out = tmp_path / "s.jsonl", tmp_path / "out.json"
    done = run_aplan("session", "pen", "--habits", edge, "--model", "confident", "--keyboard", "--planner", "online",
                     "--expansions", "20", *never, "--log", log, "--habits-out", out, stdin="\n".join(picks) + "\n")
    assert done.returncode == 2 and "--model confident sets --act-confidence" in done.stderr and not log.exists()
    done = run_aplan("session", "pen", "--habits", edge, "--model", "confident", "--keyboard", "--planner", "online",
                     "--expansions", "20", *never, "--reward-wrong", "-1000", "--log", log, "--habits-out", out,
                     stdin="\n".join(picks) + "\n")
    assert done.returncode == 0, done.stderr
    recorded = json.loads(log.read_text().splitlines()[0])["settings"]["habits"]
    assert (recorded["prior"], recorded["prior_per"], recorded["version"]) == (1.0, "state", 3)  # with orders
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
    assert json.loads(out.read_text())["prior_per"] == "edge"
    out2 = tmp_path / "out2.json"
    done = run_aplan("session", "pen", "--habits", state, "--keyboard", "--planner", "online", "--expansions", "20",
                     *never, "--reward-wrong", "-1000", "--log", tmp_path / "s2.jsonl", "--habits-out", out2,
                     stdin="\n".join(picks) + "\n")
    assert done.returncode == 0, done.stderr
    assert json.loads(out2.read_text())["prior_per"] == "state"
