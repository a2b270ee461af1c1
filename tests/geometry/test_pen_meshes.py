"""The embedded pen's meshes (made by resources/examples/pen/make_meshes.py): reproducible, closed, and the mesh
engine finds on them the pen's liaisons and its ground-truth obstruction diagrams."""
from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
import trimesh
from conftest import PEN_MODELS, REPO, require_shared

from planner.geometry import PartMesh, analyze_meshes

PEN = REPO / "resources" / "examples" / "pen"
PARTS = ("ink", "cartridge", "head", "body", "cap", "button")
LIAISONS = {("ink", "cartridge"), ("cartridge", "head"), ("head", "body"), ("body", "cap"), ("body", "button")}


@pytest.fixture(scope="module")
def make_meshes():
    spec = importlib.util.spec_from_file_location("pen_make_meshes", PEN / "make_meshes.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def shipped() -> dict[str, trimesh.Trimesh]:
    return {part: trimesh.load(PEN / "meshes" / f"{part}.stl", force="mesh") for part in PARTS}


@pytest.fixture(scope="module")
def report(shipped):
    return analyze_meshes([PartMesh(part, np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64))
                           for part, mesh in shipped.items()])


def pen_json() -> dict:
    return json.loads((PEN / "pen.json").read_text())


def test_regenerated_meshes_are_byte_identical(make_meshes, tmp_path):
    paths = make_meshes.write_meshes(tmp_path)
    assert sorted(paths) == sorted(PARTS)
    for part, path in paths.items():
        assert path.read_bytes() == (PEN / "meshes" / f"{part}.stl").read_bytes(), part


def test_meshes_are_small_closed_solids(shipped):
    for part, mesh in shipped.items():
        assert (PEN / "meshes" / f"{part}.stl").stat().st_size < 50_000
        assert mesh.is_watertight and mesh.is_winding_consistent, part
        assert mesh.volume > 0, part


def test_pen_json_names_the_meshes_and_their_volumes(shipped):
    parts = {item["id"]: item for item in pen_json()["parts"]}
    assert sorted(parts) == sorted(PARTS)
    for part, mesh in shipped.items():
        assert parts[part]["mesh"] == f"meshes/{part}.stl"
        assert parts[part]["volume"] == pytest.approx(mesh.volume, abs=1e-3)


def test_volumes_agree_with_the_closed_forms(make_meshes):
    # A solid of revolution with n facets around: each radius r counts as a regular n-gon of area
    # n r^2 sin(2 pi / n) / 2 instead of pi r^2 (the ink is a rod of radius 6 and length 80).
    vertices, faces = make_meshes.pen_meshes()["ink"]
    n = make_meshes.SEGMENTS
    assert make_meshes.mesh_volume(vertices, faces) == pytest.approx(n * 36 * np.sin(2 * np.pi / n) / 2 * 80, rel=1e-6)


def test_contacts_are_the_five_liaisons(report):
    assert set(report.contacts) == LIAISONS
    assert report.interferences == () and report.warnings == ()


@pytest.mark.parametrize("axis", ["+X", "+Y", "+Z"])
def test_obstructions_equal_pen_json_and_ground_truth(report, axis):
    listed = {o["direction"]: {tuple(pair) for pair in o["blocks"]} for o in pen_json()["obstructions"]}
    path = require_shared(PEN_MODELS / "simplified" / "GroundTruth" / f"GeomConstraints_POS_{axis[1]}.json")
    truth = {(link["source"].removesuffix("_001"), link["target"].removesuffix("_001"))
             for link in json.loads(path.read_text())["links"]}
    assert set(report.obstructions[axis]) == listed[axis] == truth
