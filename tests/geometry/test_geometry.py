"""The mesh geometry engine on shapes with known answers: boxes (closed form), a peg in a hole, thin walls."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.geometry import GeometryError, PartMesh, Tolerances, analyze_meshes


def part(name: str, mesh: trimesh.Trimesh) -> PartMesh:
    return PartMesh(name, np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64))


def box(name: str, lo, hi) -> PartMesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return part(name, trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2)))


def x_cylinder(name: str, radius: float, x0: float, x1: float, sections: int = 48, inner: float = 0.0) -> PartMesh:
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0])
    move = trimesh.transformations.translation_matrix(((x0 + x1) / 2, 0, 0))
    if inner:
        mesh = trimesh.creation.annulus(r_min=inner, r_max=radius, height=x1 - x0, sections=sections)
    else:
        mesh = trimesh.creation.cylinder(radius=radius, height=x1 - x0, sections=sections)
    mesh.apply_transform(move @ turn)
    return part(name, mesh)


def relation(report, axis):
    return set(report.obstructions[axis])


def test_stacked_boxes_touch_and_block_one_way():
    report = analyze_meshes([box("bottom", (0, 0, 0), (10, 10, 2)), box("top", (2, 2, 2), (8, 8, 4))])
    assert report.contacts == (("bottom", "top"),)
    assert relation(report, "+Z") == {("bottom", "top")}  # the bottom box moving up hits the top one
    assert relation(report, "+X") == set() and relation(report, "+Y") == set()  # sliding along the face is free


def test_peg_in_hole_slides_along_its_axis_only():
    # The two cylinders are tessellated differently, so their meshes overlap in thin slivers.
    tube = x_cylinder("tube", 10, 0, 50, sections=40, inner=4)
    peg = x_cylinder("peg", 4, -20, 30, sections=64)
    report = analyze_meshes([tube, peg])
    assert report.contacts == (("tube", "peg"),) and report.interferences == ()
    assert relation(report, "+X") == set()
    assert relation(report, "+Y") == {("tube", "peg"), ("peg", "tube")}
    assert relation(report, "+Z") == {("tube", "peg"), ("peg", "tube")}


def test_thin_obstacle_far_ahead_is_not_stepped_over():
    # A 0.05 mm sheet 100 mm ahead: no stepping along the motion, so it is always seen.
    report = analyze_meshes([box("block", (0, 0, 0), (5, 5, 5)), box("sheet", (105, -10, -10), (105.05, 15, 15))])
    assert relation(report, "+X") == {("block", "sheet")} and report.contacts == ()


def test_interference_is_contact_and_reported_above_the_tolerance():
    small = analyze_meshes([box("a", (0, 0, 0), (10, 10, 10)), box("b", (9.999, 0, 0), (20, 10, 10))])
    assert small.contacts == (("a", "b"),) and small.interferences == ()
    large = analyze_meshes([box("a", (0, 0, 0), (10, 10, 10)), box("b", (9, 0, 0), (20, 10, 10))])
    ((a, b, volume),) = large.interferences
    assert (a, b) == ("a", "b") and volume == pytest.approx(100.0, rel=1e-6)
    assert "interpenetrate by 100 cubic units" in large.warnings[0]


def test_gap_within_the_contact_tolerance():
    near = [box("a", (0, 0, 0), (1, 1, 1)), box("b", (1.05, 0, 0), (2, 1, 1))]
    assert analyze_meshes(near, Tolerances(contact=0.1)).contacts == (("a", "b"),)
    assert analyze_meshes(near, Tolerances(contact=0.01)).contacts == ()


def test_open_mesh_is_rejected_by_name():
    mesh = trimesh.creation.box(extents=(1, 1, 1))
    open_box = PartMesh("lid", np.asarray(mesh.vertices, float), np.asarray(mesh.faces[:-1], np.int64))
    with pytest.raises(GeometryError, match=r"part 'lid': its mesh is not a closed"):
        analyze_meshes([box("a", (2, 0, 0), (3, 1, 1)), open_box])


def test_flat_mesh_is_rejected_by_name():
    flat = PartMesh("sheet", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 2], [0, 2, 1]]))
    with pytest.raises(GeometryError, match=r"part 'sheet'"):
        analyze_meshes([flat])


# Boxes on an integer grid have a closed-form obstruction relation: x is blocked by y along +X when their
# projections on the YZ plane overlap with positive area and y reaches beyond x's start along X.

@st.composite
def separate_boxes(draw):
    """2 to 5 boxes, each inside its own cell of a 3x3x3 grid of 4-unit cells (so they can touch, not overlap)."""
    cells = draw(st.lists(st.tuples(*[st.integers(0, 2)] * 3), min_size=2, max_size=5, unique=True))
    boxes = []
    for cell in cells:
        lo = np.array([4 * c + draw(st.integers(0, 2)) for c in cell])
        hi = np.array([min(4 * c + 4, l + draw(st.integers(1, 4))) for c, l in zip(cell, lo)])
        boxes.append((lo, hi))
    return boxes


@given(separate_boxes())
@settings(max_examples=40, deadline=None)
def test_boxes_match_the_closed_form(boxes):
    parts = [box(f"b{i}", lo, hi) for i, (lo, hi) in enumerate(boxes)]
    report = analyze_meshes(parts)
    for axis, name in enumerate(("+X", "+Y", "+Z")):
        others = [k for k in range(3) if k != axis]
        expected = set()
        for i, (lo_i, hi_i) in enumerate(boxes):
            for j, (lo_j, hi_j) in enumerate(boxes):
                overlap = all(min(hi_i[k], hi_j[k]) > max(lo_i[k], lo_j[k]) for k in others)
                if i != j and overlap and hi_j[axis] > lo_i[axis]:
                    expected.add((f"b{i}", f"b{j}"))
        assert relation(report, name) == expected, name
    touching = {(f"b{i}", f"b{j}") for i in range(len(boxes)) for j in range(i + 1, len(boxes))
                if all(min(boxes[i][1][k], boxes[j][1][k]) >= max(boxes[i][0][k], boxes[j][0][k]) for k in range(3))}
    assert set(report.contacts) == touching


def _erode_by_hand(mask: np.ndarray, radius: int) -> np.ndarray:
    """The mesh engine's erosion before it used scipy: ``radius`` times, a pixel stays when it and its 8
    neighbours are set; pixels beyond the border count as not set."""
    out = mask.copy()
    for _ in range(radius):
        padded = np.pad(out, 1, constant_values=False)
        out = padded[1:-1, 1:-1].copy()
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                out &= padded[1 + di:padded.shape[0] - 1 + di, 1 + dj:padded.shape[1] - 1 + dj]
    return out


def test_erosion_equals_the_hand_written_one():
    from planner.geometry.projection import _erode

    rng = np.random.default_rng(7)
    eroded = 0
    for trial in range(400):
        shape = tuple(int(n) for n in rng.integers(1, 40, size=2))
        density = rng.choice([0.5, 0.8, 0.95, 1.0])
        mask = rng.random(shape) < density
        radius = int(rng.integers(0, 5))
        expected = _erode_by_hand(mask, radius)
        assert np.array_equal(_erode(mask, radius), expected), (trial, shape, density, radius)
        eroded += int(expected.sum() < mask.sum())
    assert eroded > 200  # most cases did remove pixels: the comparison is not between unchanged masks
