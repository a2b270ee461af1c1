"""The workbench's code keeps no mutable state at module level (it would be shared by every document and
outlive the objects that own it)."""
from __future__ import annotations

import ast

from conftest import REPO

_MUTABLE = (ast.List, ast.Dict, ast.Set, ast.ListComp, ast.DictComp, ast.SetComp)


def _mutable_globals(tree: ast.Module) -> list[str]:
    found = []
    for node in tree.body:
        if not isinstance(node, (ast.Assign, ast.AnnAssign)) or node.value is None:
            continue
        value = node.value
        made = isinstance(value, _MUTABLE) or (
            isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id in ("dict", "list", "set"))
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        names = [ast.unparse(t) for t in targets]
        if made and names != ["__all__"]:
            found.append(f"{', '.join(names)} (line {node.lineno})")
    return found


def test_no_module_level_mutable_state():
    offenders = {}
    for path in sorted((REPO / "freecad_aplan").rglob("*.py")):
        found = _mutable_globals(ast.parse(path.read_text(encoding="utf-8")))
        if found:
            offenders[str(path.relative_to(REPO))] = found
    assert offenders == {}


def test_the_check_sees_mutable_globals():
    tree = ast.parse("__all__ = ['a']\n_STATE: dict = {}\nJOBS = []\nNAMES = ('x',)\nSEEN = set()\n")
    assert _mutable_globals(tree) == ["_STATE (line 2)", "JOBS (line 3)", "SEEN (line 5)"]
