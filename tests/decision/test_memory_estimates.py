"""The memory estimators against what the structures take (tracemalloc, which numpy reports to), and the
state counts against the state graphs built: each estimate is at least the measured peak and within the
stated factor of it. No clock."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.assembly import make_plan
from planner.assembly.andor import and_or_graph, liaison_adjacency
from planner.assembly.state_count import count_states, count_unconstrained
from planner.decision import bounds
from planner.decision.factored_model import factored_model, factored_model_bytes
from planner.decision.lumped_model import lumped_pomdp, lumped_pomdp_bytes
from planner.decision.budget import class_values_bytes
from planner.decision.bounds import revealed_state_values
from planner.decision.solvers.tables import Tables, mdp_upper_bound, solver_bytes
from planner.product.examples import example_path
from planner.product import load_product
from planner.product.synthetic import chain_product, complete_product


REPO = Path(__file__).resolve().parents[2]

# The measures run in a child interpreter: tracemalloc sees every thread, and the suite's background jobs
# (tests/background.py) allocate and free in a thread of this process while a structure is measured.
_MEASURE = r"""
import gc, json, sys, tracemalloc
from planner.assembly import make_plan
from planner.decision.factored_model import factored_model
from planner.decision.lumped_model import lumped_pomdp
from planner.decision.online import revealed_state_values
from planner.decision.solvers.tables import Tables, mdp_upper_bound
from planner.product.synthetic import chain_product, complete_product

def peak(build):
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        result = build()
        held, top = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return result, held - before, top - before

case = sys.argv[1]
product = {"chain11": lambda: chain_product(11), "complete7": lambda: complete_product(7),
           "chain7": lambda: chain_product(7)}[case]()
plan = make_plan(product)
out = {"S": plan.states.n_states, "E": plan.states.n_edges}
model, *out["model"] = peak(lambda: factored_model(plan))
out["classes"], out["actions"] = model.n_classes, len(model.action_operations)
_, *out["values"] = peak(lambda: revealed_state_values(model))
pomdp, *out["lumped"] = peak(lambda: lumped_pomdp(model))
_, *out["solver"] = peak(lambda: mdp_upper_bound(Tables(pomdp), max_sweeps=2))
print(json.dumps(out))
"""


def _measured(case: str) -> dict:
    """Held and peak bytes ``[held, peak]`` of each structure of ``case``'s plan, measured in a child."""
    done = subprocess.run([sys.executable, "-c", _MEASURE, case], capture_output=True, text=True, timeout=600,
                          check=True, env={**os.environ, "PYTHONPATH": str(REPO)})
    return json.loads(done.stdout)


@pytest.mark.parametrize("case", ["chain11", "complete7"])
def test_factored_model_and_values_estimates(case):
    measured = _measured(case)
    S, E = measured["S"], measured["E"]
    held, peak = measured["model"]
    held_estimate, peak_estimate = factored_model_bytes(S, E)
    assert held <= held_estimate <= 2 * held
    assert peak <= peak_estimate <= 2 * peak
    held, peak = measured["values"]
    held_estimate, peak_estimate = class_values_bytes(measured["classes"], S)
    assert held <= held_estimate <= 1.5 * held
    # The block temporaries are budgeted at a full block's size: small models take far less than that.
    assert peak <= peak_estimate


def test_lumped_and_solver_estimates():
    measured = _measured("chain7")
    model = factored_model(make_plan(chain_product(7)))
    _, peak = measured["lumped"]
    estimate = lumped_pomdp_bytes(model.n_classes, len(model.action_operations))
    assert peak <= estimate <= 3 * peak
    _, peak = measured["solver"]
    assert peak <= solver_bytes(lumped_pomdp(model)) <= 4 * peak


def test_values_in_blocks_are_the_same(monkeypatch):
    """The backward passes split a level into blocks of states: any split gives the same values."""
    model = factored_model(make_plan(complete_product(6)))
    whole = revealed_state_values(model)
    monkeypatch.setattr(bounds, "VALUE_BLOCK", 7)
    monkeypatch.setattr(bounds._level_blocks, "__defaults__", (7,))
    assert len(list(bounds._level_blocks(model))) > len(model.plan.states.level_start)  # split indeed
    split = revealed_state_values(model)
    for a, b in zip((whole.value, whole.wait, whole.match, whole.wrong, whole.state),
                    (split.value, split.wait, split.match, split.wrong, split.state)):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("product", [chain_product(9), complete_product(6), chain_product(2)],
                         ids=["chain9", "complete6", "chain2"])
def test_states_counted_before_they_are_built(product):
    """No constraint: the partitions into connected sets are the states (exactly: Bell(6) = 203, 2^8 = 256)."""
    andor = and_or_graph(product)
    assert andor.every_cut
    plan = make_plan(product)
    counted = count_states(andor, liaison_adjacency(product))
    assert (counted.states, counted.edges) == (plan.states.n_states, plan.states.n_edges)
    early = count_unconstrained(liaison_adjacency(product))
    assert early.states == plan.states.n_states and early.edges <= plan.states.n_edges and not early.exact


def test_constrained_products_are_not_counted():
    """The pen's obstructions remove cuts: its partitions into subassemblies only bound its states, so none
    is claimed."""
    pen = load_product(example_path("pen"))
    andor = and_or_graph(pen)
    assert not andor.every_cut and count_states(andor, liaison_adjacency(pen)) is None


def test_the_count_stops_at_its_work():
    assert count_unconstrained(liaison_adjacency(complete_product(8)), work=100) is None


def test_the_lumped_start_leaves_out_what_does_not_fit():
    """The corner groups and the delayed-reveal points are optional: left out (points first) past the budget."""
    from planner.decision.budget import _lumped_start_bytes, lumped_start_fits, plan_bytes
    from planner.decision.lumped_model import lumped_model
    from planner.decision.solvers.tables import pomdp_bytes

    model = lumped_model(make_plan(chain_product(7)))
    plan, pomdp = model.factored.plan, model.pomdp
    held = pomdp_bytes(pomdp) + plan_bytes(plan) + solver_bytes(pomdp)
    graph, groups, points = _lumped_start_bytes(pomdp, plan)
    assert points == 16 * 193 ** 2  # a dense belief per class (193 classes), and their distinct copy
    assert lumped_start_fits(pomdp, plan, held + graph + groups + points) == (True, True)
    assert lumped_start_fits(pomdp, plan, held + graph + groups) == (True, False)
    assert lumped_start_fits(pomdp, plan, held + graph) == (False, False)
