"""The architecture: data flows one way, from FreeCAD documents to the planner, and inside the planner from the
product up the paper's pipeline. Imports inside functions count too."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest
from conftest import REPO

FORBIDDEN = {"FreeCAD", "FreeCADGui", "Part", "Mesh", "PySide", "PySide2", "PySide6", "PyQt5", "freecad",
             "freecad_aplan"}

# Each part of the planner may import its own level and those below it, never one above.
LAYERS = {
    "errors": 0, "defaults": 0, "files": 0, "plugins": 0, "interrupts": 0, "validation": 0,
    "product": 1,
    "geometry": 2,
    "assembly": 3,
    "decision": 4,
    "runtime": 5,
    "api": 6,
    "cli": 7, "__main__": 7, "__init__": 7,
}


def _imports(path: Path, package: str) -> list[tuple[int, str]]:
    """(line, absolute module) of every import in ``path``, a module of ``package`` (dotted)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                base = node.module or ""
            else:
                parts = package.split(".")
                parts = parts[:len(parts) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            out.append((node.lineno, base))
            if node.module is None or node.level:  # `from . import x`: x may be a module of its own
                out += [(node.lineno, f"{base}.{a.name}") for a in node.names]
    return out


def _planner_modules():
    for path in sorted((REPO / "planner").rglob("*.py")):
        relative = path.relative_to(REPO).with_suffix("").parts  # ("planner", "decision", "pomdp")
        yield path, relative, ".".join(relative[:-1])


def _layer(module_parts: tuple[str, ...] | list[str]) -> int:
    top = module_parts[1] if len(module_parts) > 1 else "__init__"
    return LAYERS[top]


def test_every_planner_module_has_a_layer():
    tops = {p.relative_to(REPO / "planner").parts[0].removesuffix(".py")
            for p in (REPO / "planner").rglob("*.py")}
    assert tops - set(LAYERS) == set(), "a new part of the planner: give it a layer in LAYERS"


def test_planner_imports_no_freecad():
    offenders = [f"{path.relative_to(REPO)}:{line} {name}" for path, _, package in _planner_modules()
                 for line, name in _imports(path, package) if name.split(".")[0] in FORBIDDEN]
    assert offenders == []


def test_nothing_runs_back_up_the_pipeline():
    offenders = []
    for path, relative, package in _planner_modules():
        own = _layer(relative)
        for line, name in _imports(path, package):
            parts = name.split(".")
            if parts[0] != "planner" or len(parts) < 2:
                continue
            if _layer(parts) > own:
                offenders.append(f"{path.relative_to(REPO)}:{line} imports {name}")
    assert offenders == []


def test_product_does_not_need_geometry():
    """The product (the bottom of the pipeline) is read and checked without any geometry."""
    offenders = [f"{path.relative_to(REPO)}:{line} {name}" for path, relative, package in _planner_modules()
                 if relative[1] == "product" for line, name in _imports(path, package)
                 if name.startswith("planner.geometry")]
    assert offenders == []


@pytest.mark.parametrize("source, target, expected", [
    ("from ..decision.pomdp import POMDP", "planner.runtime", "planner.decision.pomdp"),
    ("from . import plan", "planner.cli", "planner.cli.plan"),
    ("from ...errors import PlannerError", "planner.decision.io", "planner.errors"),
])
def test_relative_imports_are_resolved(tmp_path, source, target, expected):
    module = tmp_path / "m.py"
    module.write_text(source + "\n")
    assert expected in [name for _, name in _imports(module, target)]


def test_the_checker_sees_a_violation(tmp_path):
    """A module of the product importing the decision model is caught (the check can fail)."""
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from ..decision.pomdp import POMDP\n")
    names = [name for _, name in _imports(module, "planner.product")]
    assert _layer(names[0].split(".")) > _layer(("planner", "product"))


# Rooms inside the decision package (issue 24): a model never imports what is built on it. The models (their
# tables, beliefs and filters) import no solver, no bound, no planner and not the interface; the bounds
# (class-MDP, delayed reveal) no solver but the upper bound's types, and no planner; solvers no online planner;
# a policy (alpha vectors) none of them either; the interface (models.py) nothing but what it describes. Imports inside functions count too.
DECISION_ROOMS = {
    "model": ({"pomdp", "intention_model", "factored_model", "lumped_model", "parallel", "parallel_table", "parallel_values",
               "projected", "joins", "deviations", "habits", "orders", "presets", "belief", "factored_updater", "factored_belief",
               "factored_sequences", "step_observations", "step_pomdp"},
              ("solvers", "online", "bounds", "delayed_reveal", "models", "simulate", "factored_simulate",
               "episodes")),
    "bound": ({"bounds", "delayed_reveal"}, ("online", "models", "solvers.point_based", "solvers.warm_start",
                                             "solvers.sarsop")),
    "solver": ({"solvers"}, ("online", "models", "simulate", "factored_simulate")),
    "policy": ({"policy"}, ("solvers", "online", "bounds", "delayed_reveal", "models", "simulate",
                            "factored_simulate")),
    "interface": ({"models"}, ("solvers", "simulate", "factored_simulate", "episodes")),
}


def _room_of(relative: tuple[str, ...]) -> str | None:
    if len(relative) < 3 or relative[1] != "decision":
        return None
    name = relative[2]
    return next((room for room, (members, _) in DECISION_ROOMS.items() if name in members), None)


def test_decision_rooms_import_nothing_built_on_them():
    offenders = []
    for path, relative, package in _planner_modules():
        room = _room_of(relative)
        if room is None:
            continue
        forbidden = DECISION_ROOMS[room][1]
        for line, name in _imports(path, package):
            inner = name.removeprefix("planner.decision.")
            if name.startswith("planner.decision.") and any(inner == f or inner.startswith(f + ".") for f in forbidden):
                offenders.append(f"{path.relative_to(REPO)}:{line} ({room}) imports {name}")
    assert offenders == []


def test_every_decision_module_has_a_room_or_is_a_front():
    """A new module of the decision package is placed in a room, or listed here as built on them all."""
    fronts = {"__init__", "belief_plot", "budget", "episode", "episode_measures", "mind_measures", "online",
              "online_steps", "operators", "simulate", "factored_simulate", "episodes", "camera_world", "io"}
    placed = set().union(*(members for members, _ in DECISION_ROOMS.values())) | fronts
    names = {p.relative_to(REPO / "planner" / "decision").parts[0].removesuffix(".py")
             for p in (REPO / "planner" / "decision").rglob("*.py")}
    assert names - placed == set(), "a new module of planner/decision: give it a room in DECISION_ROOMS"


def test_the_room_check_finds_a_model_importing_a_solver(tmp_path):
    """A model importing the solver is caught (the check can fail)."""
    module = tmp_path / "lumped_model.py"
    module.write_text("from .solvers.upper import RelaxedQ\n")
    names = [name for _, name in _imports(module, "planner.decision")]
    assert names[0] == "planner.decision.solvers.upper"
    assert _room_of(("planner", "decision", "lumped_model")) == "model"
    assert any(names[0].removeprefix("planner.decision.").startswith(f) for f in DECISION_ROOMS["model"][1])


# Rooms of the API (issue 24): one module per stage of the pipeline, each importing only the stages before it;
# the values passed down (specs) import no stage. ``planner/api/__init__.py`` re-exports them all.
API_STAGES = {"specs": 0, "products": 1, "plans": 2, "levels": 3, "models": 4, "policies": 5, "decisions": 6}

# The command line's option bundles (planner/cli/options/): argparse types first, then the bundles, each
# importing only those below it (the planner bundle adds the model bundle's options to simulate and evaluate).
OPTION_BUNDLES = {"values": 0, "outputs": 1, "limits": 1, "geometry": 1, "advice": 1, "products": 2, "models": 3,
                  "planners": 4}

ROOMS = {("planner", "api"): API_STAGES, ("planner", "cli", "options"): OPTION_BUNDLES}


@pytest.mark.parametrize("folder", sorted(ROOMS), ids=".".join)
def test_stages_import_only_the_stages_before_them(folder):
    ranks = ROOMS[folder]
    package = ".".join(folder)
    modules = {p.stem for p in REPO.joinpath(*folder).glob("*.py")} - {"__init__"}
    assert modules == set(ranks), f"a new module of {package}: give it a rank"
    offenders = []
    for name in sorted(modules):
        path = REPO.joinpath(*folder, f"{name}.py")
        for line, imported in _imports(path, package):
            other = imported.removeprefix(package + ".").split(".")[0] if imported.startswith(package + ".") else None
            if other in ranks and other != name and ranks[other] >= ranks[name]:
                offenders.append(f"{path.relative_to(REPO)}:{line} imports {imported}")
    assert offenders == []


def _runtime_imports(path: Path, package: str) -> list[tuple[int, str]]:
    """:func:`_imports` without those under ``if TYPE_CHECKING:`` (for annotations only: they never run)."""
    tree = ast.parse(path.read_text(), str(path))
    hidden = {node.lineno for block in ast.walk(tree) if isinstance(block, ast.If)
              and ast.unparse(block.test).endswith("TYPE_CHECKING")
              for inner in block.body for node in ast.walk(inner) if isinstance(node, (ast.Import, ast.ImportFrom))}
    return [(line, name) for line, name in _imports(path, package) if line not in hidden]


def _import_graph(roots: tuple[Path, ...]):
    """Module -> the modules it imports (inside functions too; ``TYPE_CHECKING`` imports left out), over the
    modules under ``roots``. A package's ``__init__`` re-exports its modules, so it is neither a source nor a
    target here: a circle runs through the modules themselves."""
    import networkx as nx

    modules = {}
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            if path.name == "__init__.py":
                continue
            parts = path.relative_to(root.parent).with_suffix("").parts
            modules[".".join(parts)] = (path, ".".join(parts[:-1]))
    graph = nx.DiGraph()
    graph.add_nodes_from(modules)
    for name, (path, package) in modules.items():
        for _, imported in _runtime_imports(path, package):
            if imported in modules and imported != name:
                graph.add_edge(name, imported)
    return graph


def test_no_import_circles():
    """No circle of imports among the modules of the planner and the workbench (issue 24: the circles
    export/structure/workflow, gaps/mesh_engine and model/validation/designer were held open by imports inside
    functions): what two modules share lives in a third below both."""
    import networkx as nx

    graph = _import_graph((REPO / "planner", REPO / "freecad_aplan"))
    circles = sorted(" -> ".join(c + c[:1]) for c in nx.simple_cycles(graph))
    assert circles == []


def test_the_circle_check_finds_a_circle_held_open_by_a_function(tmp_path):
    """Two modules importing each other, one of them inside a function, are a circle (the check can fail); an
    import under ``TYPE_CHECKING`` is not."""
    import networkx as nx

    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("from .b import g\n\ndef f():\n    return g()\n")
    (package / "b.py").write_text("def g():\n    from .a import f\n    return f\n")
    (package / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import f\n")
    (package / "d.py").write_text("from .c import TYPE_CHECKING\n")
    graph = _import_graph((package,))
    assert sorted(sorted(c) for c in nx.simple_cycles(graph)) == [["pkg.a", "pkg.b"]]
