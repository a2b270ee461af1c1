"""The aplan command line: stats, intentions, synth; exit codes and no output on failure."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from planner import STAT_KEYS, load_product
from planner.cli import main

PEN_JSON = {"parts": 6, "contacts": 5, "complexity": 1.67, "subassemblies": 18, "operations": 21, "actions": 22,
            "states": 18, "state_edges": 32, "intentions": 69, "observations": 12, "sequences": 24}


def run(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_stats_json_has_exactly_the_keys(capsys):
    code, out, _ = run(capsys, "stats", "pen", "--json")
    assert code == 0
    data = json.loads(out)
    assert list(data) == list(STAT_KEYS)
    assert data == PEN_JSON


def test_stats_technical_switch(capsys):
    _, out, _ = run(capsys, "stats", "pen", "--json", "--technical")
    assert json.loads(out)["intentions"] == 39
    _, out, _ = run(capsys, "stats", "pen", "--json", "--no-technical")
    assert json.loads(out)["intentions"] == 69


def test_stats_base_part(capsys):
    _, out, _ = run(capsys, "stats", "pen", "--json", "--base-part")
    assert json.loads(out)["sequences"] == 10  # body, the most connected part
    per_part = {}
    for part in ("ink", "cartridge", "head", "body", "cap", "button"):
        per_part[part] = json.loads(run(capsys, "stats", "pen", "--json", "--base-part", part)[1])["sequences"]
    assert sum(per_part.values()) == 2 * 24  # each sequence starts by joining two single parts
    code, _, err = run(capsys, "stats", "pen", "--base-part", "pencil")
    assert code == 1 and "base part 'pencil' is not a part of the product" in err


def test_stats_text(capsys):
    code, out, _ = run(capsys, "stats", "pen")
    assert code == 0
    assert "intentions" in out and "69" in out and "factored view: 18 assembly states x 24 sequences" in out


def test_stats_of_a_file(capsys, tmp_path):
    target = tmp_path / "chain.json"
    assert run(capsys, "synth", "chain", "11", "-o", str(target))[0] == 0
    assert len(load_product(target).parts) == 11
    _, out, _ = run(capsys, "stats", str(target), "--json")
    data = json.loads(out)
    assert (data["subassemblies"], data["operations"], data["states"], data["intentions"], data["complexity"]) == \
        (66, 220, 1024, 9_864_101, 1.82)


def test_synth_to_stdout(capsys):
    code, out, _ = run(capsys, "synth", "complete", "4")
    assert code == 0 and len(json.loads(out)["contacts"]) == 6


def test_intentions(capsys):
    code, out, _ = run(capsys, "intentions", "pen", "--full", "--json")
    lines = [json.loads(line) for line in out.splitlines()]
    assert code == 0 and len(lines) == 24
    assert all(len(line["operations"]) == 5 and len(line["states"]) == 6 for line in lines)
    code, _, err = run(capsys, "intentions", "pen", "--limit", "50")
    assert code == 1 and "69 would be enumerated, more than the limit of 50" in err


@pytest.mark.parametrize("content, fragment", [
    ("{", "malformed JSON"),
    ('{"format": "aplan-product", "version": 9, "parts": [], "contacts": []}', "unknown format version 9"),
    ('{"format": "aplan-product", "version": 1, "parts": [{"id": "a"}, {"id": "b"}], "contacts": []}',
     "not connected"),
])
def test_bad_input_exits_non_zero(capsys, tmp_path, content, fragment):
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    code, out, err = run(capsys, "stats", str(bad))
    assert code == 1 and out == "" and fragment in err and err.startswith("aplan: error: ")


def test_failed_synth_writes_nothing(tmp_path):
    target = tmp_path / "out.json"
    result = subprocess.run([sys.executable, "-m", "planner", "synth", "chain", "0", "-o", str(target)],
                            capture_output=True, text=True)
    assert result.returncode == 2 and "must be a whole number at least 1, got 0" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_unknown_product_is_a_clear_error():
    result = subprocess.run([sys.executable, "-m", "planner", "stats", "pencil"], capture_output=True, text=True)
    assert result.returncode == 1
    assert "pencil: no such file, and no embedded example of that name (embedded: pen)" in result.stderr


def test_lumped_model_written_and_solved(capsys, tmp_path):
    from lxml import etree

    from planner import api
    from planner.decision import read_policy
    from planner.decision.io.pomdpx import read_pomdpx

    model = tmp_path / "pen.pomdpx"
    code, out, _ = run(capsys, "pomdp", "pen", "--no-technical", "--lumped", "-o", str(model))
    assert code == 0 and "33 states, 22 actions, 12 observations" in out   # 32 state edges + the finished product
    lumped = api.lumped_model("pen", technical=False)
    read = read_pomdpx(model)
    assert read.n_states == 33 and read.name == lumped.name == lumped.pomdp.name
    # The precision stops the solver at once (no clock): the gap at the initial belief is below 10 already.
    policy = tmp_path / "pen.policy"
    code, out, _ = run(capsys, "solve", "pen", "--no-technical", "--lumped", "--precision", "10", "--json",
                       "-o", str(policy))
    assert code == 0 and json.loads(out)["upper_bound"] - json.loads(out)["lower_bound"] <= 10
    assert etree.parse(str(policy)).getroot().get("model").endswith(":lumped")
    assert read_policy(policy, lumped.pomdp).alphas.shape[1] == 33
    # --lumped on a model file is refused with the way forward.
    code, _, err = run(capsys, "solve", str(model), "--lumped", "-o", str(tmp_path / "x.policy"))
    assert code == 1 and "aplan pomdp PRODUCT --lumped" in err and not (tmp_path / "x.policy").exists()
