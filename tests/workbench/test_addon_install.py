"""APLAN installed as FreeCAD users install addons: ``package.xml`` requires only packages the Addon Manager may
install (FreeCAD's allowed list) and declares the others optional; a git clone of this repository into a fresh
home's ``Mod`` folder (what the Addon Manager does), without the addon's ``.venv`` and with the optional packages
hidden from FreeCAD's Python, loads in FreeCADCmd and in the FreeCAD window, says what is missing, and works:
the pen is detected (the occt engine standing in for the mesh engine), its decision model and bundle exported.

The clone is of the repository's last commit (HEAD), as a user would get it: uncommitted changes are not in it.
FreeCADCmd's and the window's runs are background jobs (tests/background.py).
"""
from __future__ import annotations

import atexit
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from background import ENVIRONMENT, Job, run
from conftest import PEN_MODELS, REPO, require_freecad_gui, require_freecadcmd, require_shared
from integration.freecad_tools import GUI_HELPERS

from freecad_aplan import dependencies
from planner.files import write_atomic

PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"
NAMESPACE = {"p": "https://wiki.freecad.org/Package_Metadata"}

#: Hides the optional packages from FreeCAD's Python, as a Python without them (a sitecustomize on PYTHONPATH
#: runs before FreeCAD loads any addon; FreeCAD's subprocesses inherit it).
BLOCKER = """
import sys

class _NotInstalled:
    names = {names!r}

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in self.names:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None

sys.meta_path.insert(0, _NotInstalled())
"""

SCRIPT = """
import json, os, shutil, subprocess
import FreeCAD
import freecad_aplan
from freecad_aplan import dependencies, workflow
from freecad_aplan.intent import create_analysis
TMP = {tmp!r}
out = {{"addon": freecad_aplan.ADDON_DIR, "missing": [o.package for o in dependencies.missing()],
        "mesh_python": workflow._mesh_python()}}
out["message"] = dependencies.message(dependencies.missing(), workflow._mesh_python())
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
analysis = create_analysis(doc)
engine, out["note"] = dependencies.detection_engine(analysis.Engine, workflow._mesh_python())
out["engine"] = engine
folder = os.path.join(TMP, "detect")
os.mkdir(folder)
workflow.export_for_detection(doc, folder)
command = workflow.worker_command("analyze", engine)
done = subprocess.run(command, capture_output=True, text=True, timeout=600,
                      env=dict(os.environ, APLAN_BATCH=json.dumps({{"action": "analyze", "folder": folder,
                                                                   "engine": engine}})))
line = [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]
out["detected"] = line
workflow.store_detection(analysis, folder)
product = workflow.analysis_product(analysis)
out["pomdpx"] = workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdpx"))
workflow.export_analysis_bundle(doc, analysis, os.path.join(TMP, "bundle"))
print("APLAN-RESULT " + json.dumps(out))
"""

GUI_SCRIPT = r"""
import json, os, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui

OUT, COPY, BLOCKER = {out!r}, {copy!r}, {blocker!r}
result = {{}}

{gui_helpers}


def start():
    # FreeCAD's window does not run sitecustomize from PYTHONPATH: hide the optional packages here, before the
    # workbench is activated (FreeCAD has imported only freecad_aplan's icon path so far).
    exec(BLOCKER)
    FreeCADGui.activateWorkbench("AplanWorkbench")
    import freecad_aplan
    result["addon"] = freecad_aplan.ADDON_DIR
    result["workbench"] = FreeCADGui.activeWorkbench().name()
    from freecad_aplan import dependencies
    result["missing"] = [o.package for o in dependencies.missing()]
    result["warnings_shown"] = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/OutputWindow").GetBool(
        "checkWarning", True)
    FreeCAD.openDocument(COPY)
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    from freecad_aplan.intent import find_analysis
    result["analysis"] = find_analysis(FreeCAD.ActiveDocument) is not None
    for _ in range(10):
        QtGui.QApplication.processEvents()
    result["report_view"] = FreeCADGui.getMainWindow().findChild(QtGui.QDockWidget, "Report view").widget(
        ).toPlainText()
    finish(0)


QtCore.QTimer.singleShot(1000, guarded(start))
"""


NOT_A_CLONE = "not a git checkout: the Addon Manager installs with git clone"


def _installed(tmp_path):
    """A home whose FreeCAD Mod folder holds a git clone of this repository's HEAD (no .venv), and the
    environment FreeCAD runs in (the session start's): that home, the optional packages hidden, no
    APLAN_PYTHON. None when this is not a git checkout."""
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True)
    if head.returncode != 0 or shutil.which("git") is None:
        return None
    home = tmp_path / "home"
    addon = home / ".local" / "share" / "FreeCAD" / "Mod" / "APLAN"
    addon.parent.mkdir(parents=True)
    subprocess.run(["git", "clone", "--quiet", str(REPO), str(addon)], check=True, capture_output=True)
    subprocess.run(["git", "-C", str(addon), "checkout", "--quiet", head.stdout.strip()], check=True,
                   capture_output=True)
    blocker = tmp_path / "blocker"
    blocker.mkdir()
    write_atomic(blocker / "sitecustomize.py", BLOCKER.format(names=sorted(o.module for o in dependencies.OPTIONAL)))
    env = {k: v for k, v in ENVIRONMENT.items() if not k.startswith(("APLAN_", "PYTHON", "VIRTUAL_ENV"))}
    env.update(HOME=str(home), PYTHONPATH=str(blocker), LANG="C.UTF-8")
    env["PATH"] = ":".join(p for p in env.get("PATH", "").split(":") if ".venv" not in p)
    return addon, env


def test_package_xml_requires_only_what_the_addon_manager_installs():
    from lxml import etree

    root = etree.parse(str(REPO / "package.xml")).getroot()
    depends = root.findall("p:depend", NAMESPACE)
    required = [d.text for d in depends if d.get("type") == "python" and d.get("optional") != "true"]
    optional = [d.text for d in depends if d.get("type") == "python" and d.get("optional") == "true"]
    assert required == list(dependencies.REQUIRED)
    assert optional == [o.package for o in dependencies.OPTIONAL]
    # Every run-time dependency of the Python package is declared, one way or the other.
    tomllib = pytest.importorskip("tomllib")  # Python 3.11
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    names = {d.split(">")[0].split("=")[0].split("<")[0].strip() for d in project}
    assert names == set(required) | set(optional), names ^ (set(required) | set(optional))


def test_dependencies_message_and_the_engine_fallback(monkeypatch):
    monkeypatch.setattr(dependencies, "installed", lambda module: module not in ("manifold3d", "cv2"))
    lacking = dependencies.missing()
    assert [o.package for o in lacking] == ["manifold3d", "opencv-python-headless"]
    text = dependencies.message(lacking, None)
    assert text.startswith("APLAN: FreeCAD's Python lacks 2 optional packages (the Addon Manager cannot install")
    assert "manifold3d: the mesh engine" in text and "Detect uses the occt engine" in text
    assert "pip install manifold3d opencv-python-headless" in text
    # With the addon's .venv the mesh engine runs there: only the camera package is missed.
    assert "manifold3d" not in dependencies.message(lacking, "/addon/.venv/bin/python").split("to add them")[0]
    assert dependencies.message([], None) == ""
    assert dependencies.detection_engine("mesh", None)[0] == "occt"
    assert "the mesh engine needs manifold3d, which FreeCAD's Python lacks" in dependencies.detection_engine(
        "mesh", None)[1]
    assert dependencies.detection_engine("mesh", "/addon/.venv/bin/python") == ("mesh", "")
    assert dependencies.detection_engine("occt", None) == ("occt", "")


def _folder(name: str) -> Path:
    """A new folder for a job, removed at exit; unlike background.folder's, its name does not hold "aplan" (the
    window's test looks for APLAN's errors in the Report view, where FreeCAD names the script's path)."""
    path = Path(tempfile.mkdtemp(prefix=f"addon-{name}-"))
    atexit.register(shutil.rmtree, path, True)
    return path


def _in_freecadcmd():
    """The clone's run in FreeCADCmd (a background job): its folder, the addon's folder and FreeCAD's run."""
    tmp_path = _folder("cmd")
    installed = _installed(tmp_path)
    if installed is None:
        return None
    addon, env = installed
    shutil.copy(PEN, tmp_path / "pen.FCStd")
    script = tmp_path / "install.py"
    script.write_text(SCRIPT.format(tmp=str(tmp_path)))
    freecadcmd = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
    return tmp_path, addon, run([freecadcmd, str(script)], timeout=900, env=env, cwd=tmp_path)


def _in_the_window():
    """The clone's run in the FreeCAD window under Xvfb (a background job), as :func:`_in_freecadcmd`."""
    tmp_path = _folder("window")
    installed = _installed(tmp_path)
    if installed is None:
        return None
    addon, env = installed
    shutil.copy(PEN, tmp_path / "pen.FCStd")
    script = tmp_path / "gui.py"
    blocker = BLOCKER.format(names=sorted(o.module for o in dependencies.OPTIONAL))
    script.write_text(GUI_SCRIPT.format(out=str(tmp_path / "result.json"), copy=str(tmp_path / "pen.FCStd"),
                                        gui_helpers=GUI_HELPERS, blocker=blocker))
    env["QTWEBENGINE_CHROMIUM_FLAGS"] = "--no-sandbox --disable-gpu"
    command = [shutil.which("xvfb-run"), "-n", "180", "-a", "-s", "-screen 0 1280x800x24", shutil.which("freecad"),
               str(script)]  # displays from 180: the tests' own start at 99 (conftest.freecad_gui_run)
    return tmp_path, addon, run(command, timeout=300, env=env, cwd=tmp_path)


RUNS = {"freecadcmd": Job("a git clone of the addon in FreeCADCmd", _in_freecadcmd),
        "window": Job("a git clone of the addon in the FreeCAD window", _in_the_window)}
#: FreeCAD's runs, done in the background (tests/background.py).
BACKGROUND = tuple(RUNS.values())


def _result(name: str):
    """The run ``name`` of :data:`RUNS`; skips when this is not a git checkout."""
    result = RUNS[name].result()
    if result is None:
        pytest.skip(NOT_A_CLONE)
    return result


@pytest.mark.freecad
def test_a_git_clone_in_a_fresh_mod_folder_works_in_freecadcmd():
    require_freecadcmd()
    require_shared(PEN)
    tmp_path, addon, done = _result("freecadcmd")
    lines = [line for line in done.stdout.splitlines() if line.startswith("APLAN-RESULT ")]
    assert lines, f"FreeCADCmd wrote no result:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    data = json.loads(lines[-1].split(" ", 1)[1])
    assert data["addon"] == str(addon) and data["mesh_python"] is None  # the clone, not this checkout
    assert data["missing"] == [o.package for o in dependencies.OPTIONAL]  # all hidden
    assert "Detect uses the occt engine" in data["message"] and "pip install manifold3d" in data["message"]
    assert data["engine"] == "occt" and "detecting with the occt engine instead" in data["note"]
    assert data["detected"].startswith("APLAN-RESULT "), data["detected"]
    assert json.loads(data["detected"].split(" ", 1)[1])["contacts"] == 5  # the pen's five liaisons (paper)
    assert (data["pomdpx"]["states"], data["pomdpx"]["actions"]) == (69, 22)  # paper: 69 intentions
    assert (tmp_path / "bundle" / "product.json").is_file() and (tmp_path / "pen.pomdpx").is_file()


@pytest.mark.freecad
def test_a_git_clone_in_a_fresh_mod_folder_loads_in_the_freecad_window():
    require_freecad_gui()
    require_shared(PEN)
    tmp_path, addon, done = _result("window")
    out = tmp_path / "result.json"
    assert out.is_file(), f"the GUI wrote no result:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    data = json.loads(out.read_text())
    assert "error" not in data, data.get("error")
    assert data["addon"] == str(addon) and data["workbench"] == "AplanWorkbench" and data["analysis"] is True
    report = data["report_view"]
    assert data["missing"] == [o.package for o in dependencies.OPTIONAL]
    assert "APLAN: FreeCAD's Python lacks 5 optional packages" in report, report
    # (the pen's A2plus objects fill it with their import errors: A2plus is not installed)
    assert not [line for line in report.splitlines() if "aplan" in line.lower() and "rror" in line], report
