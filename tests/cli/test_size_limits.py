"""The command line past its size limits: aplan stats prints what it could count and why it stopped (exit 3);
the commands that build a model refuse with the estimate and the options they have (exit 1), writing nothing."""
from __future__ import annotations

import json

import pytest

from planner import STAT_KEYS, chain_product, product_to_dict
from planner.assembly.guards import memory_options
from planner.cli import main
from planner.product.synthetic import fastened_product


def run(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def screwed(tmp_path):
    """Two parts joined by 40 screws: 3 * 2^40 + 40 connected part sets."""
    path = tmp_path / "screwed.json"
    path.write_text(json.dumps(product_to_dict(fastened_product(2, 40))))
    return str(path)


def test_stats_of_an_exploding_product(capsys, screwed):
    """Refused at once: it has 3 * 2^40 + 40 connected part sets, and the lower bound from the neighbours of
    each part says so before any enumeration."""
    code, out, err = run(capsys, "stats", screwed, "--json")
    data = json.loads(out)
    assert code == 3 and err == ""
    assert list(data) == list(STAT_KEYS) + ["not_computed"]
    assert (data["parts"], data["contacts"], data["complexity"]) == (42, 81, 3.86)
    assert data["not_computed"]["figures"] == [k for k in STAT_KEYS if k not in ("parts", "contacts", "complexity")]
    assert all(data[k] is None for k in data["not_computed"]["figures"])
    reason = data["not_computed"]["reason"]
    assert "AND/OR graph: at least 3,298,534,883,368 connected part sets" in reason
    assert "40 part(s) look like fasteners by name (screw_01, screw_02" in reason
    assert "--max-subassemblies N raises" in reason
    assert "--exclude" not in reason and "--group" not in reason  # CAD options: the product is a JSON file

    code, out, _ = run(capsys, "stats", screwed)
    assert code == 3
    assert "  subassemblies           not computed" in out and "  parts                             42" in out
    assert "not computed: subassemblies, operations, actions, states, state_edges, intentions, observations, " \
           "sequences: AND/OR graph: at least 3,298,534,883,368 connected part sets" in out


def test_stats_within_the_memory_budget(capsys, tmp_path):
    """Complete 9 with a 1 MiB budget: refused before the AND/OR graph, its states counted on the connection
    diagram (Bell(9): no constraint, so every partition into connected sets is a state)."""
    path = tmp_path / "complete9.json"
    assert run(capsys, "synth", "complete", "9", "-o", str(path))[0] == 0
    code, out, _ = run(capsys, "stats", str(path), "--json", "--max-memory", str(1 / 1024))
    data = json.loads(out)
    assert code == 3
    assert data["states"] == 21147 and data["subassemblies"] is None
    assert data["not_computed"]["figures"] == ["subassemblies", "operations", "actions", "state_edges",
                                               "intentions", "observations", "sequences"]
    reason = data["not_computed"]["reason"]
    assert "assembly state graph would need about" in reason and "21,147 states and at least" in reason
    assert "--max-memory GIB raises the memory budget" in reason and "Bell" not in reason
    code, out, _ = run(capsys, "stats", str(path), "--json")
    assert code == 0 and json.loads(out)["states"] == 21147  # Bell(9)


@pytest.fixture
def chain11(tmp_path):
    path = tmp_path / "chain11.json"
    path.write_text(json.dumps(product_to_dict(chain_product(11))))
    return str(path)


def test_model_commands_name_their_own_options(capsys, tmp_path, chain11):
    target = tmp_path / "chain11.pomdpx"
    code, _, err = run(capsys, "pomdp", chain11, "-o", str(target))
    assert code == 1 and "flat decision model would need about" in err
    assert "9,864,101 intentions x 221 actions" in err
    # About 59 GiB: a larger budget is offered only on a machine with twice that.
    assert ("--max-memory GIB" in err) == (memory_options(59 * 2 ** 30) != [])
    assert "--limit" not in err and not target.exists()
    code, _, err = run(capsys, "simulate", chain11, "--random", "2", "--planner", "offline")
    assert code == 1 and "flat decision model" in err and "--limit" not in err
    assert "--planner online" in err  # what helps: the online planner, which simulate has
    code, _, err = run(capsys, "pomdp", chain11, "-o", str(target), "--max-memory", "1000")
    assert code == 1 and "flat decision model: 9,864,101 intentions would be enumerated, more than the limit of " \
                         "1,000,000" in err and "--limit" not in err and not target.exists()
    code, _, err = run(capsys, "intentions", chain11, "--limit", "5")
    assert code == 1 and "intention graph: 9,864,101 would be enumerated" in err and "--limit N raises" in err
    code, _, err = run(capsys, "intentions", chain11, "--limit", "10000000", "--max-memory", "0.25")
    assert code == 1 and "intention graph would need about 526.8 MiB (9,864,101 intentions)" in err


def test_bad_size_options(capsys):
    with pytest.raises(SystemExit) as info:
        main(["stats", "pen", "--max-memory", "0"])
    assert info.value.code == 2 and "--max-memory: must be a finite number above 0" in capsys.readouterr().err


def test_pomdp_file_budget(capsys, tmp_path):
    """The chain of 7's POMDPX takes about 10 MiB: refused with a 1 MiB budget, nothing written."""
    product = tmp_path / "chain7.json"
    product.write_text(json.dumps(product_to_dict(chain_product(7))))
    target = tmp_path / "chain7.pomdpx"
    code, _, err = run(capsys, "pomdp", str(product), "-o", str(target), "--max-file", str(1 / 1024))
    assert code == 1 and "chain7.pomdpx would take about 10." in err and "--max-file GIB" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain7.json"]


def test_the_online_note_names_the_limit_passed():
    """Chain 10: 986,410 intentions, under the intention limit; it is the flat model's memory that is passed."""
    from planner import api
    from planner.assembly import make_plan
    from planner.assembly.guards import SizeLimits
    from planner.product.synthetic import chain_product

    plan = make_plan(chain_product(10))
    _, note = api.choose_planner(plan, None, None, limits=SizeLimits(memory=4 * 2 ** 30))
    assert "986,410 intentions" in note and "past the memory budget of 4.0 GiB" in note and "1,000,000" not in note
    _, note = api.choose_planner(plan, None, None, limit=1000, limits=SizeLimits(memory=2 ** 50))
    assert "past the intention limit of 1,000" in note and "memory" not in note
