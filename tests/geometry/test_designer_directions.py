"""The designer's directions and not-blocking marks (planner.product.designer): a block with k pegs in
parallel inclined slots cannot be taken apart along the six axes, and plans once the designer adds the slot's
direction or marks the relations that do not block. Expected counts in closed form: a star of k pegs around
the block, each free to leave, has 2^k + k connected part sets (each set of pegs with the block, and each peg
alone) and k! assembly sequences (the order in which the pegs go in)."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest
import trimesh

from planner import make_plan, plan_statistics
from planner.cli import main
from planner.errors import GeometryError, InterlockedPartsError, ProductFormatError
from planner.geometry import PartMesh, Tolerances, analyze_meshes
from planner.geometry.bundle import apply_report
from planner.product import Part, Product, load_product, product_to_dict
from planner.product.designer import (
    add_directions,
    designer_geometry,
    designer_lines,
    mark_not_blocking,
    parse_direction,
    release_marked,
    unmark_not_blocking,
)

TURN = np.radians(30)
SLOT = (0.0, -0.5, math.sqrt(3) / 2)          # +Z turned by 30 degrees about X: the slots' direction
PEGS = ("peg1", "peg2")


def _turned_box(extents, x: float = 0.0) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=extents, transform=trimesh.transformations.rotation_matrix(TURN, [1, 0, 0]))
    box.apply_translation((x, 0, 0))
    return box


def _meshes() -> dict[str, trimesh.Trimesh]:
    """A 50 x 30 x 30 block with two slots 10 x 10 along SLOT (at x = -12 and +12) and a peg in each."""
    block = trimesh.creation.box(extents=(50, 30, 30))
    for x in (-12, 12):
        block = block.difference(_turned_box((10, 10, 80), x))
    return {"block": block, "peg1": _turned_box((10, 10, 60), -12), "peg2": _turned_box((10, 10, 60), 12)}


@pytest.fixture(scope="module")
def parts() -> list[PartMesh]:
    return [PartMesh(n, np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)) for n, m in _meshes().items()]


def _product() -> Product:
    return Product(tuple(Part(n) for n in ("block", *PEGS)), (), geometry={"analysis": {}})


def _analysed(product: Product, parts, directions: int = 0) -> Product:
    designer = tuple(d.vector for d in designer_geometry(product).directions)
    report = analyze_meshes(parts, Tolerances(directions=directions, designer_directions=designer, resolution=512))
    return apply_report(product, report)


def _counts(product: Product) -> tuple[int, int]:
    stats = plan_statistics(make_plan(product))
    return stats.subassemblies, stats.sequences


def test_stuck_along_the_axes_planned_with_the_designer_direction(parts):
    axes_only = _analysed(_product(), parts)
    with pytest.raises(InterlockedPartsError, match="block and peg1; block and peg2"):
        make_plan(axes_only)
    with_slot, notes = add_directions(_product(), ["0,-1,1.7320508"])   # any length: normalised
    assert notes == [] and designer_geometry(with_slot).directions[0].vector == pytest.approx(SLOT)
    planned = _analysed(with_slot, parts)
    along = next(o for o in planned.obstructions if o.direction.name not in ("+X", "+Y", "+Z"))
    assert along.direction.vector == pytest.approx(SLOT) and along.blocks == ()
    k = len(PEGS)
    assert _counts(planned) == (2 ** k + k, math.factorial(k))
    # Recorded in the product file and the analysis; stats prints it.
    saved = product_to_dict(planned)["geometry"]
    assert saved["designer"]["directions"] == [list(along.direction.vector)]
    assert saved["analysis"]["tolerances"]["designer_directions"] == [list(along.direction.vector)]
    assert designer_lines(planned) == [f"designer directions (tested like the axes): {along.direction.name}"]


def test_directions_are_checked_and_duplicates_merged():
    product = _product()
    for bad, why in (("0,0,0", "zero vector"), ("1,nan,0", "finite"), ("1,2", "three numbers"), ("a,b,c", "three")):
        with pytest.raises(GeometryError, match=why):
            add_directions(product, [bad])
    once, notes = add_directions(product, [SLOT, tuple(-c for c in SLOT), "0.0001,0,1", "+y"])
    assert len(designer_geometry(once).directions) == 1
    assert [n.split(" merged with ")[1].split(" (")[0] for n in notes] == [
        f"the designer direction {designer_geometry(once).directions[0].name}", "the axis +Z", "the axis +Y"]
    assert parse_direction("-x") == (-1.0, 0.0, 0.0) and parse_direction("3,0,4") == (0.6, 0.0, 0.8)


def test_not_blocking_marks_release_pairs_and_survive_redetection(parts):
    axes_only = _analysed(_product(), parts)
    # peg1 moved along +Z is said not to hit the block: block and peg1 are no longer interlocked.
    marked, notes = mark_not_blocking(axes_only, [("peg1", "block", "+Z")])
    along_z = next(o for o in marked.obstructions if o.direction.name == "+Z")
    assert notes == [] and ("peg1", "block") not in along_z.blocks
    assert marked.geometry["designer"]["not_blocking"] == [
        {"blocked": "peg1", "blocking": "block", "direction": "+Z", "source": "designer"}]
    with pytest.raises(InterlockedPartsError, match=r"block and peg2\..*released 1 other pair\(s\): block and peg1"):
        make_plan(marked)
    # The same relation written along -Z is the one marked already; both pegs marked: the star's counts.
    both, notes = mark_not_blocking(marked, [("block", "peg1", "-Z"), ("peg2", "block", "+Z")])
    assert notes == ["block not blocked by peg1 along -Z: marked already"]
    k = len(PEGS)
    assert _counts(both) == (2 ** k + k, math.factorial(k))
    # Detected again: the marks are applied after the detection.
    again = _analysed(both, parts)
    assert again.obstructions == both.obstructions and _counts(again) == (2 ** k + k, math.factorial(k))
    assert sorted(map(tuple, again.geometry["analysis"]["designer"]["released"])) == [
        ("peg1", "block", "+Z"), ("peg2", "block", "+Z")]
    assert release_marked(again) == again   # idempotent
    # Unmarked: the pair it released is back, as a detection finds it.
    fewer = unmark_not_blocking(again, [("block", "peg2", "-Z")])
    assert fewer.obstructions == _analysed(fewer, parts).obstructions
    assert fewer.geometry["analysis"]["designer"]["released"] == [["peg1", "block", "+Z"]]
    with pytest.raises(InterlockedPartsError, match="block and peg2"):
        make_plan(fewer)
    with pytest.raises(GeometryError, match="no such designer mark"):
        unmark_not_blocking(fewer, [("peg2", "block", "+Z")])


def test_a_mark_along_a_found_direction_adds_it_to_the_designer_directions(parts):
    found = _analysed(_product(), parts, directions=6)
    slot = next(o.direction for o in found.obstructions if np.isclose(abs(np.dot(o.direction.vector, SLOT)), 1))
    marked, notes = mark_not_blocking(found, [("peg1", "block", slot.vector)])
    assert notes == [f"direction {slot.name} added to the designer directions (so that every detection tests it)"]
    assert len(designer_geometry(marked).directions) == 1


def test_bad_marks_are_clear_errors():
    product = _product()
    with pytest.raises(ProductFormatError, match=r"not_blocking\[0\]\.blocking: 'blok' is not a part id.*'block'"):
        mark_not_blocking(product, [("peg1", "blok", "+Z")])
    with pytest.raises(ProductFormatError, match="cannot block itself"):
        mark_not_blocking(product, [("peg1", "peg1", "+Z")])
    with pytest.raises(GeometryError, match="zero vector"):
        mark_not_blocking(product, [("peg1", "block", (0, 0, 0))])
    data = product_to_dict(product)
    mark = {"blocked": "peg1", "blocking": "block", "direction": [0, 0.6, 0.8]}
    data["geometry"]["designer"] = {"not_blocking": [mark]}
    from planner.product import product_from_dict

    with pytest.raises(ProductFormatError, match=r"not_blocking\[0\]\.direction: unknown direction"):
        product_from_dict(data, "p.json")


def _bundle(tmp_path):
    folder = tmp_path / "wedges"
    (folder / "meshes").mkdir(parents=True)
    for name, mesh in _meshes().items():
        mesh.export(folder / "meshes" / f"{name}.stl")
    (folder / "product.json").write_text(json.dumps({
        "format": "aplan-product", "version": 1, "units": "mm", "contacts": [],
        "parts": [{"id": n, "mesh": f"meshes/{n}.stl"} for n in ("block", *PEGS)]}))
    return folder


@dataclass
class _Done:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def aplan(capsys):
    """``aplan ARGS`` in this process (``planner.cli.main``): exit status, standard output and error."""
    def run(*args) -> _Done:
        if args[0] == "analyze":
            args += ("--resolution", "512")   # the slots are 10 mm wide: 512 pixels across 58 mm are plenty
        try:
            code = main(list(args))
        except SystemExit as exc:   # argparse: a usage error
            code = exc.code
        captured = capsys.readouterr()
        return _Done(code, captured.out, captured.err)
    return run


def test_the_direction_and_not_blocking_options(tmp_path, aplan):
    folder = _bundle(tmp_path)
    bad = aplan("analyze", str(folder), "--direction", "0,0,0")
    assert bad.returncode == 2 and "zero vector" in bad.stderr
    unknown = aplan("analyze", str(folder), "--directions", "0", "--not-blocking", "peg1", "blok", "+Z")
    assert unknown.returncode == 1 and "'blok' is not a part id" in unknown.stderr
    assert "designer" not in json.loads((folder / "product.json").read_text()).get("geometry", {})  # nothing written
    done = aplan("analyze", str(folder), "--directions", "0", "--direction", "0,-1,1.7320508", "--direction", "0,0,2")
    assert done.returncode == 0, done.stderr
    assert "merged with the axis +Z" in done.stderr and "designer directions (tested like the axes)" in done.stdout
    stats = aplan("stats", str(folder))
    assert stats.returncode == 0 and "designer directions (tested like the axes): [0, -0.5, 0.866025]" in stats.stdout
    k = len(PEGS)
    figures = json.loads(aplan("stats", str(folder), "--json").stdout)
    assert (figures["subassemblies"], figures["sequences"]) == (2 ** k + k, math.factorial(k))
    # Detected again (no --direction now): the recorded direction is tested again.
    assert aplan("analyze", str(folder), "--directions", "0").returncode == 0
    assert json.loads(aplan("stats", str(folder), "--json").stdout)["sequences"] == math.factorial(k)
    assert load_product(folder / "product.json").geometry["designer"]["directions"]


def test_stats_names_the_pairs_the_marks_released(tmp_path, aplan):
    """Two parts that block each other along every axis (interlocked); marked not blocking along +X, the pair
    is released: aplan stats plans it and says so."""
    from planner.product import Direction, Obstruction, save_product

    both = (("a", "b"), ("b", "a"))
    product = Product((Part("a"), Part("b")), (("a", "b"),),
                      tuple(Obstruction(Direction.from_vector(v), both) for v in ((1, 0, 0), (0, 1, 0), (0, 0, 1))),
                      geometry={"analysis": {"engine": "by hand"}})
    marked, _ = mark_not_blocking(product, [("a", "b", "+X"), ("b", "a", "+Y"), ("a", "b", "+Y")])
    save_product(marked, tmp_path / "p.json")
    done = aplan("stats", str(tmp_path / "p.json"))
    assert done.returncode == 0, done.stderr
    assert "designer mark: a not blocked by b along +X (released)" in done.stdout
    assert "designer marks released the interlocked pair a and b" in done.stdout
    assert "obstruction pairs released by designer marks: 3" in done.stdout
    with pytest.raises(InterlockedPartsError, match="a and b"):
        make_plan(product)
    assert _counts(marked) == (3, 1)
