"""The diaphragm pump (../shared/models/diaphragm_pump) without its two closed shells 16_001 and 21_001 (read
as solids since they are, they connect it; left out here with --exclude, as before they were read): 51
solids, modelled with clearances, 8 groups at the default contact tolerance: the gaps named, checked against
brute force, and --contact auto."""
from __future__ import annotations

import itertools
import shutil

import pytest
from background import Job, folder, run
from conftest import SHARED, require_freecadcmd, require_shared

from integration.freecad_tools import aplan, aplan_process, succeeded
from planner import api, load_product
from planner.errors import ContactCeilingError, DisconnectedProductError
from planner.geometry import Tolerances, analyze_product, apply_report
from planner.geometry.bundle import bundle_product_path, load_part_meshes
from planner.geometry.gaps import connection_groups, gap_report, mesh_gaps, part_gaps
from planner.geometry.meshes import _manifold

PUMP = SHARED / "models" / "diaphragm_pump" / "asm_diaphragm_pump.FCStd"


def _export_pump() -> tuple:
    bundle = folder("pump") / "bundle"
    return bundle, aplan_process("export-freecad", str(PUMP), "-o", str(bundle), "--exclude", "16_001", "--exclude",
                                 "21_001")




@pytest.fixture(scope="session")
def pump_bundle():
    """The pump without its two shells, exported once (default tolerances) for every test here."""
    require_freecadcmd()
    require_shared(PUMP)
    bundle, done = BACKGROUND[0].result()  # the module's jobs, listed below the two boxes' script
    succeeded(done)
    return bundle


@pytest.fixture(scope="session")
def pump(pump_bundle):
    product = load_product(bundle_product_path(pump_bundle))
    return product, load_part_meshes(product)


@pytest.mark.freecad
def test_pump_gaps_are_those_of_brute_force(pump):
    """The lazy search measures few pairs and finds what measuring every pair across the groups finds; the
    joining gaps agree with manifold's own gap query (another library) to 1e-4 mm."""
    product, meshes = pump
    report = mesh_gaps(meshes, product.contacts)
    groups = connection_groups(product.part_ids, product.contacts)
    assert len(groups) == 8
    home = {p: k for k, group in enumerate(groups) for p in group}
    every = [(a, b) for a, b in itertools.combinations(product.part_ids, 2) if home[a] != home[b]]
    brute = gap_report(groups, [(a, b, d) for (a, b), d in part_gaps(meshes, every).items()])
    assert [(g.a, g.b) for g in report.nearest] == [(g.a, g.b) for g in brute.nearest]
    assert [g.distance for g in report.nearest] == pytest.approx([g.distance for g in brute.nearest], abs=1e-9)
    assert [g.distance for g in report.joining] == pytest.approx([g.distance for g in brute.joining], abs=1e-9)
    assert report.queries < len(every) // 4, (report.queries, len(every))
    solids = {m.id: _manifold(m) for m in meshes}
    for gap in report.joining:
        assert solids[gap.a].min_gap(solids[gap.b], gap.distance + 1) == pytest.approx(gap.distance, abs=1e-4)
    print(f"pump: {len(every)} pairs across the groups, {report.queries} measured; joining gaps "
          f"{[(g.a, g.b, round(g.distance, 4)) for g in report.joining]}")


@pytest.mark.freecad
def test_pump_stats_name_the_gaps(pump_bundle):
    done = aplan("stats", str(pump_bundle), "--fasteners", "tagged", "--subassemblies", "designer", "--verbose",
                 check=False)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    message = done.stderr
    assert "the connection diagram is not connected: it falls apart into 8 groups" in message
    assert "group 2 {18_001}: 30.54 mm between 18_001 and 1_001 (--contact 30.6 joins them)" in message
    assert "group 3 {19_001}: 6.159 mm between 19_001 and 9_001 (--contact 6.16 joins them)" in message
    assert "--contact 30.6 joins every group" in message
    # The export recorded the gaps: the error comes from the record, as it does for `aplan stats pump.FCStd`.
    assert load_product(bundle_product_path(pump_bundle)).geometry["analysis"]["gaps"]["tolerance"] == 30.6


@pytest.mark.freecad
def test_pump_contact_auto(pump):
    """Auto needs 30.6 mm (1_001 to 23_001): refused under the default ceiling (1 % of the 401 mm diagonal);
    with the ceiling raised, the contacts are every pair whose gap is at most 30.6 (brute force), the product
    is connected, the 131 contacts added are warned about, and the AND/OR graph is refused at once by its size
    guard (fasteners and subassemblies are what helps there)."""
    product, meshes = pump
    coarse = Tolerances(contact="auto", resolution=256)  # the obstructions do not matter here
    with pytest.raises(ContactCeilingError, match=r"tolerance of 30\.6 .* ceiling of 4\.01 .* 30\.55 between 1_001 "
                                                  r"and 23_001; 30\.54 between 1_001 and 18_001") as refused:
        analyze_product(product, "mesh", coarse)
    assert refused.value.parts == ("1_001", "23_001")
    report = analyze_product(product, "mesh", Tolerances(contact="auto", contact_ceiling=40, resolution=256))
    auto = report.tolerances["contact_auto"]
    assert (auto["chosen"], auto["ceiling"], len(auto["gaps_joined"])) == (30.6, 40, 7)
    assert len(connection_groups(report.parts, report.contacts)) == 1
    # The 12 interferences found at 0.1 mm are still reported at 30.6 mm.
    assert len(report.interferences) == len(product.geometry["analysis"]["interferences"]) == 12
    every = list(itertools.combinations(product.part_ids, 2))
    within = {frozenset(p) for p, d in part_gaps(meshes, every).items() if d <= 30.6}
    assert {frozenset(c) for c in report.contacts} == within | {frozenset(c) for c in product.contacts}
    added = len(report.contacts) - len(product.contacts)
    assert any(f"adds {added} contacts to the {len(product.contacts)} found at the default 0.1" in w
               for w in report.warnings)
    connected = apply_report(product, report)
    assert connected.geometry["analysis"]["tolerances"]["contact_auto"] == auto
    _, stats = api.plan_statistics_of(connected, partial=True)
    assert stats.refused is not None and "connected part sets" in str(stats.refused)
    print(f"pump --contact auto --contact-ceiling 40: {len(report.contacts)} contacts ({added} added); "
          f"stats: {stats.refused}")


@pytest.mark.freecad
def test_pump_plan_error_from_api(pump):
    product, _ = pump
    with pytest.raises(DisconnectedProductError) as error:
        api.plan_of(product)
    assert error.value.tolerance == 30.6 and len(error.value.gaps) == 8


TWO_BOXES = """
import FreeCAD
doc = FreeCAD.newDocument("gap")
for name, x in (("Left", 0), ("Right", 10.5)):
    box = doc.addObject("Part::Box", name)
    box.Length = box.Width = box.Height = 10
    box.Placement.Base = FreeCAD.Vector(x, 0, 0)
doc.recompute()
doc.saveAs({path!r})
print("APLAN-RESULT {{}}")
"""


def _two_boxes() -> tuple:
    """TWO_BOXES built in FreeCADCmd, then exported with --contact auto (refused) and with the ceiling raised:
    (folder, the script's run, the refused export, the folder's files after it, the second export)."""
    tmp = folder("two-boxes")
    script = tmp / "make.py"
    script.write_text(TWO_BOXES.format(path=str(tmp / "gap.FCStd")))
    built = run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)], timeout=120)
    model = str(tmp / "gap.FCStd")
    refused = aplan_process("export-freecad", model, "-o", str(tmp / "b"), "--contact", "auto")
    left = sorted(p.name for p in tmp.iterdir())
    done = aplan_process("export-freecad", model, "-o", str(tmp / "b"), "--contact", "auto", "--contact-ceiling", "1")
    return tmp, built, refused, left, done


#: The exports the tests read, done in the background (tests/background.py).
BACKGROUND = (Job("export the pump without its shells", _export_pump), Job("two boxes 0.5 apart", _two_boxes))


@pytest.mark.freecad
def test_export_freecad_contact_auto():
    """Two 10 mm cubes 0.5 mm apart: auto needs 0.501, above the default ceiling (1 % of the 24.9 mm
    diagonal): refused, no bundle; with --contact-ceiling 1 the bundle records the choice."""
    from integration.freecad_tools import freecad_result

    require_freecadcmd()
    tmp, built, refused, left, done = BACKGROUND[1].result()
    freecad_result(built)
    assert refused.returncode == 1 and "Traceback" not in refused.stderr
    assert "tolerance of 0.501 to be connected, above the ceiling of 0.249" in refused.stderr
    assert "0.5 between Left and Right" in refused.stderr
    assert left == ["gap.FCStd", "make.py"]  # nothing written
    succeeded(done)
    assert "contact tolerance auto: 0.501 (ceiling 1), joining 1 gap(s): Left/Right 0.5" in done.stdout
    product = load_product(bundle_product_path(tmp / "b"))
    assert product.contacts == (("Left", "Right"),)
    assert product.geometry["analysis"]["tolerances"]["contact_auto"] == {
        "chosen": 0.501, "ceiling": 1.0, "default": 0.1, "gaps_joined": [["Left", "Right", 0.5]]}
