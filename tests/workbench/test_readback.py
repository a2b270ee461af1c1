"""The analysis' structure entries fitted to the exported components (freecad_aplan.readback; plain Python, no
FreeCAD): kept, mapped onto a group, dropped, dissolved, each change one warning naming the entry and member."""
from __future__ import annotations

from freecad_aplan.readback import fit_fasteners, fit_subassemblies

# Components and their objects' internal names: the bolt's objects were grouped with the nut into 'bolted'.
OBJECTS = {"base": ["Box"], "lid": ["Box001"], "bolted": ["Screw", "Nut"], "axle": ["Cyl"]}
LABELS = {"Box": "base", "Box001": "lid", "Screw": "screw_1", "Nut": "nut_1", "Cyl": "axle", "Gone": "washer"}


def test_members_are_kept_mapped_or_dropped():
    tree = [{"id": "top_half", "parts": ["lid", "screw_1", "washer"]},
            {"id": "frame", "parts": ["base", "top_half", "Nut", "axle"]}]
    fitted, warnings = fit_subassemblies(tree, OBJECTS, LABELS, "tree")
    # screw_1 (a label) is now in 'bolted'; washer is gone; Nut maps to 'bolted' again, already in top_half
    assert fitted == [{"id": "top_half", "parts": ["lid", "bolted"]},
                      {"id": "frame", "parts": ["base", "top_half", "axle"]}]
    assert warnings == [
        "tree: 'top_half' lists 'screw_1', which the export made part of the component 'bolted': 'bolted' stands "
        "for it",
        "tree: 'top_half' lists 'washer', which is no exported part (excluded, folded, or the input of another "
        "feature): dropped from it",
        "tree: 'frame' lists 'Nut', which the export made part of the component 'bolted': 'bolted' stands for it",
        "tree: 'bolted' is in 'top_half' already: dropped from 'frame'"]


def test_a_subassembly_left_with_one_member_is_dissolved_up_the_tree():
    tree = [{"id": "inner", "parts": ["lid", "washer"]}, {"id": "outer", "parts": ["inner", "Gone"]},
            {"id": "whole", "parts": ["outer", "base"]}]
    fitted, warnings = fit_subassemblies(tree, OBJECTS, LABELS, "tree")
    assert fitted == [{"id": "whole", "parts": ["lid", "base"]}]  # inner, then outer stand for lid
    assert "tree: 'inner' is dissolved: it is left only 'lid', which takes its place" in warnings
    assert "tree: 'outer' is dissolved: it is left only 'lid', which takes its place" in warnings


def test_fastener_tags_keep_only_components_of_their_own():
    tags = [{"id": "g1", "objects": ["Screw", "Gone"], "hosts": ["Box", "Box001"]},  # Screw is grouped with Nut
            {"id": "g2", "objects": ["Cyl"], "hosts": ["Box", "Gone"], "tool": "press"},  # one host is left
            {"id": "g3", "objects": ["Screw", "Nut"], "hosts": ["Box", "Box001"]}]
    kept, warnings = fit_fasteners(tags, OBJECTS, LABELS)
    assert kept == [tags[2]]
    assert warnings == [
        "fastener group 'g1': 'screw_1' is grouped with other objects into 'bolted': dropped from it (ungroup it "
        "to tag it as a fastener)",
        "fastener group 'g1': 'washer' is no exported part (left out or missing): dropped from it",
        "fastener group 'g1': no fastener left: the group is dropped (its parts are planned as parts)",
        "fastener group 'g2': its host 'washer' is no exported part: dropped",
        "fastener group 'g2': fewer than two hosts left: the group is dropped (its parts are planned as parts)"]
