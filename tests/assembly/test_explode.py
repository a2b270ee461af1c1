"""The exploded view of an assembly sequence (planner.assembly.explode) on the pen: sequences by rank against a
brute-force enumeration, free directions against the ground-truth obstruction graphs in ../shared, moving
sides by their rule, offsets by their closed form."""
from __future__ import annotations

import json

import pytest
from conftest import PEN_MODELS, require_shared

from planner import api
from planner.assembly import count_sequences, make_plan
from planner.assembly.explode import (
    FALLBACK_DIRECTION,
    SequenceError,
    check_sequence,
    exploded_view,
    free_direction,
    moving_side,
    sequence_at,
    sequence_count,
)


@pytest.fixture(scope="module")
def plan(pen):
    return make_plan(pen)


def _all_sequences(plan, base_part=None):
    """Brute force: every path from the initial to the final state, depth first, edges in increasing order."""
    states, out = plan.states, []
    first = None if base_part is None else {e for e in range(states.n_edges) if states.edge_source[e] == states.initial
                                            and base_part in plan.andor.parts_of(plan.andor.operations[
                                                int(states.edge_operation[e])].parent)}

    def walk(state, done):
        if state == states.final:
            out.append(done)
            return
        for e in range(states.n_edges):
            if states.edge_source[e] == state and (first is None or state != states.initial or e in first):
                walk(int(states.edge_target[e]), done + [int(states.edge_operation[e])])

    walk(states.initial, [])
    return out


def _ground_truth():
    """Per axis name (+X, -X, ...): the pairs (x, y) such that x, moved along it, hits y (the simplified pen)."""
    truth = {}
    for axis in "XYZ":
        path = require_shared(PEN_MODELS / "simplified" / "GroundTruth" / f"GeomConstraints_POS_{axis}.json")
        pairs = {(link["source"].removesuffix("_001"), link["target"].removesuffix("_001"))
                 for link in json.loads(path.read_text())["links"]}
        truth[f"+{axis}"], truth[f"-{axis}"] = pairs, {(y, x) for x, y in pairs}
    return truth


def test_sequences_by_rank_are_the_brute_force_enumeration(plan):
    expected = _all_sequences(plan)
    assert len(expected) == 24 == sequence_count(plan)  # README: the pen's 24 sequences
    assert [sequence_at(plan, r) for r in range(24)] == expected
    count, listed = api.sequence_choices(plan, limit=5)
    assert count == 24 and listed == expected[:5]


def test_sequences_from_the_base_part(plan):
    expected = _all_sequences(plan, "body")
    assert sequence_count(plan, "body") == len(expected) == count_sequences(plan.states, "body")
    assert [sequence_at(plan, r, "body") for r in range(len(expected))] == expected
    assert api.sequence_choices(plan, "auto")[0] == len(expected)  # auto: body, the most connected part


def test_free_directions_are_allowed_by_the_ground_truth(plan):
    truth = _ground_truth()
    for operations in _all_sequences(plan):
        view = exploded_view(plan, operations, spacing=10.0)
        assert [s.operation for s in view.steps] == operations
        for step in view.steps:
            hits = {(x, y) for x, y in truth[step.direction.name] if x in step.moving and y in step.fixed}
            assert hits == set(), (step.description, step.direction.name)
            assert step.moving | step.fixed == frozenset().union(*plan.andor.inputs(step.operation))


def test_a_direction_clear_of_the_whole_product_comes_first(plan, pen):
    truth = _ground_truth()
    # The button leaves the body along +X, and nothing else of the pen is in its way that way.
    direction = free_direction(pen, frozenset({"button"}), frozenset({"body"}))
    assert direction.name == "+X" and not any(x == "button" for x, _ in truth["+X"])
    # The ink alone: hits the button along +X (not in the fixed side), the head along -X: +X is only free
    # of the cartridge and the head it joins.
    assert free_direction(pen, frozenset({"ink"}), frozenset({"cartridge", "head"})).name == "+X"
    # Between the cap and the button the ink is stuck: +X hits the button, -X the cap, Y and Z both.
    with pytest.raises(SequenceError, match=r"\{ink\} cannot leave \{button, cap\} along any direction"):
        free_direction(pen, frozenset({"ink"}), frozenset({"cap", "button"}))
    assert {("ink", "button")} <= truth["+X"] and {("ink", "cap")} <= truth["-X"]
    unconstrained = api.resolve_product("pen").__class__(parts=pen.parts, contacts=pen.contacts)
    assert free_direction(unconstrained, frozenset({"ink"}), frozenset({"cartridge"})) == FALLBACK_DIRECTION


def test_moving_side_rule(plan):
    for operation in range(len(plan.andor.operations)):
        moving, fixed = moving_side(plan, operation)
        assert len(moving) <= len(fixed)
        moving, fixed = moving_side(plan, operation, "body")
        if "body" in moving | fixed:
            assert "body" in fixed
    # A tie of sizes goes to the smaller volume: the ink (9,022 mm^3) moves into the cartridge (12,687).
    (join,) = [j for j in range(len(plan.andor.operations)) if set(map(frozenset, plan.andor.inputs(j)))
               == {frozenset({"ink"}), frozenset({"cartridge"})}]
    assert moving_side(plan, join) == (frozenset({"ink"}), frozenset({"cartridge"}))


def test_offsets_collapse_one_step_at_a_time(plan):
    spacing = 25.0
    for rank in (0, 7, 23):
        view = api.plan_in_3d(plan, rank, spacing)
        assert len(view.offsets) == len(view.steps) + 1 == 6
        assert all(v == (0.0, 0.0, 0.0) for v in view.offsets[-1].values())
        for k, step in enumerate(view.steps):
            roles = view.roles(k)
            assert {p for p, r in roles.items() if r == "moving"} == step.moving
            assert {p for p, r in roles.items() if r == "fixed"} == step.fixed
            for part in view.parts:
                delta = [a - b for a, b in zip(view.offsets[k][part], view.offsets[k + 1][part])]
                away = spacing * (1 + k / 5)  # the later steps farther out
                expected = [away * c for c in step.direction.vector] if part in step.moving else [0, 0, 0]
                assert delta == pytest.approx(expected)
        assert set(view.roles(len(view.steps)).values()) == {"idle"}
    # Closed form: before step 0, a part sits at the weighted sum of the directions it moves along.
    view = api.plan_in_3d(plan, 0, 1.0)
    for part in view.parts:
        total = [sum((1 + j / 5) * s.direction.vector[i] for j, s in enumerate(view.steps) if part in s.moving)
                 for i in range(3)]
        assert list(view.offsets[0][part]) == pytest.approx(total)


def test_bad_sequences_are_refused_with_the_reason(plan):
    with pytest.raises(SequenceError, match=r"sequence rank 24 is out of range: the plan has 24 full assembly "
                                            r"sequences, ranked 0..23"):
        sequence_at(plan, 24)
    first = sequence_at(plan, 0)
    with pytest.raises(SequenceError, match=r"step 2 \(.*\) cannot follow the state"):
        check_sequence(plan, [first[0], first[0]])
    with pytest.raises(SequenceError, match="stops at the state .* before the product is complete"):
        exploded_view(plan, first[:3])
    with pytest.raises(SequenceError, match="operation 999"):
        check_sequence(plan, [999])


def test_with_a_base_part_it_never_moves(plan):
    count, listed = api.sequence_choices(plan, "body", limit=100)
    assert len(listed) == count > 0
    for rank in range(count):
        view = api.plan_in_3d(plan, rank, 1.0, "body")
        assert all("body" in step.fixed for step in view.steps if "body" in step.moving | step.fixed)
        assert view.offsets[0]["body"] == (0.0, 0.0, 0.0)  # the base part stays put throughout
