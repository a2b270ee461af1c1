"""Interlocks a designer would resolve at once, in documents built by FreeCAD here, each run from ``.FCStd`` to
``aplan session --demo 0`` with the default flags (issue 26, items 1 and 5):

- a press-fit pin: radius 5.1 in a blind bore of radius 5 (the overlap measured by OCCT's common): inserted
  along +Z;
- a splined hub on a shaft turned by (20, 30, 0) degrees yaw-pitch-roll, six teeth 4 mm wide in keyways
  3.6 mm wide: inserted along the shaft's axis (FreeCAD's rotation of +Z);
- a knob captured by a cover bolted to a housing (its collar under the cover, its head on it): one component
  with the cover, the four bolts folded;
- bad input, a ball in a closed cage: one line naming the pair and what helps, nothing written.

One FreeCADCmd process builds the four documents and exports all but the press fit (a few seconds); the press
fit's session runs from its ``.FCStd`` (exporting it itself), the others' from their bundles, each a process of
its own, in a folder of its own, in the background (tests/background.py).
"""
from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from background import ENVIRONMENT, Job, folder, run
from conftest import REPO, require_freecadcmd

from integration.freecad_tools import freecad_result
from integration.interlock_documents import DOCUMENTS, SCRIPT



#: The document whose session runs from its ``.FCStd`` end to end (the export inside the session); the
#: others' sessions read the bundles the same FreeCADCmd process exported them to (FreeCAD started once).
FROM_CAD = "press_fit"

EXPORT = """
import sys
sys.path.insert(0, REPO)
from freecad_aplan.export import export_model
for name in BUNDLES:
    export_model(os.path.join(TMP, name + ".FCStd"), os.path.join(TMP, name + "_bundle"))
print("APLAN-EXPORTED " + json.dumps(BUNDLES), flush=True)
"""


def _build() -> tuple[Path, subprocess.CompletedProcess]:
    tmp = folder("interlock-docs")
    script = tmp / "interlock_docs.py"
    bundles = [name for name in DOCUMENTS if name != FROM_CAD]
    script.write_text(f"TMP = {str(tmp)!r}\nREPO = {str(REPO)!r}\nBUNDLES = {bundles!r}\n" + SCRIPT + EXPORT)
    return tmp, run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])


def _session(name: str):
    def work() -> tuple[Path, subprocess.CompletedProcess]:
        documents, built = BACKGROUND[0].result()
        if "APLAN-EXPORTED" not in built.stdout:
            return folder(f"interlock-{name}"), built
        model = documents / (f"{name}.FCStd" if name == FROM_CAD else f"{name}_bundle")
        here = folder(f"interlock-{name}")   # the session's own working folder: its logs, or nothing
        done = run([sys.executable, "-m", "planner", "session", str(model), "--demo", "0"],
                   cwd=here, env={**ENVIRONMENT, "PYTHONPATH": str(REPO)})
        return here, done
    return work


#: FreeCAD builds the documents; then one session per document.
BACKGROUND = (Job("interlock documents in FreeCAD", _build),
              *(Job(f"aplan session {name}.FCStd", _session(name)) for name in DOCUMENTS))


@pytest.fixture(scope="module")
def built() -> dict:
    require_freecadcmd()
    return freecad_result(BACKGROUND[0].result()[1])


def _ran(name: str) -> tuple[Path, subprocess.CompletedProcess]:
    require_freecadcmd()
    return BACKGROUND[1 + DOCUMENTS.index(name)].result()


def _assembled(done: subprocess.CompletedProcess) -> None:
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert re.search(r"^assembled: the product is assembled", done.stdout, re.M), done.stdout[-2000:]


@pytest.mark.freecad
def test_a_press_fit_pin_is_inserted_along_its_bore(built):
    here, done = _ran("press_fit")
    _assembled(done)
    line = next(line for line in done.stderr.splitlines() if "interlock:" in line)
    volume = float(re.search(r"overlap by ([\d.]+) cubic units", line).group(1))
    assert volume == pytest.approx(built["press_fit_overlap"], rel=0.02)   # the mesh's against OCCT's
    assert "Block and Pin" in line and "inserted along +Z, Pin leaves Block along +Z" in line
    assert any(p.suffix == ".jsonl" for p in here.iterdir())   # the session's log


@pytest.mark.freecad
def test_a_splined_hub_slides_along_the_shaft_axis(built):
    _, done = _ran("splined_hub")
    _assembled(done)
    line = next(line for line in done.stderr.splitlines() if "interlock:" in line)
    assert "Shaft and Hub overlap by" in line
    found = [float(c) for c in re.search(r"inserted along \[([^\]]+)\]", line).group(1).split(",")]
    cosine = abs(sum(a * b for a, b in zip(found, built["spline_axis"]))) / math.hypot(*found)
    assert math.degrees(math.acos(min(1.0, cosine))) < 2.0


@pytest.mark.freecad
def test_a_knob_captured_by_a_bolted_cover_is_one_component_with_it():
    _, done = _ran("captured")
    _assembled(done)
    assert "interlock: Cover and Knob: one component Cover+Knob" in done.stderr
    assert "1 fastener group" in done.stderr   # the four bolts fold, into the cover unit and the housing


@pytest.mark.freecad
def test_an_interlock_no_rule_resolves_is_one_line_and_writes_nothing():
    here, done = _ran("caged_ball")
    assert done.returncode == 1 and "Traceback" not in done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("aplan: error:")]
    assert len(errors) == 1, done.stderr
    assert "Cage and Ball block each other along every direction tried (+/-X, +/-Y, +/-Z" in errors[0]
    assert "--direction X,Y,Z" in errors[0] and "diagrams panel" in errors[0]
    assert list(here.iterdir()) == []
