"""Motion directions besides the axes (mesh engine): found on the parts' faces and axes, tested like the
axes; expected directions in closed form (a part turned by 30 degrees about X)."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from aplan_runner import run_aplan

from planner import make_plan, plan_statistics
from planner.errors import InterlockedPartsError
from planner.geometry import PartMesh, Tolerances, analyze_meshes
from planner.geometry.bundle import apply_report
from planner.geometry.mesh_engine import candidate_directions
from planner.product import Part, Product

TURN = np.radians(30)
SLOT = np.array([0.0, -np.sin(TURN), np.cos(TURN)])      # +Z turned by 30 degrees about X
SIDE = np.array([0.0, np.cos(TURN), np.sin(TURN)])       # +Y turned the same way


def part(name: str, mesh: trimesh.Trimesh) -> PartMesh:
    return PartMesh(name, np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64))


def turned_box(extents) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents, transform=trimesh.transformations.rotation_matrix(TURN, [1, 0, 0]))


def same_line(u, v) -> bool:
    return abs(abs(float(np.dot(u, v))) - 1) < 1e-9


def test_a_turned_box_proposes_its_face_normals():
    found = candidate_directions([part("block", turned_box((10, 10, 30)))], limit=6)
    # Its faces' normals are X (an axis: merged), SIDE (a fifth of its area each side) and SLOT (the ends: too
    # small a share), and SLOT is its long axis (its normals turn around it).
    assert len(found) == 2 and all(np.isclose(np.linalg.norm(d), 1) for d in found)
    assert any(same_line(d, SLOT) for d in found) and any(same_line(d, SIDE) for d in found)
    assert candidate_directions([part("block", turned_box((10, 10, 30)))], limit=0) == []
    # A flat plate: its large faces propose their normal; no axis (its normals do not turn around a line).
    plate = candidate_directions([part("plate", turned_box((30, 30, 2)))], limit=6)
    assert len(plate) == 1 and same_line(plate[0], SLOT)


def test_a_turned_pin_proposes_its_axis():
    pin = trimesh.creation.cylinder(radius=2, height=40, sections=64,
                                    transform=trimesh.transformations.rotation_matrix(TURN, [1, 0, 0]))
    found = candidate_directions([part("pin", pin)], limit=6)
    assert found and same_line(found[0], SLOT)


def test_axis_aligned_parts_propose_nothing(pen):
    from planner.geometry.bundle import load_part_meshes

    assert candidate_directions(load_part_meshes(pen), limit=6) == []


def test_a_peg_in_an_inclined_slot_leaves_along_the_slot():
    """Along every axis the peg and the block block each other (a proof that, with the axes alone, they
    cannot be taken apart); along the slot the peg slides out, so the product has its one sequence."""
    block = trimesh.creation.box(extents=(30, 30, 30))
    slot = turned_box((10, 10, 80))
    holed = block.difference(slot)
    peg = turned_box((10, 10, 60))
    parts = [part("block", holed), part("peg", peg)]
    product = Product((Part("block"), Part("peg")), ())
    axes_only = apply_report(product, analyze_meshes(parts, Tolerances(directions=0)))
    with pytest.raises(InterlockedPartsError, match="block and peg"):
        make_plan(axes_only)
    report = analyze_meshes(parts)
    assert report.contacts == (("block", "peg"),)
    turned = [name for name in report.obstructions if name not in ("+X", "+Y", "+Z")]
    along = next(name for name in turned if same_line(report.directions[name], SLOT))
    assert report.obstructions[along] == ()   # sliding along the slot: nothing blocks either way
    planned = apply_report(product, report)
    assert any(o.direction.name == along for o in planned.obstructions)
    stats = plan_statistics(make_plan(planned))
    assert (stats.subassemblies, stats.sequences) == (3, 1)


def test_the_directions_option_is_checked_and_recorded(tmp_path):
    import json

    folder = tmp_path / "b"
    (folder / "meshes").mkdir(parents=True)
    trimesh.creation.box(extents=(30, 30, 30)).difference(turned_box((10, 10, 80))).export(folder / "meshes" / "block.stl")
    turned_box((10, 10, 60)).export(folder / "meshes" / "peg.stl")
    (folder / "product.json").write_text(json.dumps({
        "format": "aplan-product", "version": 1, "units": "mm", "contacts": [],
        "parts": [{"id": "block", "mesh": "meshes/block.stl"}, {"id": "peg", "mesh": "meshes/peg.stl"}]}))

    def aplan(*args):
        return run_aplan(*args)

    bad = aplan("analyze", str(folder), "--directions", "65")
    assert bad.returncode == 2 and "must be a whole number from 0 to 64, got 65" in bad.stderr
    assert aplan("analyze", str(folder), "--directions", "0", "-o", str(tmp_path / "axes.json")).returncode == 0
    refused = aplan("stats", str(tmp_path / "axes.json"))
    assert refused.returncode == 1 and "block and peg" in refused.stderr
    assert aplan("analyze", str(folder)).returncode == 0
    saved = json.loads((folder / "product.json").read_text())
    assert saved["geometry"]["analysis"]["tolerances"]["directions"] == 6
    assert len(saved["obstructions"]) > 3
    assert json.loads(aplan("stats", str(folder), "--json").stdout)["sequences"] == 1


def test_a_wheel_on_a_stub_in_its_blind_bore_leaves_along_the_axle():
    """The bore's rim is no outline of the wheel seen along its axle (the hub covers it), so the slivers
    between the stub and the bore, tessellated differently, are ignored as at an outline (a step in depth):
    the wheel is blocked towards the chassis only. The truck's five tires were interlocked with its chassis
    before this rule."""
    def along_x(mesh):
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
        return mesh

    def x_cylinder(radius, x0, x1, sections):
        mesh = along_x(trimesh.creation.cylinder(radius=radius, height=x1 - x0, sections=sections))
        mesh.apply_translation(((x0 + x1) / 2, 0, 0))
        return mesh

    wheel = x_cylinder(10, -12, 0, 96).difference(x_cylinder(2.5, -8, 0.5, 40))
    stub = trimesh.creation.box(extents=(10, 30, 30), transform=trimesh.transformations.translation_matrix((5, 0, 0)))
    stub = stub.union(x_cylinder(2.5, -8, 0.5, 28))
    report = analyze_meshes([part("wheel", wheel), part("stub", stub)], Tolerances(directions=0))
    assert report.contacts == (("wheel", "stub"),)
    assert set(report.obstructions["+X"]) == {("wheel", "stub")}
    assert set(report.obstructions["+Y"]) == set(report.obstructions["+Z"]) == {("wheel", "stub"), ("stub", "wheel")}
