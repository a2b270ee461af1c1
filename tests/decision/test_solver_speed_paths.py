"""The solver's faster paths give the numbers of the plain ones: products over the beliefs' columns, the
column-major mirrors of the bounds, the bounds at b0 reused, and a whole solve after a fixed number of trials."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, make_plan
from planner.decision.lumped_model import lumped_model
from planner.decision.solvers.warm_start import solver_start
from planner.decision.solvers import PointBasedSolver
from planner.decision.solvers.lower import LowerBound
from planner.decision.solvers.tables import Rows, best_products


def _sparse_beliefs(rng: np.random.Generator, m: int, S: int, support: int) -> np.ndarray:
    B = np.zeros((m, S))
    for row in B:
        cols = rng.choice(S, size=support, replace=False)
        row[cols] = rng.random(support)
        row /= row.sum()
    return B


@pytest.mark.parametrize("m", [1, 3, 8, 40])
def test_lower_bound_over_the_beliefs_columns_is_the_brute_force_maximum(m):
    rng = np.random.default_rng(m)
    S = 60
    V = rng.normal(size=(300, S))
    B = _sparse_beliefs(rng, m, S, 6)                 # small supports: the column-major path
    lower = LowerBound(V[:100], range(100))
    lower.extend(V[100:], range(100, 300))           # grown past its first capacity
    values, best = lower.at(B)
    brute = np.array([[float(np.dot(v, b)) for v in V] for b in B])
    assert np.allclose(values, brute.max(axis=1), rtol=0, atol=1e-12)
    assert np.allclose(brute[np.arange(m), best], brute.max(axis=1), rtol=0, atol=1e-12)
    plain = best_products(B, V)
    assert np.allclose(plain[0], values, rtol=0, atol=1e-12)


def test_rows_keep_their_column_mirror_through_appends_and_pruning():
    rng = np.random.default_rng(0)
    rows = Rows(7, columns=True)
    data = rng.random((150, 7))
    rows.extend(data[:10])
    for row in data[10:]:
        rows.append(row)
    assert np.array_equal(rows.columns, data.T)
    mask = rng.random(150) < 0.4
    rows.keep(mask)
    assert np.array_equal(rows.rows, data[mask]) and np.array_equal(rows.columns, data[mask].T)
    assert Rows(7).columns is None
    columns_only = Rows(7, columns=True, dtype=np.float32, by_row=False)
    columns_only.extend(data[:100] > 0.5)
    columns_only.keep(mask[:100])
    assert columns_only.rows is None and np.array_equal(columns_only.columns, (data[:100][mask[:100]] > 0.5).T)


def test_a_solve_gives_the_numbers_of_the_unoptimised_solver():
    """Chain 6 (81 classes) after 120 trials, no time limit: the bounds the solver gave before these faster
    paths (main at f9e70f7, whose trials aimed at 0.9 of the gap), to 1e-12, with as many vectors and steps."""
    lumped = lumped_model(make_plan(chain_product(6)))
    options = solver_start(lumped).solve_options
    result = PointBasedSolver(time_limit=None, precision=1e-4, max_iterations=120,
                              gap_fraction=0.9).solve(lumped.pomdp, **options)
    assert abs(result.lower_bound - 0.577911572815069) <= 1e-12
    assert abs(result.upper_bound - 0.7307250438198984) <= 1e-12
    assert result.policy.alphas.shape == (800, 81) and len(result.history) == 138
