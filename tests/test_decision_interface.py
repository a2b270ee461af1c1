"""One decision-model interface (issue 24 item 1): outside ``planner/decision/`` no code tells decision models,
beliefs or policies apart by their type; it asks :mod:`planner.decision.models` (an AST check, as
tests/test_interrupts.py checks handlers). And the interface answers the same for each model as the models do."""
from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from conftest import REPO

from planner import api
from planner.decision import models

DECISION = REPO / "planner" / "decision"


def _decision_types() -> set[str]:
    """The names of every class defined in the decision package."""
    names = set()
    for path in DECISION.rglob("*.py"):
        names |= {n.name for n in ast.walk(ast.parse(path.read_text())) if isinstance(n, ast.ClassDef)}
    return names


def _names(node: ast.expr) -> set[str]:
    if isinstance(node, ast.Tuple):
        return set().union(*(_names(e) for e in node.elts)) if node.elts else set()
    if isinstance(node, ast.Attribute):
        return {node.attr}
    return {node.id} if isinstance(node, ast.Name) else set()


def type_tests(source: str, types: set[str]) -> list[tuple[int, str]]:
    """The lines of ``source`` where ``isinstance`` or ``issubclass`` tests one of ``types``, or ``type(x)`` is
    compared with one, with the names tested."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") in ("isinstance", "issubclass") \
                and len(node.args) == 2 and _names(node.args[1]) & types:
            found.append((node.lineno, ", ".join(sorted(_names(node.args[1]) & types))))
        if isinstance(node, ast.Compare) and isinstance(node.left, ast.Call) \
                and getattr(node.left.func, "id", "") == "type":
            hit = set().union(*(_names(c) for c in node.comparators)) & types
            if hit:
                found.append((node.lineno, ", ".join(sorted(hit))))
    return found


def test_the_check_finds_type_tests():
    types = {"IntentionModel", "FactoredBelief"}
    source = ("if isinstance(m, IntentionModel): pass\n"
              "x = isinstance(b, (np.ndarray, factored_model.FactoredBelief))\n"
              "y = type(m) is IntentionModel\n"
              "z = isinstance(m, Product)\n")
    assert type_tests(source, types) == [(1, "IntentionModel"), (2, "FactoredBelief"), (3, "IntentionModel")]


def test_no_type_test_on_decision_types_outside_the_decision_package():
    types = _decision_types()
    assert {"IntentionModel", "FactoredIntentionModel", "LumpedModel", "POMDP", "FactoredBelief",
            "AlphaVectorPolicy", "OnlinePlanner"} <= types
    offenders = []
    for folder in ("planner", "freecad_aplan"):
        for path in sorted((REPO / folder).rglob("*.py")):
            if DECISION in path.parents:
                continue
            offenders += [f"{path.relative_to(REPO)}:{line}: {names}"
                          for line, names in type_tests(path.read_text(), types)]
    assert not offenders, ("decision types tested outside planner/decision/ (ask planner.decision.models "
                           "instead):\n" + "\n".join(offenders))


def test_the_interface_answers_for_every_model(tmp_path):
    flat = api.load_model("pen")
    lumped = api.load_model("pen", lumped=True)
    factored = lumped.factored
    api.save_model(flat, tmp_path / "pen.pomdpx")
    file = api.load_model(tmp_path / "pen.pomdpx")
    assert [models.belief_over(m) for m in (flat, factored, lumped, file)] == \
        ["intentions", "classes", "classes", "states"]
    assert [models.of_product(m) for m in (flat, factored, lumped, file)] == [True, True, True, False]
    assert models.tables(flat) is flat.pomdp and models.tables(lumped) is lumped.pomdp and models.tables(file) is file
    assert models.final_of(flat) == flat.final_state and models.final_of(lumped) == factored.final_class
    assert models.final_of(file) is None
    for model in (flat, factored, lumped, file):
        assert isinstance(model, models.DecisionModel)
        belief = models.updater_for(model).initialize()
        top = models.top_intentions(belief, 3)
        assert top and all(abs(models.belief_at(belief, i) - p) < 1e-6 for i, p in top)
    # the file model's filter is over its states: its initial belief is the file's
    assert np.allclose(models.updater_for(file).initialize(), file.initial)
