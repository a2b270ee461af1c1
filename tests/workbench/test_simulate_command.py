"""The workbench's Simulate (freecad_aplan.workflow.simulate_sequence), without FreeCAD: the GUI command only
asks for the level, the policy and the sequence and calls it. It plays a policy over intentions on the flat
model and a policy over the lumped model's classes on the factored model, as ``aplan simulate --policy`` does;
the expected episodes are the command line's own run (its JSON line) of the same policy and sequence."""
from __future__ import annotations

import contextlib
import io
import json
from dataclasses import replace

import pytest

from freecad_aplan import workflow
from planner import api
from planner.cli import main
from planner.decision.policy import write_policy
from planner.errors import PlannerError


@pytest.fixture(scope="module")
def policies(tmp_path_factory):
    """The pen's policies over intentions (flat) and over classes (lumped), solved by a fixed number of trials
    (no clock: the same policies on any machine)."""
    folder = tmp_path_factory.mktemp("policies")
    written = {}
    for kind, model in (("flat", api.decision_model("pen")), ("lumped", api.lumped_model("pen"))):
        written[kind] = str(folder / f"{kind}.policy")
        write_policy(api.solve(model, None, iterations=20).policy, written[kind], api.tables(model).name)
    return written


def _command_line(policy: str, sequence: int) -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["simulate", "pen", "--policy", policy, "--sequence", str(sequence), "--operator", "turns",
                     "--json"]) == 0
    return json.loads(out.getvalue().splitlines()[0])


@pytest.mark.parametrize("kind, sequence", [("lumped", 3), ("flat", 50)])
def test_simulate_plays_the_policy_as_the_command_line(tmp_path, policies, kind, sequence):
    """A lumped policy (what Solve writes where the flat model does not fit) runs on the factored model, its
    sequence numbered by rank; a flat one on the flat model: the same operations, confidence and steps as
    ``aplan simulate --policy P --sequence K --operator turns``, and the belief plot is written."""
    choice = replace(workflow.SIMULATE_EPISODE, sequences=(sequence,))
    result = workflow.simulate_sequence(api.resolve_product("pen"), policies[kind], str(tmp_path / "belief"), choice)
    expected = _command_line(policies[kind], sequence)
    assert result["model"] == kind and result["sequence"] == sequence
    assert result["operations"] == expected["operations"] and len(result["operations"]) == 5  # the pen's five
    assert result["confident_after"] == expected["confident_after_operations"]
    assert expected["robot_operations"] + expected["operator_operations"] == 5  # taking turns, it finishes
    assert len(result["steps"]) >= 1 and all(0 <= p <= 1 for _, _, p in result["steps"])
    assert sorted(p.rsplit(".", 1)[1] for p in result["plots"]) == ["png", "svg"]
    assert (tmp_path / "belief.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_simulate_plays_one_sequence_and_checks_its_rank(tmp_path, policies):
    pen = api.resolve_product("pen")
    with pytest.raises(PlannerError, match="Simulate plays one full sequence"):
        workflow.simulate_sequence(pen, policies["lumped"], str(tmp_path / "b"),
                                   replace(workflow.SIMULATE_EPISODE, every=True))
    with pytest.raises(PlannerError, match="sequence 24: with the online planner sequences are numbered by rank, "
                                           "from 0 to 23"):
        workflow.simulate_sequence(pen, policies["lumped"], str(tmp_path / "b"),
                                   replace(workflow.SIMULATE_EPISODE, sequences=(24,)))
    assert not list(tmp_path.iterdir())  # refused before any plot
