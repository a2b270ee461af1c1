"""Observations of the step taken (``--observe step``, planner/decision/step_observations.py): the factored
model's filter equals an explicit filter over every (state, completion) pair of the product, with the camera's
likelihood written out here (habits, change of mind and mistakes included); the online planner's split agrees
with the filter; the camera's idle blank keeps the belief where it is (closed form 5/6); the camera world never
resets it; the POMDP over (class, seen observation) pairs (planner/decision/step_pomdp.py), filtered by the
generic updater, is the same filter and its POMDPX file reads back; what cannot hold it (the lumped POMDP of
the classes, the flat model, policies in a session, ``--model paper``) refuses; a cell session replays."""
from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp
from aplan_runner import run_aplan

from planner import chain_product, make_plan
from planner.decision import FactoredUpdater, factored_model, lumped_pomdp
from planner.decision.deviations import Deviations
from planner.decision.habits import habit_weights_from
from planner.decision.online import OnlinePlanner, _split_of
from planner.decision.belief import DiscreteUpdater
from planner.decision.step_observations import JOIN, STEP, check_observe, predict_seen, step_posterior
from planner.decision.step_pomdp import step_pomdp, step_states
from planner.defaults import CAMERA_BLANK, STAY
from planner.errors import PlannerError


class CompletionFilter:
    """The Bayes filter written over (assembly state, completion) pairs, the flat model's intentions: each pair's
    prior is the product of the edge weights along its path; the camera's likelihood per step (blank when the
    operator did nothing; its step's observation with 4/5, else blank); a change of mind redraws the completion
    at the pair's state in proportion to the completions' weights; mistakes mix ``mu / Z`` in. Nothing here
    reads the factored model's tables but its state edges, actions and weights."""

    def __init__(self, model, weights, deviations: Deviations | None = None):
        self.model = model
        self.w = np.ones(model.n_classes - 1) if weights is None else np.asarray(weights, dtype=float)
        self.sigma = deviations.switch if deviations else 0.0
        self.mu = deviations.mistake if deviations else 0.0
        full = [tuple(model.sequence(r)) for r in range(model.n_sequences)]
        self.pairs = sorted({p[j:] for p in full for j in range(len(p) + 1)})
        self.index = {p: k for k, p in enumerate(self.pairs)}
        self.state = [int(model.class_source[p[0]]) if p else model.final_state for p in self.pairs]
        self.weight = np.array([np.prod(self.w[list(p)]) if p else 1.0 for p in self.pairs])
        self.obs = [int(model.plan.operation_observation[model.class_operation[p[0]]]) if p else 0
                    for p in self.pairs]
        self.prior = np.zeros(len(self.pairs))
        for p in full:
            self.prior[self.index[p]] = self.weight[self.index[p]]
        self.prior /= self.prior.sum()

    def _redraw(self, k: int):
        """A change of mind first: (pair, probability) pieces."""
        if not self.pairs[k] or not self.sigma:
            return [(k, 1.0)]
        same = [j for j in range(len(self.pairs)) if self.state[j] == self.state[k] and self.pairs[j]]
        total = sum(self.weight[j] for j in same)
        return [(k, 1.0 - self.sigma)] + [(j, self.sigma * self.weight[j] / total) for j in same]

    def _operator(self, k: int, p: float, out: list) -> None:
        """The operator's stay or advance from pair ``k`` (after the redraw): (pair, probability, seen)."""
        for j, q in self._redraw(k):
            if not self.pairs[j]:
                out.append((j, p * q, 0))
                continue
            out.append((j, p * q * STAY, 0))
            out.append((self.index[self.pairs[j][1:]], p * q * (1 - STAY), self.obs[j]))

    def update(self, belief: np.ndarray, action: int, z: int) -> np.ndarray:
        pieces = []
        for k in np.flatnonzero(belief > 0):
            p = self.pairs[k]
            if action == self.model.wait:
                self._operator(k, belief[k], pieces)
            elif p and self.model.class_action[p[0]] == action:
                self._operator(self.index[p[1:]], belief[k], pieces)  # the robot's step, then the operator's
            else:
                pieces.append((k, belief[k], 0))
        out = np.zeros(len(self.pairs))
        Z = len(self.model.plan.observations)
        for j, p, seen in pieces:
            like = (1.0 if seen == 0 else CAMERA_BLANK) if z == 0 else ((1 - CAMERA_BLANK) if seen == z else 0.0)
            out[j] += p * ((1 - self.mu) * like + self.mu / Z)
        return out / out.sum()

    def by_class(self, belief: np.ndarray) -> np.ndarray:
        out = np.zeros(self.model.n_classes)
        for k, p in enumerate(self.pairs):
            out[p[0] if p else self.model.final_class] += belief[k]
        return out

    def draw(self, belief: np.ndarray, action: int, rng) -> int:
        """An observation the filter's own world could emit from a pair drawn from ``belief``."""
        k = int(rng.choice(len(self.pairs), p=belief))
        pieces = []
        self._operator(k, 1.0, pieces) if action == self.model.wait else pieces.append((k, 1.0, 0))
        j, _, seen = pieces[int(rng.choice(len(pieces), p=[q for _, q, _ in pieces]))]
        return 0 if seen == 0 or rng.random() < CAMERA_BLANK else seen


PRODUCTS = {"pen": None, "chain 5": 5}
CASES = {"uniform": (False, None), "habits": (True, None), "switch and mistakes": (True, Deviations(0.2, 0.05))}


@pytest.fixture(scope="module")
def plans(pen):
    return {"pen": make_plan(pen, True), "chain 5": make_plan(chain_product(5))}


@pytest.mark.parametrize("observe", [STEP, JOIN])
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("product", PRODUCTS)
def test_the_step_filter_equals_the_filter_over_every_completion(plans, product, case, observe):
    plan = plans[product]
    habits, deviations = CASES[case]
    rng = np.random.default_rng(7)
    weights = habit_weights_from(plan, rng.integers(0, 4, plan.states.n_edges).astype(float), 1.0) if habits else None
    model = factored_model(plan, weights=weights, deviations=deviations, observe=observe)
    reference = CompletionFilter(model, model.weights, deviations)
    updater = FactoredUpdater(model)
    for episode in range(4):
        belief, flat = updater.initialize(), reference.prior
        assert np.allclose(belief.dense(model.n_classes), reference.by_class(flat), atol=1e-12)
        for _ in range(12):
            action = model.wait if rng.random() < 0.6 else int(rng.integers(len(model.actions)))
            z = reference.draw(flat, action, rng)
            belief, flat = updater.update(belief, action, z), reference.update(flat, action, z)
            assert np.allclose(belief.dense(model.n_classes), reference.by_class(flat), atol=1e-9, rtol=0)
    assert updater.events == []  # every observation drawn from the world is explained: no reset


@pytest.mark.parametrize("observe", [STEP, JOIN])
@pytest.mark.parametrize("parallel", [False, "joins"])
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("product", PRODUCTS)
def test_the_step_pomdp_summed_over_the_seen_is_the_step_filter(plans, product, case, parallel, observe):
    """The POMDP over (class, seen) pairs (planner/decision/step_pomdp.py), filtered exactly by the generic
    DiscreteUpdater and summed over the seen observation, is the factored step filter; its rows are
    distributions, and the observations are drawn from the POMDP itself (so parallel joins are covered)."""
    plan = plans[product]
    habits, deviations = CASES[case]
    rng = np.random.default_rng(11)
    weights = habit_weights_from(plan, rng.integers(0, 4, plan.states.n_edges).astype(float), 1.0) if habits else None
    model = factored_model(plan, weights=weights, deviations=deviations, parallel=parallel, observe=observe)
    pomdp = step_pomdp(model)
    pair_class, pair_seen = step_states(model)
    assert pomdp.n_states == pair_class.size and np.all(pair_seen[np.flatnonzero(np.diff(pair_class)) + 1] == 0)
    for table in (*pomdp.transition, pomdp.observation[0]):
        assert np.allclose(np.asarray(table.sum(axis=1)).ravel(), 1.0, atol=1e-12)
    by_class = sp.csr_matrix((np.ones(pair_class.size), (np.arange(pair_class.size), pair_class)),
                             shape=(pair_class.size, model.n_classes))
    generic, factored = DiscreteUpdater(pomdp), FactoredUpdater(model)
    for episode in range(3):
        flat, belief = generic.initialize(), factored.initialize()
        assert np.allclose(by_class.T @ flat, belief.dense(model.n_classes), atol=1e-12)
        for _ in range(12):
            action = model.wait if rng.random() < 0.6 else int(rng.integers(len(model.actions)))
            predicted = generic.predict(flat, action)
            chance = pomdp.observation[action].T @ predicted
            z = int(rng.choice(chance.size, p=chance / chance.sum()))
            flat, belief = generic.update(flat, action, z), factored.update(belief, action, z)
            assert np.allclose(by_class.T @ flat, belief.dense(model.n_classes), atol=1e-9, rtol=0)
    assert generic.events == [] and factored.events == []


def test_an_idle_blank_keeps_five_sixths_on_the_state(plans):
    """The operator is seen doing a first operation of the pen's, then the camera sees nothing: every operation
    out of the state it reached shows a part, so it stayed with probability 1/2 / (1/2 + 1/2 x 1/5) = 5/6 (else
    the camera missed its next step). The paper's filter reads the same blank as evidence that it moved on (the
    reached state's row gives blank only 1/5 of the time, as the next one's does): less than 5/6 stays."""
    plan = plans["pen"]
    step, paper = factored_model(plan, observe=STEP), factored_model(plan)
    first = step.classes_from(plan.states.initial)[0]
    z = int(plan.operation_observation[step.class_operation[first]])
    on_reached = {}
    for name, model in (("step", step), ("paper", paper)):
        updater = FactoredUpdater(model)
        seen = updater.update(updater.initialize(), model.wait, z)
        reached = np.concatenate([model.classes_from(int(s)) for s in np.unique(model.class_source[seen.classes])])
        assert z != 0 and np.all(plan.operation_observation[model.class_operation[reached]] != 0)
        on_reached[name] = updater.update(seen, model.wait, 0).dense(model.n_classes)[reached].sum()
    assert on_reached["step"] == pytest.approx(STAY / (STAY + (1 - STAY) * CAMERA_BLANK), abs=1e-12)
    assert on_reached["step"] == pytest.approx(5 / 6, abs=1e-12)
    assert on_reached["paper"] < on_reached["step"] - 0.1


@pytest.mark.parametrize("deviations", [None, Deviations(0.1, 0.05)], ids=["plain", "switch and mistakes"])
def test_the_online_split_is_the_filter(plans, deviations):
    """Each branch of the online planner's split is the filter's posterior for its observation, the branch
    probabilities sum to 1, and each is the observation's probability under the prediction's pieces."""
    plan = plans["pen"]
    model = factored_model(plan, deviations=deviations, parallel="joins", observe=STEP)
    updater = FactoredUpdater(model)
    belief = updater.update(updater.initialize(), model.wait, 0)
    for action in range(len(model.actions)):
        split = _split_of(model, belief, action, None)
        total = sum(p for _, p, _ in split.branches)
        assert total == pytest.approx(1.0, abs=1e-12)
        pieces = predict_seen(model, belief, action)
        for z, p, _ in split.branches:
            posterior = split.posterior(z)
            expected = updater.update(belief, action, z)
            assert np.allclose(posterior.dense(model.n_classes), expected.dense(model.n_classes), atol=1e-12)
            if deviations is None:
                seen = pieces.mass[pieces.seen == z].sum()
                closed = (pieces.mass[pieces.seen == 0].sum() + CAMERA_BLANK * pieces.mass[pieces.seen != 0].sum()
                          if z == 0 else (1 - CAMERA_BLANK) * seen)
                assert p == pytest.approx(closed, abs=1e-12)
    assert step_posterior(model, predict_seen(model, belief, model.wait), 0) is not None


def test_the_online_planner_decides_on_it_and_the_camera_world_never_resets_it(plans):
    """Online planner, joins, the camera world: the same actions for the same work, and no reset in any episode
    (every camera observation is one the model's steps emit)."""
    from planner import api
    from planner.decision.operators import parse_operator

    model = factored_model(plans["pen"], parallel="joins", observe=STEP)
    choice = api.EpisodeChoice(random=6, seed=3, operator_model=parse_operator("uniform"), world="camera")
    runs = [api.simulate(model, OnlinePlanner(model, expansions=40), choice) for _ in range(2)]
    assert [[s.action for s in e.steps] for e in runs[0]] == [[s.action for s in e.steps] for e in runs[1]]
    assert all(e.finished for e in runs[0])
    assert sum(e.resets for e in runs[0]) == 0


def test_what_cannot_hold_observations_of_the_step_refuses(plans, tmp_path):
    model = factored_model(plans["pen"], observe=STEP)
    with pytest.raises(PlannerError, match="online planner"):
        lumped_pomdp(model)
    with pytest.raises(PlannerError, match="unknown observation model 'camera'"):
        check_observe("camera")
    for args, message in ((["--planner", "offline"], "--planner offline is a policy of the paper's observations"),
                          (["--model", "paper"], "--model paper is Alg. 3 as published")):
        done = run_aplan("simulate", "pen", "--random", "1", "--observe", "step", *args)
        assert done.returncode != 0 and message in done.stderr, done.stderr
    solve = run_aplan("solve", "pen", "--observe", "step", "-o", tmp_path / "p.policy")
    assert solve.returncode != 0 and "add --lumped for the POMDP over (class, seen observation) pairs" in solve.stderr
    assert not (tmp_path / "p.policy").exists()


def test_the_step_pomdp_is_written_and_read_back_and_solved(pen, tmp_path):
    """``aplan pomdp pen --lumped --observe step`` (change of mind and mistakes on): a POMDPX file whose tables
    are those of step_pomdp (to the file's precision), with more states than classes, which ``aplan solve``
    solves."""
    from planner.decision.io.pomdpx import read_pomdpx

    path = tmp_path / "step.pomdpx"
    done = run_aplan("pomdp", "pen", "--lumped", "--observe", "step", "--switch", "0.1", "--mistakes", "0.05",
                     "-o", path)
    assert done.returncode == 0, done.stderr
    model = factored_model(make_plan(pen), observe=STEP, deviations=Deviations(0.1, 0.05))  # the file's constraints
    expected, read = step_pomdp(model), read_pomdpx(path)
    assert (read.n_states, read.n_actions, read.n_observations) == (expected.n_states, len(model.actions),
                                                                    len(model.plan.observations))
    assert read.n_states > model.n_classes  # pairs beyond the classes: the step's observation is in the state
    for a in range(read.n_actions):
        assert np.allclose(read.transition[a].toarray(), expected.transition[a].toarray(), atol=1e-6)
        assert np.allclose(read.observation[a].toarray(), expected.observation[a].toarray(), atol=1e-6)
    assert np.allclose(read.reward, expected.reward, atol=1e-6)
    assert np.allclose(read.initial, expected.initial, atol=1e-9)
    solved = run_aplan("solve", path, "-o", tmp_path / "step.policy", "--trials", "20")
    assert solved.returncode == 0 and "lower bound" in solved.stdout, solved.stderr


def test_a_cell_session_observing_steps_records_it_and_replays(tmp_path):
    log = tmp_path / "step.jsonl"
    done = run_aplan("session", "pen", "--demo", "5", "--observe", "step", "--expansions", "40", "--log", log)
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    start = json.loads(log.read_text().splitlines()[0])
    assert start["settings"]["observe"] == "step" and start["belief_over"] == "classes"
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
    damaged = tmp_path / "damaged.jsonl"
    lines = log.read_text().splitlines()
    first = json.loads(lines[0])
    first["settings"]["observe"] = "camera"
    damaged.write_text("\n".join([json.dumps(first)] + lines[1:]) + "\n")
    bad = run_aplan("replay", damaged)
    assert bad.returncode != 0 and "'observe' setting 'camera'" in bad.stderr, bad.stderr
