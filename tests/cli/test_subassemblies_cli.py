"""``--subassemblies``, ``--level`` and ``aplan stats`` per level (issue 13, item 2): two chains of 3 joined by one
contact, each a subassembly, counted by the chain formulas; the pen unchanged; simulations and sessions that go
through the levels in order."""
from __future__ import annotations

import json
from math import comb, factorial

import pytest

from planner.cli import main
from planner.product import Part, Product, Subassembly, save_product
from planner.product.synthetic import chain_product
from planner.runtime.log import read_log, replay


def two_chains() -> Product:
    """Chains a1-a2-a3 and b1-b2-b3 joined by a3-b1, each a subassembly."""
    parts = tuple(Part(p) for p in ("a1", "a2", "a3", "b1", "b2", "b3"))
    contacts = (("a1", "a2"), ("a2", "a3"), ("b1", "b2"), ("b2", "b3"), ("a3", "b1"))
    return Product(parts, contacts, subassemblies=(Subassembly("A", ("a1", "a2", "a3")),
                                                   Subassembly("B", ("b1", "b2", "b3"))), name="two chains")


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def _chain(n: int) -> dict:
    return {"subassemblies": n * (n + 1) // 2, "operations": comb(n + 1, 3), "states": 2 ** (n - 1),
            "intentions": sum(comb(n - 1, j) * factorial(j) for j in range(n)), "sequences": factorial(n - 1)}


@pytest.fixture
def chains(tmp_path):
    path = tmp_path / "two-chains.json"
    save_product(two_chains(), path)
    return path


def test_stats_per_level_total_and_flat(capsys, chains):
    code, out, _ = run(capsys, "stats", chains, "--json")
    assert code == 0
    data = json.loads(out)
    assert [level["level"] for level in data["levels"]] == ["A", "B", "top"]
    for level, n in zip(data["levels"], (3, 3, 2)):
        assert {k: level[k] for k in _chain(n)} == _chain(n)
    assert data["levels"][2]["members"] == ["A", "B"]
    assert data["total"] == {"parts": 6, "subassemblies": 6 + 6 + 3, "operations": 4 + 4 + 1, "states": 4 + 4 + 2,
                             "state_edges": 4 + 4 + 1, "intentions": 5 + 5 + 2, "sequences": 2 * 2 * 1}
    assert {k: data["flat"][k] for k in _chain(6)} == _chain(6)
    code, text, _ = run(capsys, "stats", chains)
    assert code == 0
    rows = {line.split()[0]: line.split()[1:] for line in text.splitlines()[2:7]}
    assert rows["A"] == ["3", "0", "6", "4", "4", "4", "5", "2"] and rows["top"][:2] == ["2", "2"]
    assert rows["total"] == ["6", "2", "15", "9", "10", "9", "12", "4"]
    assert rows["flat"] == ["6", "0", "21", "35", "32", "80", "326", "120"]


def test_one_level_and_flat(capsys, chains):
    code, out, _ = run(capsys, "stats", chains, "--level", "B", "--json")
    assert code == 0 and {k: json.loads(out)[k] for k in _chain(3)} == _chain(3)
    code, out, _ = run(capsys, "stats", chains, "--subassemblies", "none", "--json")
    assert code == 0 and {k: json.loads(out)[k] for k in _chain(6)} == _chain(6)
    code, _, err = run(capsys, "stats", chains, "--base-part")
    assert code == 1 and "add --level ID" in err
    code, out, _ = run(capsys, "stats", chains, "--level", "A", "--base-part", "a1", "--json")
    assert code == 0 and json.loads(out)["sequences"] == 1  # a chain of 3 starting from its end: a1 + a2 first
    code, _, err = run(capsys, "stats", chains, "--level", "C")
    assert code == 1 and "--level C: no such subassembly; the levels are A, B, top" in err


def test_the_pen_is_unchanged(capsys):
    plain = run(capsys, "stats", "pen")
    assert run(capsys, "stats", "pen", "--subassemblies", "auto") == plain
    assert run(capsys, "stats", "pen", "--subassemblies", "none") == plain
    assert "intentions                        69" in plain[1]


def test_auto_proposes_workstations(capsys, tmp_path):
    path = tmp_path / "chain.json"
    save_product(chain_product(12), path)
    code, out, _ = run(capsys, "stats", path, "--subassemblies", "auto", "--max-components", "5", "--json")
    data = json.loads(out)
    assert code == 0 and len(data["levels"]) > 1 and all(level["parts"] <= 5 for level in data["levels"])
    assert data["total"]["parts"] == 12 and data["flat"]["sequences"] == factorial(11)
    # designer (the default): the file has none, so flat.
    code, out, _ = run(capsys, "stats", path, "--json")
    assert "levels" not in json.loads(out)


def test_models_need_a_level(capsys, chains, tmp_path):
    code, _, err = run(capsys, "pomdp", chains, "-o", tmp_path / "m.pomdp")
    assert code == 1 and "pick one with --level ID" in err and not (tmp_path / "m.pomdp").exists()
    code, out, _ = run(capsys, "pomdp", chains, "--level", "A", "-o", tmp_path / "m.pomdp")
    assert code == 0 and "5 states" in out  # the intentions of a chain of 3
    code, _, err = run(capsys, "pomdp", tmp_path / "m.pomdp", "--level", "A", "-o", tmp_path / "n.pomdp")
    assert code == 1 and "a model file is one model" in err
    code, out, _ = run(capsys, "evaluate", chains, "--level", "top", "--episodes", "3", "--expansions", "20",
                       "--json")
    assert code == 0 and json.loads(out)["episodes"] == 3


def test_simulate_goes_through_the_levels(capsys, chains):
    code, out, _ = run(capsys, "simulate", chains, "--expansions", "20", "--json")
    *episodes, run_line = [json.loads(line) for line in out.splitlines()]
    assert code == 0 and len(episodes) == 3 and run_line["run"]["episodes"] == 3  # the run's line: every level
    assert [len(e["operations"]) for e in episodes] == [2, 2, 1]  # n - 1 operations per level
    assert all(e["finished"] for e in episodes)
    code, out, _ = run(capsys, "simulate", chains, "--expansions", "20")
    assert [line.split()[1] for line in out.splitlines() if line.startswith("level ")] == ["A", "B", "top"]


def test_session_goes_through_the_levels_with_a_log_each(capsys, chains, tmp_path, monkeypatch):
    from planner.cli import runtime

    calls = []
    monkeypatch.setattr(runtime, "_session_level", lambda args, product, path, level, spec, choice: calls.append(
        (level, product.part_ids, path, spec, choice)) or 0)
    code, out, _ = run(capsys, "session", chains, "--demo", "0", "--log", tmp_path / "s.jsonl")
    assert code == 0 and [c[0] for c in calls] == ["A", "B", "top"]
    assert all(c[3] is calls[0][3] and c[4] is calls[0][4] for c in calls)  # the options read once, for every level
    assert [c[1] for c in calls] == [("a1", "a2", "a3"), ("b1", "b2", "b3"), ("A", "B")]
    assert [c[2] for c in calls] == [str(tmp_path / f"s-{level}.jsonl") for level in ("A", "B", "top")]
    assert [line.split()[1] for line in out.splitlines() if line.startswith("level ")] == ["A", "B", "top"]


def test_a_session_of_one_level_logs_it_and_replays(capsys, chains, tmp_path):
    # The top level: one operation (A + B), seen through the simulated cell's vision pipeline.
    log = tmp_path / "top.jsonl"
    code, out, _ = run(capsys, "session", chains, "--level", "top", "--demo", "0", "--expansions", "20", "--log", log)
    assert code == 0, out
    start = read_log(log)[0]
    assert start["settings"]["level"] == "top" and [p["id"] for p in start["product"]["parts"]] == ["A", "B"]
    done = replay(log)
    assert not done.mismatches and done.end["reason"] == "assembled"


def test_a_sequence_per_level(capsys, chains):
    """``aplan sequence`` plans one workstation as ``stats`` does: level A (a chain of 3: 2 sequences), the top
    level (A + B: one operation), and a product of several levels without ``--level`` is an error naming them."""
    code, out, _ = run(capsys, "sequence", chains, "--level", "A", "--rank", "1", "--json")
    assert code == 0
    steps = json.loads(out)["steps"]
    assert len(steps) == 2 and set().union(*(s["moving"] + s["fixed"] for s in steps)) == {"a1", "a2", "a3"}
    code, out, _ = run(capsys, "sequence", chains, "--level", "A", "--rank", "2")
    assert code == 1
    code, out, _ = run(capsys, "sequence", chains, "--level", "top", "--json")
    assert code == 0 and [sorted(s["moving"] + s["fixed"]) for s in json.loads(out)["steps"]] == [["A", "B"]]
    code, _, err = run(capsys, "sequence", chains)
    assert code == 1 and "pick one with --level ID" in err and "A, B, top" in err

