"""A machine too large to judge flat with a closed gearbox as one of its workstations (issue 26): the
support-contact rule (planner.assembly.support_contacts) cannot say whether the flat product needs its
contacts (past CHECK_LIMIT connected part sets), so it records its candidates and the levels judge them
(planner.assembly.level_supports): the gearbox's level gets a support contact per gear, said in one line
naming the level, and every level plans; ``--support-contacts error`` refuses naming the level, ``keep`` leaves
the level's error."""
from __future__ import annotations

import logging
from dataclasses import replace

import pytest
import trimesh

from aplan_runner import run_aplan
from planner import NotDisassemblableError, Part, Product, and_or_graph, api, resolve_product
from planner.product import Subassembly
from planner.assembly.andor import connected_sets_bound, liaison_adjacency
from planner.assembly.hierarchy import product_levels
from planner.assembly.level_supports import CANDIDATES_KEY, with_level_supports
from planner.assembly.subassembly_proposals import with_subassemblies
from planner.assembly.support_contacts import CHECK_LIMIT, apply_support_mode, support_contacts
from planner.errors import PlannerError, SupportRefusedError
from planner.product.io import save_product

from test_floating_parts import BOXES, box_meshes, closed_gearbox

GEARBOX = ("housing", "shaft_a", "shaft_b", "gear_a", "gear_b")
#: Brackets on the machine's base plate, each touching it alone: the plate and any set of its brackets are
#: connected, 2^20 sets with the plate alone, more than CHECK_LIMIT.
BRACKETS = tuple(f"bracket{k}" for k in range(20))


def machine_boxes() -> dict:
    """The gearbox's boxes (tests/assembly/test_floating_parts.py) on a base plate z -10..0, with a row of
    10 x 10 x 20 brackets along its front edge (y -40..-30), clear of the gearbox and of each other."""
    boxes = {**BOXES, "plate": ((-300, -50, -10), (400, 110, 0))}
    for k, bracket in enumerate(BRACKETS):
        x = -290 + 30 * k if k < 9 else 110 + 30 * (k - 9)
        boxes[bracket] = ((x, -40, 0), (x + 10, -30, 20))
    return boxes


def machine() -> Product:
    """The closed gearbox (its diagrams) resting on the plate, the brackets standing on it: moving +Z the plate
    hits everything above it; along X and Y nothing else meets (the brackets stand apart)."""
    gearbox = closed_gearbox()
    above = GEARBOX + BRACKETS
    obstructions = tuple(replace(o, blocks=o.blocks + tuple(("plate", p) for p in above))
                         if o.direction.name == "+Z" else o for o in gearbox.obstructions)
    parts = gearbox.parts + (Part("plate", volume=7000.0),) + tuple(Part(b, volume=2.0) for b in BRACKETS)
    contacts = gearbox.contacts + (("plate", "housing"),) + tuple(("plate", b) for b in BRACKETS)
    return Product(parts, contacts, obstructions, name="machine")


def bundle(folder) -> Product:
    """The machine as a bundle in ``folder``: its product file (analysed) and a mesh file per part (its box)."""
    for mesh in box_meshes(machine_boxes()):
        trimesh.Trimesh(mesh.vertices, mesh.faces).export(folder / f"{mesh.id}.stl")
    product = replace(machine(), parts=tuple(replace(p, mesh=f"{p.id}.stl") for p in machine().parts),
                      geometry={"analysis": {"engine": "mesh"}}, source=str(folder / "product.json"))
    save_product(product, folder / "product.json")
    return product


def gearbox_level(product: Product):
    return next(level for level in product_levels(product) if "housing" in level.members)


def test_the_flat_machine_is_past_the_check_limit_so_the_flat_rule_does_not_judge_it():
    assert connected_sets_bound(liaison_adjacency(machine())) >= 2 ** len(BRACKETS) > CHECK_LIMIT
    assert support_contacts(machine(), box_meshes(machine_boxes())) == (machine(), ())


def test_without_the_level_rule_the_gearbox_workstation_cannot_be_taken_apart():
    proposed = with_subassemblies(machine(), "auto")
    level = gearbox_level(proposed)
    assert set(level.members) == set(GEARBOX)
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(level.product)
    assert info.value.floating_parts == ("gear_a",)


def test_the_gearbox_level_gets_a_support_contact_per_gear_and_every_level_plans(tmp_path, caplog):
    bundle(tmp_path)
    with caplog.at_level(logging.INFO, logger="planner"):
        product = resolve_product(tmp_path, subassemblies="auto")
    level = gearbox_level(product)
    assert set(level.members) == set(GEARBOX)  # the gearbox is one workstation of its own
    records = product.geometry["analysis"]["support_contacts"]
    assert [(r["parts"], r["level"]) for r in records] == [(["gear_a", "housing"], level.id),
                                                          (["gear_b", "housing"], level.id)]
    assert set(product.contacts) - set(machine().contacts) == {("gear_a", "housing"), ("gear_b", "housing")}
    assert CANDIDATES_KEY not in product.geometry["analysis"]  # consumed by the levels
    for each in product_levels(product):
        and_or_graph(each.product)
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("support contacts")]
    assert lines == [f"support contacts: level {level.id}: gear_a rests in housing (inside its box, walled in along "
                     "5 of the 6 axis directions); gear_b rests in housing (inside its box, walled in along 5 of the 6 "
                     "axis directions): the level cannot be taken apart otherwise (once what holds such a part is "
                     "out, it would touch none of the parts left, and a subassembly must be connected in the "
                     "connection diagram); --support-contacts error to refuse instead"]
    # The proposals counted the gearbox buildable with its contacts: no warning that it cannot be built.
    assert not any("cannot be built on its own" in r.getMessage() for r in caplog.records)


def test_error_refuses_naming_the_level_and_keep_leaves_the_levels_error(tmp_path):
    bundle(tmp_path)
    with pytest.raises(SupportRefusedError) as info:
        resolve_product(tmp_path, subassemblies="auto", supports="error")
    assert info.value.contacts == (("gear_a", "housing"), ("gear_b", "housing"))
    message = str(info.value)
    assert "\n" not in message and message.startswith("machine: level sa1: 2 support contact(s) refused by "
                                                      "--support-contacts error: gear_a rests in housing")
    assert "--group NAME=housing,gear_a" in message
    kept = resolve_product(tmp_path, subassemblies="auto", supports="keep")
    assert kept.contacts == machine().contacts
    with pytest.raises(NotDisassemblableError, match="taking shaft_a out would leave gear_a touching nothing"):
        and_or_graph(gearbox_level(kept).product)


def test_a_level_that_plans_already_gets_nothing(caplog):
    # The candidates recorded (the flat product is not judged), then the gears' contacts given: the gearbox's
    # level plans, and nothing is added or said; the record is consumed all the same.
    recorded = apply_support_mode(machine(), "add", box_meshes(machine_boxes()))
    assert [c["parts"] for c in recorded.geometry["analysis"][CANDIDATES_KEY]["contacts"]] == [
        ["gear_a", "housing"], ["gear_b", "housing"]]
    given = replace(recorded, contacts=recorded.contacts + (("gear_a", "housing"), ("gear_b", "housing")))
    with caplog.at_level(logging.INFO, logger="planner"):
        proposed = with_subassemblies(given, "auto")
    assert proposed.contacts == given.contacts and "support_contacts" not in proposed.geometry["analysis"]
    assert CANDIDATES_KEY not in proposed.geometry["analysis"] and not caplog.records
    assert with_level_supports(proposed) is proposed  # nothing recorded: nothing to do


def test_the_command_line_plans_every_workstation_with_the_default_flags(tmp_path):
    bundle(tmp_path)
    done = run_aplan("stats", tmp_path)
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.startswith("aplan: support contacts: ")]
    assert len(lines) == 1 and lines[0].startswith("aplan: support contacts: level sa1: gear_a rests in housing")
    assert "cannot be disassembled" not in done.stderr + done.stdout


def test_a_candidates_record_read_with_the_product_takes_the_modes_of_the_command(tmp_path):
    # The record written with the product (aplan fasteners -o keeps the geometry as it is), its meshes gone: the
    # levels judge the recorded candidates, in the mode asked for now; a record edited by hand is refused.
    recorded = apply_support_mode(machine(), "add", box_meshes(machine_boxes()))
    path = tmp_path / "machine.json"
    save_product(recorded, path)
    assert ("gear_a", "housing") in resolve_product(path, subassemblies="auto").contacts
    with pytest.raises(SupportRefusedError, match="level sa1: 2 support contact"):
        resolve_product(path, subassemblies="auto", supports="error")
    assert resolve_product(path, subassemblies="auto", supports="keep").contacts == machine().contacts
    broken = replace(recorded, geometry={"analysis": {CANDIDATES_KEY: {"mode": "add", "contacts": [{"parts": []}]}}})
    save_product(broken, path)
    with pytest.raises(PlannerError, match=r"machine.json: geometry.analysis.support_candidates: expected .*; delete "
                                           r"it \(the support-contact rule records it again from the meshes\)$"):
        resolve_product(path, subassemblies="auto")


def test_a_product_with_its_own_subassemblies_is_judged_when_it_is_read(tmp_path, caplog):
    # The gearbox as the designer's subassembly (a document's container): resolved without choosing a mode, its
    # levels are known, so they are judged at once, in one line, and every later look at them is as planned
    # (the top level, the plate and its 20 brackets with the gearbox, is past the limit itself: not planned here).
    product = replace(bundle(tmp_path), subassemblies=(Subassembly("gearbox", GEARBOX, "Gearbox"),))
    save_product(product, tmp_path / "product.json")
    with caplog.at_level(logging.INFO, logger="planner"):
        resolved = resolve_product(tmp_path)
        for _ in range(2):  # the levels looked at again: nothing more to judge, nothing said
            and_or_graph(next(lv for lv in api.levels_of(resolved) if lv.id == "gearbox").product)
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("support contacts")]
    assert len(lines) == 1 and lines[0].startswith("support contacts: level gearbox: gear_a rests in housing")
    assert [r["level"] for r in resolved.geometry["analysis"]["support_contacts"]] == ["gearbox", "gearbox"]


def test_a_detection_records_the_candidates_and_the_levels_proposals_name_the_gearbox_level():
    """What the workbench's detection records of the machine (too large to judge flat): the rule's candidates,
    mode add, and no flat proposal; at the levels of the machine's subassemblies, the proposals are the two
    gears resting in the housing, at the gearbox's level (as the command line adds them)."""
    recorded = api.record_detection_proposals(machine(), box_meshes(machine_boxes()))
    analysis = recorded.geometry["analysis"]
    assert analysis[CANDIDATES_KEY]["mode"] == "add" and "support_proposals" not in analysis
    assert [c["parts"] for c in analysis[CANDIDATES_KEY]["contacts"]] == [["gear_a", "housing"],
                                                                           ["gear_b", "housing"]]
    assert api.level_support_proposals(recorded) == []  # planned flat: no level to judge them
    chosen = replace(recorded, subassemblies=with_subassemblies(machine(), "auto").subassemblies)
    level = gearbox_level(chosen)
    proposals = api.level_support_proposals(chosen)
    assert [(p["rule"], p["parts"], p["level"]) for p in proposals] == [("support", ["gear_a", "housing"], level.id),
                                                                        ("support", ["gear_b", "housing"], level.id)]
    assert proposals[0]["text"].startswith(f"level {level.id}: gear_a rests in housing")
    # What they propose is what planning adds.
    added = with_level_supports(chosen)
    assert [r["parts"] for r in added.geometry["analysis"]["support_contacts"]] == [p["parts"] for p in proposals]
    # One candidate dropped (the workbench drops those the designer rejected): the other alone does not free
    # the level (gear_a would still float), so the rule proposes nothing there and the level's plan names it.
    one = {**analysis[CANDIDATES_KEY], "contacts": analysis[CANDIDATES_KEY]["contacts"][1:]}
    fewer = replace(chosen, geometry={**chosen.geometry, "analysis": {**analysis, CANDIDATES_KEY: one}})
    assert api.level_support_proposals(fewer) == []
    with pytest.raises(NotDisassemblableError, match="gear_a"):
        and_or_graph(gearbox_level(with_level_supports(fewer)).product)
