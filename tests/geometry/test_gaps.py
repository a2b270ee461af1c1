"""Gaps between parts and groups, --contact auto and its ceiling, the "everything touches" warning, and the
gaps named when a product falls apart: on boxes at known distances (every gap in closed form)."""
from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest
import trimesh
from aplan_runner import run_aplan

from planner import api, load_product
from planner.errors import ContactCeilingError, DisconnectedProductError, GeometryError
from planner.geometry import PartMesh, Tolerances, analyze_product, apply_report
from planner.geometry.gaps import connection_groups, contact_tolerance_for, gap_report, mesh_gaps, part_gaps
from planner.geometry.mesh_engine import analyze_meshes
from planner.product import save_product


def box(name: str, lo, hi) -> PartMesh:
    center = [(a + b) / 2 for a, b in zip(lo, hi)]
    mesh = trimesh.creation.box(extents=[b - a for a, b in zip(lo, hi)],
                                transform=trimesh.transformations.translation_matrix(center))
    return PartMesh(name, np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64))


def test_gaps_between_boxes_are_exact():
    unit = box("a", (0, 0, 0), (1, 1, 1))
    face = box("face", (1.3, 0.2, 0.2), (2, 0.8, 0.8))            # face to face: 0.3
    edge = box("edge", (1.3, 1.4, 0), (2, 2, 1))                  # edge to edge: sqrt(0.3^2 + 0.4^2)
    corner = box("corner", (1.2, 1.3, 1.6), (2, 2, 2))            # corner to corner: sqrt(.2^2 + .3^2 + .6^2)
    touching = box("touching", (1, 0, 0), (2, 1, 1))
    gaps = part_gaps([unit, face, edge, corner, touching], [("a", n) for n in ("face", "edge", "corner", "touching")])
    assert gaps["a", "face"] == pytest.approx(0.3, abs=1e-9)
    assert gaps["a", "edge"] == pytest.approx(0.5, abs=1e-9)
    assert gaps["a", "corner"] == pytest.approx(0.7, abs=1e-9)
    assert gaps["a", "touching"] == 0.0


def chain():
    """a1|a2 touching, b 0.5 from a2, c 2.0 from b (3.5 from a2), z far away but joined to c by a contact."""
    parts = [box("a1", (0, 0, 0), (1, 1, 1)), box("a2", (1, 0, 0), (2, 1, 1)), box("b", (2.5, 0, 0), (3.5, 1, 1)),
             box("c", (5.5, 0, 0), (6.5, 1, 1)), box("z", (1000, 0, 0), (1001, 1, 1))]
    return parts, [("a1", "a2"), ("c", "z")]


def test_nearest_gaps_and_the_tolerance_that_joins_every_group():
    parts, contacts = chain()
    report = mesh_gaps(parts, contacts)
    assert report.groups == (("a1", "a2"), ("b",), ("c", "z"))
    assert [(g.a, g.b) for g in report.nearest] == [("a2", "b"), ("b", "a2"), ("c", "b")]
    assert [g.distance for g in report.nearest] == pytest.approx([0.5, 0.5, 2.0])
    assert [(g.a, g.b) for g in report.joining] == [("a2", "b"), ("b", "c")]
    assert report.bottleneck == pytest.approx(2.0)
    # Exact distances only for the pairs whose boxes are within the bottleneck (2.0): a2-b, a1-b, b-c; z is
    # 993.5 away from everything it is not joined to and never measured.
    assert report.queries == 3


def test_a_connected_diagram_has_nothing_to_join():
    parts, _ = chain()
    report = mesh_gaps(parts[:2], [("a1", "a2")])
    assert report.groups == (("a1", "a2"),) and report.joining == () and report.bottleneck == 0.0


def test_recorded_gaps_give_the_same_report():
    parts, contacts = chain()
    measured = mesh_gaps(parts, contacts)
    again = gap_report([list(g) for g in measured.groups], [g.as_list() for g in measured.visited])
    assert again.nearest == measured.nearest and again.joining == measured.joining
    # Coarser groups (a contact added): the same gaps still explain them.
    coarse = gap_report([["a1", "a2", "b"], ["c", "z"]], measured.visited)
    assert [(g.a, g.b) for g in coarse.nearest] == [("b", "c"), ("c", "b")]


def test_connection_groups():
    assert connection_groups(["a", "b", "c", "d"], [("d", "b")]) == [["a"], ["b", "d"], ["c"]]


@pytest.mark.parametrize("gap, tolerance", [(6.1595, 6.16), (30.5404, 30.6), (0.4941, 0.495), (2.0, 2.01),
                                            (0.12339997, 0.124), (0.0, 0.0), (123.4, 124.0)])
def test_contact_tolerance_is_the_gap_rounded_up(gap, tolerance):
    assert contact_tolerance_for(gap) == pytest.approx(tolerance)
    assert gap == 0 or contact_tolerance_for(gap) > gap


def test_the_contact_test_agrees_with_the_gaps():
    """The mesh engine's contacts at a tolerance are the pairs whose gap is at most it (FCL above the default
    tolerance, manifold's query at it): the chain's 0.5 and 2.0 gaps join at 0.501 and 2.01, not below."""
    parts, _ = chain()
    contacts = lambda t: {frozenset(c) for c in analyze_meshes(parts[:4], Tolerances(contact=t, resolution=64)).contacts}
    assert contacts(0.1) == {frozenset(("a1", "a2"))}
    assert contacts(0.499) == {frozenset(("a1", "a2"))}
    assert contacts(0.501) == {frozenset(("a1", "a2")), frozenset(("a2", "b"))}
    assert contacts(2.01) == {frozenset(p) for p in [("a1", "a2"), ("a2", "b"), ("b", "c"), ("a1", "b")]}


# ----------------------------------------------------------------------------------------------- bundles

def make_bundle(folder, boxes: dict, contacts=()):
    (folder / "meshes").mkdir(parents=True)
    for name, (lo, hi) in boxes.items():
        center = [(a + b) / 2 for a, b in zip(lo, hi)]
        trimesh.creation.box(extents=[b - a for a, b in zip(lo, hi)],
                             transform=trimesh.transformations.translation_matrix(center)).export(
            folder / "meshes" / f"{name}.stl")
    product = {"format": "aplan-product", "version": 1, "units": "mm",
               "parts": [{"id": n, "mesh": f"meshes/{n}.stl"} for n in boxes],
               "contacts": [list(c) for c in contacts], "geometry": {"source": "made by the test"}}
    (folder / "product.json").write_text(json.dumps(product))
    return folder


# The peg floats 0.1234 above the base (0.12339997 in the STL's single precision); the lid sits on the peg.
PEG = {"base": ((0, 0, 0), (10, 10, 2)), "peg": ((4, 4, 2.1234), (6, 6, 8)), "lid": ((0, 0, 8), (10, 10, 9))}


def aplan(*args):
    """``aplan`` (in this process); ``analyze`` with a coarse raster (the obstructions do not matter here)."""
    extra = ["--resolution", "64"] if args[0] == "analyze" else []
    return run_aplan(*args, *extra)


def test_auto_chooses_the_smallest_tolerance_that_connects_and_records_it(tmp_path):
    bundle = make_bundle(tmp_path / "b", PEG)
    product = load_product(bundle / "product.json")
    report = analyze_product(product, "mesh", Tolerances(contact="auto", resolution=64))
    assert {frozenset(c) for c in report.contacts} == {frozenset(("base", "peg")), frozenset(("peg", "lid"))}
    auto = report.tolerances["contact_auto"]
    diagonal = math.sqrt(10 ** 2 + 10 ** 2 + 9 ** 2)
    assert auto["chosen"] == pytest.approx(0.124) and report.tolerances["contact"] == pytest.approx(0.124)
    assert auto["ceiling"] == pytest.approx(0.01 * diagonal, rel=1e-5) and auto["default"] == 0.1
    [(a, b, gap)] = auto["gaps_joined"]
    assert (a, b) == ("base", "peg") and gap == pytest.approx(0.1234, abs=1e-6)
    save_product(apply_report(product, report), bundle / "product.json")
    saved = load_product(bundle / "product.json").geometry["analysis"]["tolerances"]
    assert saved["contact_auto"] == auto and saved["contact"] == pytest.approx(0.124)


def test_auto_keeps_the_default_when_the_product_is_connected(tmp_path):
    boxes = {**PEG, "peg": ((4, 4, 2), (6, 6, 8))}
    product = load_product(make_bundle(tmp_path / "b", boxes) / "product.json")
    report = analyze_product(product, "mesh", Tolerances(contact="auto", resolution=64))
    assert report.tolerances["contact"] == 0.1 and report.tolerances["contact_auto"]["gaps_joined"] == []


def test_auto_refuses_above_the_ceiling_and_writes_nothing(tmp_path):
    bundle = make_bundle(tmp_path / "b", PEG)
    before = (bundle / "product.json").read_bytes()
    with pytest.raises(ContactCeilingError, match=r"tolerance of 0\.124 .* above the ceiling of 0\.12 .* "
                                                  r"0\.1234 between base and peg.*--contact-ceiling 0\.124"):
        analyze_product(load_product(bundle / "product.json"), "mesh", Tolerances(contact="auto", contact_ceiling=0.12, resolution=64))
    done = aplan("analyze", str(bundle), "--contact", "auto", "--contact-ceiling", "0.12")
    assert done.returncode == 1 and "0.1234 between base and peg" in done.stderr and "Traceback" not in done.stderr
    assert (bundle / "product.json").read_bytes() == before
    done = aplan("analyze", str(bundle), "--contact", "auto")
    assert done.returncode == 0, done.stderr
    assert "contact tolerance auto: 0.124 (ceiling 0.168), joining 1 gap(s): base/peg 0.1234" in done.stdout


def test_contact_option_takes_a_length_or_auto():
    from planner.cli.options import contact_tolerance, positive_length

    assert contact_tolerance("auto") == "auto" and contact_tolerance("0.5") == 0.5
    for bad in ("-1", "nan", "inf", "wide"):
        with pytest.raises(argparse.ArgumentTypeError):
            contact_tolerance(bad)
    with pytest.raises(argparse.ArgumentTypeError):
        positive_length("0")
    with pytest.raises(GeometryError, match="a number or 'auto'"):
        Tolerances(contact="wide")


# Six unit cubes in a row, touching: 5 contacts of 15 pairs at the default; at 1.5 each cube also touches the
# one after next (gap 1): 4 more contacts, more than 10 % of the 15 pairs.
ROW = {f"c{k}": ((k, 0, 0), (k + 1, 1, 1)) for k in range(6)}


def test_a_tolerance_that_makes_everything_touch_is_warned_about(tmp_path):
    product = load_product(make_bundle(tmp_path / "b", ROW) / "product.json")
    report = analyze_product(product, "mesh", Tolerances(contact=1.5, resolution=64))
    [warning] = [w for w in report.warnings if "adds" in w]
    assert "the contact tolerance 1.5 adds 4 contacts to the 5 found at the default 0.1: 9 of all 15 part pairs " \
           "touch (60 %)" in warning
    assert "c0/c2 1" in warning
    assert not any("adds" in w for w in analyze_product(product, "mesh", Tolerances(contact=0.9, resolution=64)).warnings)
    done = aplan("analyze", str(tmp_path / "b"), "--contact", "1.5")
    assert done.returncode == 0 and "aplan: warning: the contact tolerance 1.5 adds 4 contacts" in done.stderr


# base, {peg, lid} and a washer 10 mm beside the base: three groups.
APART = {**PEG, "washer": ((20, 0, 0), (21, 1, 1))}


def _expect_gaps_in(message: str):
    assert "falls apart into 3 groups: {base} | {peg, lid} | {washer}" in message
    assert "group 1 {base}: 0.1234 mm between base and peg (--contact 0.124 joins them)" in message
    assert "group 2 {peg, lid}: 0.1234 mm between peg and base (--contact 0.124 joins them)" in message
    assert "group 3 {washer}: 10 mm between washer and base (--contact 10.1 joins them)" in message
    assert "--contact 10.1 joins every group" in message


def test_a_product_that_falls_apart_names_the_gaps(tmp_path):
    bundle = make_bundle(tmp_path / "b", APART)
    done = aplan("analyze", str(bundle))
    assert done.returncode == 0 and "fall apart into 3 groups; joined by --contact 10.1" in done.stdout
    recorded = load_product(bundle / "product.json").geometry["analysis"]["gaps"]
    assert recorded["groups"] == [["base"], ["peg", "lid"], ["washer"]] and recorded["tolerance"] == 10.1
    stats = aplan("stats", str(bundle))  # one line: the groups' sizes and the tolerance that joins them
    assert stats.returncode == 1 and "Traceback" not in stats.stderr and len(stats.stderr.splitlines()) == 1
    assert "is not connected: 3 groups of 1, 2, 1 parts" in stats.stderr and "--contact 10.1 joins them" in stats.stderr
    stats = aplan("stats", str(bundle), "--verbose")  # the whole message: every group's nearest gap
    assert stats.returncode == 1 and "Traceback" not in stats.stderr
    _expect_gaps_in(stats.stderr)
    # The record is enough: without the meshes the error still names the gaps.
    for mesh in (bundle / "meshes").iterdir():
        mesh.unlink()
    with pytest.raises(DisconnectedProductError) as error:
        api.plan_of(bundle)
    _expect_gaps_in(str(error.value))
    assert error.value.tolerance == 10.1 and [g[:2] for g in error.value.gaps] == [
        ("base", "peg"), ("peg", "base"), ("washer", "base")]


def test_gaps_measured_when_the_contacts_were_given_by_hand(tmp_path):
    """A product whose contacts came from elsewhere (no analysis record): measured on its meshes."""
    bundle = make_bundle(tmp_path / "b", APART, contacts=[("peg", "lid")])
    product = load_product(bundle / "product.json")
    with pytest.raises(DisconnectedProductError) as error:
        api.plan_statistics_of(product, partial=True)
    _expect_gaps_in(str(error.value))


def test_without_meshes_the_groups_alone_are_named():
    from planner.product import product_from_dict

    product = product_from_dict({"format": "aplan-product", "version": 1, "parts": [{"id": "a"}, {"id": "b"}],
                                 "contacts": []}, "<memory>")
    with pytest.raises(DisconnectedProductError, match=r"2 groups: \{a\} \| \{b\}\. Add the missing") as error:
        api.plan_of(product)
    assert error.value.gaps is None


def test_stats_analyses_again_with_contact_auto(tmp_path):
    bundle = make_bundle(tmp_path / "b", PEG)
    assert aplan("analyze", str(bundle)).returncode == 0
    before = (bundle / "product.json").read_bytes()  # base apart from {peg, lid} at 0.1
    done = aplan("stats", str(bundle), "--contact", "auto")
    assert done.returncode == 0, done.stderr
    assert "contact tolerance auto: 0.124 (ceiling 0.168), joining 1 gap(s): base/peg 0.1234" in done.stdout
    assert " sequences " in done.stdout and done.stdout.split(" sequences ")[1].split()[0] == "2"
    assert (bundle / "product.json").read_bytes() == before  # analysed in memory only
    refused = aplan("stats", str(bundle), "--contact", "auto", "--contact-ceiling", "0.1")
    assert refused.returncode == 1 and "above the ceiling of 0.1" in refused.stderr
    alone = aplan("stats", str(bundle), "--contact-ceiling", "1")
    assert alone.returncode == 1 and "--contact-ceiling only applies with --contact auto" in alone.stderr
