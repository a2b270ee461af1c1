"""Messy real CAD (issue 13, item 4): each part's mesh against its B-rep before and after the mesh check, and
the exact (OCCT) engine on the real models, with its per-pair budget (needs FreeCAD).

Run: ``.venv/bin/python bench/bench_messy_cad.py [--parts] [--occt] [--springs] [--documents [--models]]``
(about a minute; with --occt, several; --documents about 15 minutes on a loaded machine, --models adds 40).

- *before*: the export's former tessellation (MeshPart Standard at the default deflections, duplicated
  points merged, holes filled); *after*: :func:`freecad_aplan.tessellation.checked_mesh` (the same first,
  other methods when the volume or area is off by more than 1 %). The volume error is
  ``(mesh volume - B-rep volume) / B-rep volume``; ``--parts`` prints it for every part.
- ``--occt``: ``aplan export-freecad MODEL --engine none``, then ``aplan analyze BUNDLE --engine occt``
  timed (wall clock), with the pair counts and the undecided pairs of the engine's answer.
- ``--springs``: helical springs of pitch 4, 10 and 20 turns (tests/workbench/spring_document.py), each
  ``aplan export-freecad DOC -o BUNDLE --engine mesh|occt`` with the default flags otherwise, under
  ``prlimit --as`` 6 GiB: CPU seconds (the command and FreeCADCmd), peak memory, parts per fallback rule
  and the pairs OCCT left undecided. Before the OCCT bounds, the 10-turn spring ran past 10 minutes and 11 GB.
- ``--documents [--engines mesh,occt] [--models] [--only NAMES]``: issue 26's test documents, built in FreeCAD as the tests
  build them (tests/integration/interlock_documents.py: press fit, splined hub, captured part, caged ball;
  tests/integration/test_cad_documents.py: a group with non-parts, a bearing with balls, linked documents;
  the 10-turn spring of tests/workbench/spring_document.py, the open coil and the sphere and torus as NURBS of
  tests/workbench/test_heavy_shapes.py), with ``--models`` the pen, the truck and the pump
  too: per document and engine, ``aplan export-freecad DOC -o BUNDLE --engine E`` with the default flags: CPU
  seconds of the command and its FreeCADCmd children (wall beside), the parts per fallback rule, the interlocked
  pairs and what the interlock rules did with them, and the pairs OCCT left undecided (of them, those of a
  sweep that lost a face).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT.parent / "shared" / "models"
CASES = [("toy truck", MODELS / "toy_truck/asm_cement_mixer_truck.FCStd"),
         ("diaphragm pump", MODELS / "diaphragm_pump/asm_diaphragm_pump.FCStd")]

MESH_SCRIPT = r"""
import json, os, sys, time
sys.path.insert(0, os.environ["ROOT"])
import MeshPart
from freecad_aplan.document import open_model, read_components
from freecad_aplan.tessellation import checked_mesh
from planner.defaults import ANGULAR_DEFLECTION, LINEAR_DEFLECTION
rows, seconds = [], {"before": 0.0, "after": 0.0}
for component in read_components(open_model(os.environ["MODEL"])).components:
    shape, volume = component.shape, component.shape.Volume
    start = time.perf_counter()
    mesh = MeshPart.meshFromShape(Shape=shape, LinearDeflection=LINEAR_DEFLECTION,
                                  AngularDeflection=ANGULAR_DEFLECTION, Relative=False)
    if not mesh.isSolid():
        mesh.removeDuplicatedPoints()
    if not mesh.isSolid():
        mesh.fillupHoles(1000, 1)
    seconds["before"] += time.perf_counter() - start
    before = (mesh.Volume - volume) / volume
    start = time.perf_counter()
    _, check = checked_mesh(shape.copy(), LINEAR_DEFLECTION, ANGULAR_DEFLECTION)
    seconds["after"] += time.perf_counter() - start
    rows.append([component.id, before, check.volume_error, check.method])
print("APLAN-RESULT " + json.dumps({"rows": rows, "seconds": seconds}), flush=True)
"""


def _mesh_errors(model: Path) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        script = Path(folder) / "mesh_errors.py"
        script.write_text(MESH_SCRIPT)
        done = subprocess.run(["freecadcmd", str(script)], capture_output=True, text=True, timeout=1800,
                              env={**os.environ, "ROOT": str(ROOT), "MODEL": str(model)})
    for line in done.stdout.splitlines():
        if line.startswith("APLAN-RESULT "):
            return json.loads(line.split(" ", 1)[1])
    raise SystemExit(f"{model}: no result\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")


def _occt(model: Path, budget: float | None) -> str:
    aplan = [sys.executable, "-m", "planner"]
    with tempfile.TemporaryDirectory() as folder:
        bundle = Path(folder) / "bundle"
        subprocess.run(aplan + ["export-freecad", str(model), "-o", str(bundle), "--engine", "none"], check=True,
                       capture_output=True, timeout=1800)
        extra = [] if budget is None else ["--pair-budget", str(budget)]
        start = time.perf_counter()
        done = subprocess.run(aplan + ["analyze", str(bundle), "--engine", "occt", "--json"] + extra,
                              capture_output=True, text=True, timeout=3600, cwd=ROOT)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            return f"failed after {wall:.0f} s: {done.stderr.strip()[-300:]}"
        report = json.loads(done.stdout)
        undecided = [w for w in report["warnings"] if w.startswith("OCCT did not decide")]
        shutil.rmtree(bundle, ignore_errors=True)
    pairs = "/".join(str(len(report["obstructions"][a])) for a in ("+X", "+Y", "+Z"))
    return (f"{wall:.0f} s wall, {len(report['contacts'])} contacts, obstructions {pairs}, "
            f"{len(undecided)} pairs undecided")


SPRING_SCRIPT = r"""
import os, sys
sys.path.insert(0, os.path.join(os.environ["ROOT"], "tests", "workbench"))
from spring_document import build_spring_document
build_spring_document(os.environ["OUT"], pitch=float(os.environ["PITCH"]), height=float(os.environ["HEIGHT"]))
"""


NURBS_SCRIPT = r"""
import os
import FreeCAD, Part
V = FreeCAD.Vector
document = FreeCAD.newDocument("nurbs")
for name, shape in (("Ball", Part.makeSphere(5).toNurbs()), ("BallBlock", Part.makeBox(10, 4, 4, V(5.05, -2, -2))),
                    ("Torus", Part.makeTorus(8, 3, V(0, 100, 0)).toNurbs()),
                    ("TorusBlock", Part.makeBox(10, 4, 2, V(11.05, 98, -1)))):
    document.addObject("Part::Feature", name).Shape = shape
document.recompute()
document.saveAs(os.environ["OUT"])
"""


def _spring_rows(pitch: float = 4.0, turns=(10, 20)) -> list[str]:
    """One table row per spring document and engine (module docstring)."""
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        script = Path(folder) / "build_spring.py"
        script.write_text(SPRING_SCRIPT)
        for count in turns:
            document = Path(folder) / f"spring_{count}.FCStd"
            subprocess.run(["freecadcmd", str(script)], check=True, capture_output=True, timeout=600,
                           env={**os.environ, "ROOT": str(ROOT), "OUT": str(document), "PITCH": str(pitch),
                                "HEIGHT": str(pitch * count)})
            for engine in ("mesh", "occt"):
                bundle = Path(folder) / f"bundle_{count}_{engine}"
                times = Path(folder) / "time.txt"
                done = subprocess.run(["/usr/bin/time", "-o", str(times), "-f", "%U %S %M", "prlimit",
                                       f"--as={6 * 2 ** 30}", "--", sys.executable, "-m", "planner",
                                       "export-freecad", str(document), "-o", str(bundle), "--engine", engine],
                                      capture_output=True, text=True, timeout=1800, cwd=ROOT)
                user, system, peak = times.read_text().split()[-3:]
                if done.returncode != 0:
                    rows.append(f"| {count} | {engine} | failed: {done.stderr.strip()[-200:]} | | | |")
                    continue
                product = json.loads((bundle / "product.json").read_text())
                rules = product["geometry"]["mesh_check"]["rules"]
                pairs = product["geometry"].get("analysis", {}).get("tolerances", {}).get("pairs", {})
                rows.append(f"| {count} | {engine} | {float(user) + float(system):.1f} | {int(peak) / 1024:.0f} | "
                            + ", ".join(f"{rule} {len(ids)}" for rule, ids in rules.items() if ids)
                            + f" | {len(pairs.get('undecided', []))} |")
    return rows


def _document_row(name: str, model: Path, bundle: Path, engine: str) -> str:
    """One row of ``--documents`` (module docstring)."""
    from planner import load_product
    from planner.assembly.feasibility import interlocked_pairs
    from planner.assembly.interlocks import resolve_interlocks

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "planner", "export-freecad", str(model), "-o", str(bundle),
                           "--engine", engine], capture_output=True, text=True, timeout=3600, cwd=ROOT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    if done.returncode != 0:
        return f"| {name} | {engine} | failed: {(done.stderr or done.stdout).strip()[-160:]} | | | | |"
    product = load_product(bundle / "product.json")
    rules = product.geometry.get("mesh_check", {}).get("rules", {})
    pairs = product.geometry.get("analysis", {}).get("tolerances", {}).get("pairs", {})
    found = interlocked_pairs(product)
    _, decisions, unresolved = resolve_interlocks(product)
    resolved = ", ".join(f"{rule} {n}" for rule, n in sorted(Counter(d.rule for d in decisions).items()))
    lost = {frozenset((part, other)) for part, _, _ in pairs.get("sweeps_lost", ())
            for other in product.part_ids if other != part} & {frozenset(p) for p in pairs.get("undecided", ())}
    undecided = "-" if engine == "mesh" else f"{len(pairs.get('undecided', []))} ({len(lost)} with a part whose sweep lost a face)"
    return (f"| {name} | {engine} | {len(product.parts)} | {cpu:.1f} ({wall:.0f}) | "
            f"{', '.join(f'{rule} {len(ids)}' for rule, ids in rules.items() if ids)} | {len(found)}: "
            f"{resolved or 'none'}{f', {len(unresolved)} unresolved' if unresolved else ''} | {undecided} |")


def _documents(engines: list[str], models: bool, only: list[str] | None = None) -> None:
    """The ``--documents`` table (module docstring); ``only``: those documents alone (all are built)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from integration.interlock_documents import DOCUMENTS as INTERLOCKS
    from integration.interlock_documents import SCRIPT as INTERLOCK_SCRIPT
    from integration.test_cad_documents import BALLS, BUILD
    from integration.test_cad_documents import DOCUMENTS as STRUCTURE

    print("| document | engine | parts | export CPU s (wall s) | parts per rule | interlocked: resolved by rule "
          "| OCCT pairs undecided |\n|---|---|---:|---:|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="aplan-documents-") as tmp:
        folder = Path(tmp)
        # The open coil (pitch 12: its ring 13 times its volume, rule closest) as
        # tests/workbench/test_heavy_shapes.py builds it, and its sphere and torus as NURBS beside their boxes.
        for name, script, pitch, height in (("interlocks", f"TMP = {tmp!r}\n" + INTERLOCK_SCRIPT, 0, 0),
                                            ("structure", BUILD.format(folder=tmp, repo=str(ROOT), balls=BALLS), 0, 0),
                                            ("spring", SPRING_SCRIPT, 4, 40), ("open_coil", SPRING_SCRIPT, 12, 60),
                                            ("nurbs", NURBS_SCRIPT, 0, 0)):
            path = folder / f"{name}_build.py"
            path.write_text(script)
            subprocess.run(["freecadcmd", str(path)], check=True, capture_output=True, timeout=900,
                           env={**os.environ, "ROOT": str(ROOT), "OUT": str(folder / f"{name}.FCStd"),
                                "PITCH": str(pitch), "HEIGHT": str(height)})
        cases = [(n, folder / f"{n}.FCStd") for n in (*INTERLOCKS, *STRUCTURE, "spring", "open_coil", "nurbs")]
        if models:
            cases += [("pen (simplified)", MODELS / "bourjault_pen/simplified/asm_bourjault_ballpoint.FCStd"),
                      *CASES]
        for name, model in cases:
            if only and name not in only:
                continue
            for engine in engines:
                print(_document_row(name, model, folder / f"{name}_{engine}".replace(" ", "_"), engine), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--parts", action="store_true", help="print the volume error of every part")
    parser.add_argument("--occt", action="store_true", help="also time the OCCT engine on both models")
    parser.add_argument("--pair-budget", type=float, help="the OCCT engine's budget per pair (default: its own)")
    parser.add_argument("--springs", action="store_true", help="only the helical springs of pitch 4 (10, 20 turns)")
    parser.add_argument("--documents", action="store_true", help="issue 26's test documents (module docstring)")
    parser.add_argument("--engines", default="mesh,occt", help="--documents: the engines, comma-separated")
    parser.add_argument("--models", action="store_true", help="--documents: the pen, the truck and the pump too")
    parser.add_argument("--only", help="--documents: these documents alone, comma-separated (e.g. open_coil,nurbs)")
    args = parser.parse_args()
    if args.documents:
        _documents(args.engines.split(","), args.models, args.only.split(",") if args.only else None)
        return
    if args.springs:
        print("| turns | engine | CPU s | peak MB | parts per rule | pairs undecided |\n|---:|---|---:|---:|---|---:|")
        print("\n".join(_spring_rows()))
        return
    print("| model | parts | off by > 1 % before | worst before | worst after | methods after "
          "| tessellation s before / after |")
    print("|---|---:|---|---:|---:|---|---:|")
    details = []
    for name, model in CASES:
        result = _mesh_errors(model)
        rows = result["rows"]
        off = [f"{part} {before:+.1%}" for part, before, _, _ in rows if abs(before) > 0.01]
        worst_before = max(rows, key=lambda r: abs(r[1]))
        worst_after = max(rows, key=lambda r: abs(r[2]))
        methods: dict[str, int] = {}
        for row in rows:
            methods[row[3]] = methods.get(row[3], 0) + 1
        print(f"| {name} | {len(rows)} | {', '.join(off) or 'none'} | {worst_before[1]:+.2%} ({worst_before[0]}) | "
              f"{worst_after[2]:+.2%} ({worst_after[0]}) | {', '.join(f'{m} {n}' for m, n in methods.items())} | "
              f"{result['seconds']['before']:.1f} / {result['seconds']['after']:.1f} |")
        details.append((name, rows))
    if args.parts:
        print("\n| model | part | volume error before | after | method |\n|---|---|---:|---:|---|")
        for name, rows in details:
            for part, before, after, method in rows:
                print(f"| {name} | {part} | {before:+.3%} | {after:+.3%} | {method} |")
    if args.occt:
        print()
        for name, model in CASES:
            print(f"- {name}, OCCT engine: {_occt(model, args.pair_budget)}")


if __name__ == "__main__":
    main()
