"""The planner never imports FreeCAD or Qt: data flows one way, from FreeCAD documents to the planner."""
from __future__ import annotations

import ast

from conftest import REPO

FORBIDDEN = {"FreeCAD", "FreeCADGui", "Part", "Mesh", "PySide", "PySide2", "PySide6", "PyQt5", "freecad",
             "freecad_aplan"}


def test_planner_imports_no_freecad():
    offenders = []
    for path in sorted((REPO / "planner").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            offenders += [f"{path.name}:{node.lineno} {n}" for n in names if n.split(".")[0] in FORBIDDEN]
    assert offenders == []
