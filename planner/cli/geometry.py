"""``aplan analyze``: the connection and obstruction diagrams of a bundle from its geometry."""
from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from ..geometry.bundle import PRODUCT_FILE, analyse_bundle
from ..product import load_product
from ..product.designer import add_directions, designer_lines, mark_not_blocking
from .options import add_force, add_tolerance_options, tolerances_from

__all__ = ["add_commands", "contact_choice"]

log = logging.getLogger(__name__)


def contact_choice(analysis: dict) -> str | None:
    """One line on the contact tolerance ``--contact auto`` chose (from ``geometry.analysis``), or None."""
    auto = analysis.get("tolerances", {}).get("contact_auto")
    if not auto:
        return None
    joined = auto.get("gaps_joined", [])
    if not joined:
        return (f"contact tolerance auto: {auto['chosen']:g} (the default: the product is connected; ceiling "
                f"{auto['ceiling']:.3g})")
    shown = ", ".join(f"{a}/{b} {gap:.4g}" for a, b, gap in joined)
    return (f"contact tolerance auto: {auto['chosen']:g} (ceiling {auto['ceiling']:.3g}), joining "
            f"{len(joined)} gap(s): {shown}")


def _analyze(args: argparse.Namespace) -> int:
    target = Path(args.product)
    path = target / PRODUCT_FILE if target.is_dir() else target
    product = load_product(path)
    product, notes = add_directions(product, args.direction)
    if args.not_blocking:  # checked (parts, direction) before the analysis runs
        product, more = mark_not_blocking(product, args.not_blocking)
        notes += more
    analysed, report = analyse_bundle(product, args.output or path, args.engine, tolerances_from(args))
    for note in notes:
        log.warning("%s", note)
    if args.json:
        print(json.dumps(report.as_dict()))
        return 0
    print(f"{path}: {len(report.parts)} parts, {len(report.contacts)} contacts, "
          f"{len(report.interferences)} interferences ({report.engine} engine, {report.seconds:.2f} s)")
    for a, b, volume in report.interferences:
        print(f"  interference {a} / {b}: {volume:.4g} cubic units")
    for axis, pairs in report.obstructions.items():
        print(f"  obstructions {axis}: {len(pairs)} pairs")
    choice = contact_choice(report.as_dict())
    if choice:
        print(f"  {choice}")
    if report.gaps:
        print(f"  the contacts fall apart into {len(report.gaps['groups'])} groups; joined by --contact "
              f"{report.gaps['tolerance']:g} (aplan stats names the gaps)")
    for line in designer_lines(analysed):
        print(f"  {line}")
    for warning in analysed.geometry["analysis"]["warnings"]:
        log.warning("%s", warning)
    return 0


def add_commands(commands) -> None:
    analyze = commands.add_parser(
        "analyze", help="compute contacts and obstruction diagrams from a bundle's geometry",
        description="Fill in the connection diagram and the +X/+Y/+Z obstruction diagrams of a product bundle "
                    "from its part meshes (mesh engine) or B-reps (occt engine, through FreeCAD).")
    analyze.add_argument("product", metavar="BUNDLE", help="a bundle folder (or its product .json)")
    analyze.add_argument("-o", "--output", metavar="FILE", help="write the product here (default: in place)")
    analyze.add_argument("--engine", default="mesh", help="mesh (default) or occt")
    analyze.add_argument("--json", action="store_true", help="print the analysis as JSON")
    add_tolerance_options(analyze)
    analyze.add_argument("--not-blocking", nargs=3, action="append", default=[],
                         metavar=("BLOCKED", "BLOCKING", "DIRECTION"),
                         help="the designer's mark: part BLOCKED, moved along DIRECTION (+X ... -Z, or X,Y,Z), does "
                              "not hit part BLOCKING, whatever the engine finds; recorded in the product "
                              "(geometry.designer) and applied after every detection; repeatable")
    add_force(analyze)
    analyze.set_defaults(run=_analyze)
