"""Model files stay sparse: exact round trips at scale, reading without dense tables, APPL's wildcards."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from test_pomdp_io import DOORS

from planner import chain_product, complete_product, make_plan
from planner.decision import intention_pomdp
from planner.decision.io import sparse_tables
from planner.decision.io.cassandra import CassandraError, read_cassandra, write_cassandra
from planner.decision.io.pomdpx import PomdpxError, pomdpx_text, read_pomdpx, write_pomdpx
from planner.decision.io.sparse_tables import SparseTable, split_rows

FORMATS = {"pomdpx": (".pomdpx", write_pomdpx, read_pomdpx), "cassandra": (".pomdp", write_cassandra, read_cassandra)}


def assert_same_tables(model, again, reward_tolerance: float = 0.0) -> None:
    """The same tables, entry for entry (same sparsity, bitwise equal values); the reward within
    ``reward_tolerance`` (relative)."""
    assert again.n_states == model.n_states and again.n_actions == model.n_actions
    assert again.n_observations == model.n_observations
    for kind in ("transition", "observation"):
        for a, (x, y) in enumerate(zip(getattr(model, kind), getattr(again, kind))):
            x, y = x.tocsr().sorted_indices(), y.tocsr().sorted_indices()
            x.eliminate_zeros()
            assert np.array_equal(x.indptr, y.indptr) and np.array_equal(x.indices, y.indices), (kind, a)
            assert np.array_equal(x.data, y.data), (kind, a)
    assert np.allclose(model.reward, again.reward, rtol=reward_tolerance, atol=0)
    assert np.array_equal(model.initial, again.initial)
    assert again.discount == model.discount


@pytest.fixture(scope="module")
def models(pen):
    return {"pen": intention_pomdp(make_plan(pen)), "pen technical": intention_pomdp(make_plan(pen, True)),
            "chain 7": intention_pomdp(make_plan(chain_product(7))),
            "complete 5": intention_pomdp(make_plan(complete_product(5)))}


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("name", ["pen", "pen technical", "chain 7", "complete 5"])
def test_round_trips_are_exact(tmp_path, models, name, fmt):
    suffix, write, read = FORMATS[fmt]
    path = tmp_path / ("model" + suffix)
    write(models[name], path)
    # A .pomdp reward is R(s, a, s', z), read back as its expectation over T and O: the same up to rounding.
    assert_same_tables(models[name], read(path), reward_tolerance=1e-12 if fmt == "cassandra" else 0.0)


def test_reading_chain_7_allocates_nothing_dense(tmp_path, models):
    model = models["chain 7"]
    path = tmp_path / "chain7.pomdpx"
    write_pomdpx(model, path)
    nnz = sum(t.nnz for t in model.transition) + sum(o.nnz for o in model.observation)
    entry_bytes = nnz * (8 + 4)  # a CSR entry: its value and its column
    dense_bytes = model.n_actions * model.n_states ** 2 * 8
    tracemalloc.start()
    try:
        read_pomdpx(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 20 * entry_bytes, (f"reading {path.name} peaked at {peak / 2 ** 20:.0f} MiB, over 20 x the "
                                     f"{entry_bytes / 2 ** 20:.1f} MiB of its {nnz:,} non-zero entries "
                                     f"(the dense A x S x S array: {dense_bytes / 2 ** 30:.1f} GiB)")


DOORS_POMDPX = """<?xml version="1.0"?>
<pomdpx version="0.1" id="doors">
<Discount>0.9</Discount>
<Variable>
<StateVar vnamePrev="s0" vnameCurr="s1"><ValueEnum>left right</ValueEnum></StateVar>
<ObsVar vname="z"><ValueEnum>saw-left saw-right</ValueEnum></ObsVar>
<ActionVar vname="a"><ValueEnum>look open-left open-right</ValueEnum></ActionVar>
<RewardVar vname="r"/>
</Variable>
<InitialStateBelief><CondProb><Var>s0</Var><Parent>null</Parent><Parameter>
<Entry><Instance>-</Instance><ProbTable>uniform</ProbTable></Entry>
</Parameter></CondProb></InitialStateBelief>
<StateTransitionFunction><CondProb><Var>s1</Var><Parent>s0 a</Parent><Parameter type="TBL">
<Entry><Instance>* look right</Instance><ProbTable>0.7</ProbTable></Entry>
<Entry><Instance>- look -</Instance><ProbTable>identity</ProbTable></Entry>
<Entry><Instance>- open-left -</Instance><ProbTable>uniform</ProbTable></Entry>
<Entry><Instance>* open-right *</Instance><ProbTable>0.5</ProbTable></Entry>
</Parameter></CondProb></StateTransitionFunction>
<ObsFunction><CondProb><Var>z</Var><Parent>a s1</Parent><Parameter type="TBL">
<Entry><Instance>* - -</Instance><ProbTable>0.5 0.5 0.5 0.5</ProbTable></Entry>
<Entry><Instance>look left -</Instance><ProbTable>1 0</ProbTable></Entry>
<Entry><Instance>look - saw-left</Instance><ProbTable>1 0</ProbTable></Entry>
<Entry><Instance>look right saw-right</Instance><ProbTable>1</ProbTable></Entry>
</Parameter></CondProb></ObsFunction>
<RewardFunction><Func><Var>r</Var><Parent>s0 a</Parent><Parameter type="TBL">
<Entry><Instance>left -</Instance><ValueTable>0 1 -1</ValueTable></Entry>
<Entry><Instance>right -</Instance><ValueTable>0 -1 1</ValueTable></Entry>
</Parameter></Func></RewardFunction>
</pomdpx>
"""


def test_pomdpx_wildcards_give_the_two_doors(tmp_path):
    """'*', '-', identity, uniform, variables in the file's own order, and later entries overriding earlier
    ones (zeros included: the identity clears the 0.7 of 'look', the listed zero clears a 0.5 of 'look')
    give the same model as the Cassandra file."""
    (tmp_path / "doors.pomdp").write_text(DOORS)
    (tmp_path / "doors.pomdpx").write_text(DOORS_POMDPX)
    expected = read_cassandra(tmp_path / "doors.pomdp")
    assert_same_tables(expected, read_pomdpx(tmp_path / "doors.pomdpx"))
    # the writer's shortcut: 'look' leaves the state as it is
    assert "<Instance>look - -</Instance><ProbTable>identity</ProbTable>" in pomdpx_text(expected)
    write_pomdpx(expected, tmp_path / "again.pomdpx")
    assert_same_tables(expected, read_pomdpx(tmp_path / "again.pomdpx"))


def test_pomdpx_errors_name_the_line(tmp_path):
    bad = tmp_path / "bad.pomdpx"
    bad.write_text(DOORS_POMDPX.replace("<Instance>* open-right *</Instance>", "<Instance>* open-middle *</Instance>"))
    with pytest.raises(PomdpxError, match=r"bad.pomdpx: line 17: unknown value 'open-middle' of variable 'a'"):
        read_pomdpx(bad)
    bad.write_text(DOORS_POMDPX.replace("<ProbTable>1 0</ProbTable>", "<ProbTable>1 0 0</ProbTable>"))
    with pytest.raises(PomdpxError, match=r"line 21: 3 values for instance 'look left -', expected 2"):
        read_pomdpx(bad)


def _covered(shape, index):
    """Every cell's coordinates, and which cells ``index`` covers."""
    grid = np.indices(shape)
    covered = np.ones(shape, dtype=bool)
    for k, i in enumerate(index):
        if i is not None:
            covered &= grid[k] == i
    return grid, covered


@pytest.mark.parametrize("chunk", [5, 1 << 21])
def test_sparse_table_agrees_with_dense_assignment(monkeypatch, chunk):
    """Random entries of every kind, applied in order to a dense array, give the table's cells (also when
    the cells are resolved a few at a time)."""
    monkeypatch.setattr(sparse_tables, "_CHUNK", chunk)
    rng = np.random.default_rng(7)
    for _ in range(200):
        shape = tuple(int(n) for n in rng.integers(1, 4, size=3))
        table, dense = SparseTable(shape), np.zeros(shape)
        for _ in range(int(rng.integers(1, 8))):
            index = tuple(int(rng.integers(n)) if rng.random() < 0.6 else None for n in shape)
            free = [k for k, i in enumerate(index) if i is None]
            where = tuple(slice(None) if i is None else i for i in index)
            kind = int(rng.integers(3)) if free else 0
            if kind == 0:
                value = float(rng.integers(3))
                table.set(index, value)
                dense[where] = value
            elif kind == 1:
                axes = tuple(sorted(int(k) for k in rng.choice(free, size=int(rng.integers(1, len(free) + 1)),
                                                                 replace=False)))
                values = rng.integers(3, size=[shape[k] for k in axes]).astype(float)
                table.set_listed(index, axes, values)
                grid, covered = _covered(shape, index)
                dense[covered] = values[tuple(grid[k][covered] for k in axes)]
            elif len(free) >= 2:
                axes = tuple(free[-2:])
                table.set_identity(index, axes)
                grid, covered = _covered(shape, index)
                dense[covered] = (grid[axes[0]] == grid[axes[1]])[covered]
        assert np.array_equal(table.dense(), dense)
        assert np.array_equal(table.values_at(np.arange(dense.size)), dense.ravel())
        assert np.array_equal(np.stack([m.toarray() for m in split_rows(table)]), dense)


def test_cassandra_errors_name_the_line(tmp_path):
    """One-line entries (read by the fast path) and entries over several lines report their own line."""
    bad = tmp_path / "bad.pomdp"
    bad.write_text(DOORS.replace("O: look : left : saw-left 1.0", "O: look : left : saw-middle 1.0"))
    with pytest.raises(CassandraError, match=r"bad.pomdp: line 13: unknown name 'saw-middle'"):
        read_cassandra(bad)
    bad.write_text(DOORS.replace("O: look : left : saw-left 1.0", "O: look : left : saw-left one"))
    with pytest.raises(CassandraError, match=r"bad.pomdp: line 13: expected a number, got 'one'"):
        read_cassandra(bad)
    bad.write_text(DOORS.replace("0.5 0.5\n0.5 0.5", "0.5 0.5\n0.5 half"))
    with pytest.raises(CassandraError, match=r"bad.pomdp: line 19: expected a number, got 'half'"):
        read_cassandra(bad)
