"""The Python packages the workbench uses that FreeCAD's Addon Manager may not install, what each is for, and
what the workbench does without it (no FreeCAD import: the tests read it anywhere).

The Addon Manager installs only the packages on FreeCAD's allowed list (FreeCAD-addons'
``ALLOWED_PYTHON_PACKAGES.txt``): numpy, networkx, scipy, lxml, matplotlib and trimesh are on it and are
required in ``package.xml``; the packages below are not (or are not packaged for every FreeCAD), so they are
declared ``optional="true"`` there and each has a fallback. :func:`missing` lists those FreeCAD's Python
lacks; :func:`message` is what the workbench prints once in the Report view when it is activated.
"""
from __future__ import annotations

import importlib.util
import os
from dataclasses import dataclass

from . import ADDON_DIR

__all__ = ["Optional", "OPTIONAL", "REQUIRED", "installed", "missing", "message", "MESH_ENGINE", "detection_engine",
           "mesh_python", "warn_missing"]


@dataclass(frozen=True)
class Optional:
    """``module`` (as imported) from the pip package ``package``: what it gives (``for_``) and what the workbench
    does without it (``without``)."""

    module: str
    package: str
    for_: str
    without: str


#: The packages APLAN needs that are on FreeCAD's allowed list (FreeCAD-addons' ``ALLOWED_PYTHON_PACKAGES.txt``,
#: read 2026-12): the Addon Manager installs them, so ``package.xml`` requires them.
REQUIRED = ("numpy", "networkx", "scipy", "lxml", "matplotlib", "trimesh")

#: The modules of the mesh engine (exact mesh booleans and gaps); without them Detect uses the occt engine.
MESH_ENGINE = ("trimesh", "manifold3d")

OPTIONAL = (
    Optional("manifold3d", "manifold3d", "the mesh engine (Detect with Engine = mesh, the default)",
             "Detect uses the occt engine, FreeCAD's own B-rep geometry (same diagrams on the examples, slower)"),
    Optional("fcl", "python-fcl", "exact gaps between parts in the mesh engine at a raised contact tolerance",
             "the mesh engine measures those gaps with manifold3d (slower)"),
    Optional("jsonschema", "jsonschema", "the JSON path of a mistake in a product file's structure",
             "the planner's own checks: a malformed file is still refused, without the JSON path"),
    Optional("cv2", "opencv-python-headless", "camera sessions and marker sheets (aplan session, aplan markers)",
             "no camera sessions in FreeCAD's Python: run them with the command line (scripts/setup.sh)"),
    Optional("threadpoolctl", "threadpoolctl", "one BLAS thread per solver thread",
             "the BLAS libraries keep their own thread counts"),
)


def installed(module: str) -> bool:
    """True when ``module`` can be imported here (found on the path; a finder that refuses it counts as not)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def missing() -> list[Optional]:
    """The optional packages this Python lacks, in the order of :data:`OPTIONAL`. Cost: one path search each."""
    return [o for o in OPTIONAL if not installed(o.module)]


def message(lacking: list[Optional], mesh_python: str | None = None) -> str:
    """What the workbench says about ``lacking`` (empty: nothing to say): each package, what it is for and
    what happens without it, and how to install them. With ``mesh_python`` (the addon's ``.venv``, or
    ``$APLAN_PYTHON``) the mesh engine runs there, so its packages are not missed."""
    if mesh_python:
        lacking = [o for o in lacking if o.module not in MESH_ENGINE and o.module != "fcl"]
    if not lacking:
        return ""
    lines = [f"APLAN: FreeCAD's Python lacks {len(lacking)} optional package{'s' if len(lacking) > 1 else ''} "
             "(the Addon Manager cannot install them); the workbench works without them:"]
    lines += [f"  {o.package}: {o.for_}; without it {o.without}" for o in lacking]
    lines.append("  to add them: pip install " + " ".join(o.package for o in lacking) + " for FreeCAD's Python, "
                 "or run `bash scripts/setup.sh` in the addon's folder (a .venv that runs the mesh engine)")
    return "\n".join(lines) + "\n"


def detection_engine(engine: str, mesh_python: str | None) -> tuple[str, str]:
    """The engine Detect runs for the analysis' ``engine``, and a note when it is not that one. The mesh engine
    needs :data:`MESH_ENGINE`, which the Addon Manager cannot install (manifold3d is not on FreeCAD's allowed
    list): without them here and without ``mesh_python`` (a Python that has them: the addon's ``.venv`` or
    ``$APLAN_PYTHON``, :func:`freecad_aplan.workflow.worker_command`), the occt engine detects instead.
    Cost: a path search per module."""
    if engine != "mesh" or mesh_python is not None or all(installed(m) for m in MESH_ENGINE):
        return engine, ""
    lacking = " and ".join(m for m in MESH_ENGINE if not installed(m))
    return "occt", (f"the mesh engine needs {lacking}, which FreeCAD's Python lacks: detecting with the occt engine "
                    "instead (pip install trimesh manifold3d for FreeCAD's Python, or scripts/setup.sh in the addon "
                    "folder, brings the mesh engine back; set Engine = occt to keep this one)")


def mesh_python() -> str | None:
    """The Python that runs the mesh engine: ``$APLAN_PYTHON``, else the addon's own ``.venv`` (made by
    ``scripts/setup.sh``), else None (then FreeCADCmd, when FreeCAD's Python has trimesh and manifold3d)."""
    explicit = os.environ.get("APLAN_PYTHON")
    if explicit:
        return explicit
    venv = os.path.join(ADDON_DIR, ".venv", "bin", "python")
    return venv if os.path.isfile(venv) and os.access(venv, os.X_OK) else None


def warn_missing() -> str:
    """Print :func:`message` for this Python in FreeCAD's Report view (a warning; nothing when nothing is
    missing) and return it. Called when the workbench is activated."""
    import FreeCAD

    note = message(missing(), mesh_python())
    if note:
        FreeCAD.Console.PrintWarning(note)
    return note
