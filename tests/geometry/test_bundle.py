"""Bundles without FreeCAD: aplan analyze on meshes written by the test, and its errors."""
from __future__ import annotations

import json

import trimesh
from aplan_runner import run_aplan

from planner import load_product, resolve_product

PRODUCT = {"format": "aplan-product", "version": 1, "units": "mm",
           "parts": [{"id": "base", "mesh": "meshes/base.stl"}, {"id": "peg", "mesh": "meshes/peg.stl"},
                     {"id": "lid", "mesh": "meshes/lid.stl"}],
           "contacts": [], "geometry": {"source": "made by the test"}}


def make_bundle(folder):
    (folder / "meshes").mkdir(parents=True)
    boxes = {"base": ((0, 0, 0), (10, 10, 2)), "peg": ((4, 4, 2), (6, 6, 8)), "lid": ((0, 0, 8), (10, 10, 9))}
    for name, (lo, hi) in boxes.items():
        center = [(a + b) / 2 for a, b in zip(lo, hi)]
        mesh = trimesh.creation.box(extents=[b - a for a, b in zip(lo, hi)],
                                    transform=trimesh.transformations.translation_matrix(center))
        mesh.export(folder / "meshes" / f"{name}.stl")
    (folder / "product.json").write_text(json.dumps(PRODUCT))
    return folder


def aplan(*args):
    return run_aplan(*args)


def test_analyze_fills_in_the_diagrams(tmp_path):
    bundle = make_bundle(tmp_path / "b")
    done = aplan("analyze", str(bundle))
    assert done.returncode == 0, done.stderr
    assert "3 parts, 2 contacts, 0 interferences (mesh engine" in done.stdout
    product = load_product(bundle / "product.json")
    assert {frozenset(c) for c in product.contacts} == {frozenset(("base", "peg")), frozenset(("peg", "lid"))}
    blocks = {o.direction.name: set(o.blocks) for o in product.obstructions}
    assert blocks["+Z"] == {("base", "peg"), ("base", "lid"), ("peg", "lid")}
    assert blocks["+X"] == set() and blocks["+Y"] == set()
    assert product.geometry["source"] == "made by the test" and product.geometry["analysis"]["engine"] == "mesh"
    stats = json.loads(aplan("stats", str(bundle), "--json").stdout)
    # 3 single parts, {base, peg}, {peg, lid}, the whole; base+peg then lid, or peg+lid then base
    assert (stats["subassemblies"], stats["sequences"]) == (6, 2)


def test_unanalysed_bundle_is_analysed_when_planned(tmp_path):
    bundle = make_bundle(tmp_path / "b")
    before = (bundle / "product.json").read_bytes()
    assert len(resolve_product(bundle).contacts) == 2
    assert (bundle / "product.json").read_bytes() == before  # planning never rewrites the bundle


def test_output_elsewhere(tmp_path):
    bundle = make_bundle(tmp_path / "b")
    before = (bundle / "product.json").read_bytes()
    assert aplan("analyze", str(bundle), "-o", str(tmp_path / "out.json"), "--json").returncode == 0
    assert (bundle / "product.json").read_bytes() == before
    assert len(load_product(tmp_path / "out.json").contacts) == 2


def test_bad_meshes_name_the_part_and_change_nothing(tmp_path):
    bundle = make_bundle(tmp_path / "b")
    before = (bundle / "product.json").read_bytes()
    (bundle / "meshes" / "peg.stl").unlink()
    done = aplan("analyze", str(bundle))
    assert done.returncode == 1 and "part 'peg': mesh file" in done.stderr and "does not exist" in done.stderr
    (bundle / "meshes" / "peg.stl").write_bytes(b"solid nonsense\nfacet oops\n")
    done = aplan("analyze", str(bundle))
    assert done.returncode == 1 and "part 'peg'" in done.stderr
    mesh = trimesh.creation.box(extents=(1, 1, 1))
    trimesh.Trimesh(mesh.vertices, mesh.faces[:-2]).export(bundle / "meshes" / "peg.stl")
    done = aplan("analyze", str(bundle))
    assert done.returncode == 1 and "part 'peg': its mesh is not a closed" in done.stderr
    assert (bundle / "product.json").read_bytes() == before
    assert sorted(p.name for p in bundle.iterdir()) == ["meshes", "product.json"]


def test_unknown_engine(tmp_path):
    bundle = make_bundle(tmp_path / "b")
    done = aplan("analyze", str(bundle), "--engine", "magic")
    assert done.returncode == 1 and "unknown geometry engine 'magic'; available: mesh, occt" in done.stderr


def test_analyse_bundle_is_the_one_analysis_and_save(tmp_path):
    """analyse_bundle (what aplan analyze, the workbench and the FreeCAD export run): the engine's report applied
    and written; a report found elsewhere (the workbench's OCCT run) is applied as given, without the engine."""
    from dataclasses import replace

    from planner.geometry.bundle import analyse_bundle, load_bundle

    bundle = make_bundle(tmp_path / "b")
    product = load_bundle(bundle)
    analysed, report = analyse_bundle(product, bundle / "product.json")
    assert load_product(bundle / "product.json").contacts == analysed.contacts and len(report.contacts) == 2
    given = replace(report, contacts=(("base", "lid"),), engine="given")
    again, same = analyse_bundle(product, tmp_path / "given.json", "no such engine", report=given)
    assert same is given and {frozenset(c) for c in again.contacts} == {frozenset(("base", "lid"))}
    assert load_product(tmp_path / "given.json").geometry["analysis"]["engine"] == "given"
