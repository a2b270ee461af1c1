"""The product bundle: the options that turn a PRODUCT argument into the product a plan is made of (fasteners,
subassemblies, interlocks, a CAD model's components, technical constraints, base part), and :func:`product_from`."""
from __future__ import annotations

import argparse

from ... import api
from ...assembly.hierarchy import SUBASSEMBLY_MODES
from ...defaults import MAX_COMPONENTS, STRUCTURE_DEFAULT
from ...product.examples import EXAMPLES

from .limits import add_size_options
from .values import number

__all__ = ["PRODUCT_HELP", "add_technical", "add_base_part", "add_hierarchy", "add_fasteners", "add_interlocks",
           "parse_group", "add_model_options", "model_options_from", "product_from", "add_product_options"]


PRODUCT_HELP = (f"a product file (.json), a bundle folder, a FreeCAD document or STEP file (read through "
                f"FreeCAD), or an embedded example ({', '.join(EXAMPLES)})")


def add_technical(parser) -> None:
    parser.add_argument("--technical", action=argparse.BooleanOptionalAction, default=None,
                        help="switch every technical constraint on (--technical) or off (--no-technical); "
                             "by default each constraint is as the product file marks it ('active')")


def add_base_part(parser) -> None:
    """``--base-part [PART]`` (paper Sec. V); the value is ``auto`` when PART is left out, None without the option."""
    parser.add_argument("--base-part", nargs="?", const="auto", metavar="PART",
                        help="only the assembly sequences that start from PART (their first operation joins it) "
                             "and their intentions; without PART: the most connected part (paper Sec. V)")


def add_hierarchy(parser, level: bool = True) -> None:
    """``--subassemblies {designer,auto,none}``, ``--max-components N`` and (with ``level``) ``--level ID``."""
    parser.add_argument("--subassemblies", choices=SUBASSEMBLY_MODES, default=STRUCTURE_DEFAULT,
                        help="designer: plan each subassembly of the product file as a workstation of its own (flat "
                             "when it has none); auto: the same, proposing subassemblies when it has none; none: "
                             "plan the whole product flat. Default: designer, or auto when a CAD model (a bundle) "
                             "has neither fastener groups nor subassemblies of its own (a note says so)")
    parser.add_argument("--max-components", type=number(2, integer=True), default=MAX_COMPONENTS, metavar="N",
                        help=f"--subassemblies auto: at most N members per proposed subassembly, at least 2 "
                             f"(default {MAX_COMPONENTS})")
    if level:
        parser.add_argument("--level", metavar="ID",
                            help="plan one subassembly (one workstation; 'top' for the top level): its members "
                                 "are its parts, a built subassembly is one part")


def add_fasteners(parser) -> None:
    """``--fasteners {tagged,auto,none}``: the fastener groups a plan folds into the operations that install them."""
    parser.add_argument("--fasteners", choices=("tagged", "auto", "none"), default=STRUCTURE_DEFAULT,
                        help="fold fasteners into the operations that install them: tagged: the groups of the "
                             "product's 'fasteners' section; auto: those and the planner's proposals (names such "
                             "as screw, bolt, nut; small parts joining two others: see aplan fasteners); none: plan "
                             "every part. Default: tagged, or auto when a CAD model (a bundle) has neither fastener "
                             "groups nor subassemblies of its own (a note says so)")
    add_interlocks(parser)


def add_interlocks(parser) -> None:
    """``--interlocks {resolve,error,keep}``: what to do with parts that block each other along every direction;
    ``--support-contacts {add,error,keep}``: with parts that would float in the part whose cavity holds them."""
    parser.add_argument("--interlocks", choices=("resolve", "error", "keep"), default="resolve",
                        help="pairs of parts that block each other along every direction, in a product drawn in "
                             "CAD: resolve: from the geometry (an overlap's insertion direction, a direction found "
                             "on the pair, else one component), one line per decision (default); error: refuse, "
                             "naming what would be done; keep: plan the diagrams as they are")
    parser.add_argument("--support-contacts", choices=("add", "error", "keep"), default="add",
                        help="parts of a product drawn in CAD that would touch nothing once what holds them is "
                             "taken out, inside a part whose cavity holds them (a gear in a closed housing once "
                             "its shaft is out): add: a support contact with that part, when the product cannot "
                             "be taken apart otherwise, one line saying so (default); error: refuse, naming the "
                             "contacts; keep: plan the contacts as they are")


def parse_group(text: str) -> tuple[str, list[str]]:
    """``NAME=A,B,...`` (``--group``): the component's name and its objects' labels or patterns."""
    name, sep, members = text.partition("=")
    if not sep or not name or not members:
        raise argparse.ArgumentTypeError(f"expected NAME=LABEL,LABEL,..., got {text!r}")
    return name, [m for m in members.split(",") if m]


def add_model_options(parser) -> None:
    """``--group`` and ``--exclude`` for a PRODUCT given as a CAD model (export-freecad's, same meaning)."""
    group = parser.add_argument_group("when PRODUCT is a CAD model (.FCStd, STEP), as aplan export-freecad")
    group.add_argument("--group", action="append", type=parse_group, default=[], metavar="NAME=A,B,...",
                       help="make one component NAME of the objects A, B, ... (labels or shell-style patterns; "
                            "repeatable)")
    group.add_argument("--exclude", action="append", default=[], metavar="LABEL",
                       help="leave out the objects with this label or matching this pattern (repeatable)")


def model_options_from(args: argparse.Namespace) -> dict:
    """The CAD model options of ``args`` (:func:`add_model_options`) for :func:`planner.api.resolve_product`."""
    return {"groups": dict(getattr(args, "group", None) or []), "exclude": list(getattr(args, "exclude", None) or [])}


def product_from(args: argparse.Namespace, argument, tolerances=None):
    """PRODUCT resolved with ``--fasteners``, ``--subassemblies`` (``--max-components``) and the CAD model
    options (a Product, its subassemblies chosen: plan it with the ``designer`` mode); a decision model file's
    name stays as it is. ``tolerances``: the geometry analysed again with them (``--contact``)."""
    if isinstance(argument, api.Product) or str(argument).lower().endswith(api.MODEL_SUFFIXES):
        return argument   # a product already resolved (a level: its fasteners were chosen with the whole)
    return api.resolve_product(argument, tolerances, getattr(args, "fasteners", STRUCTURE_DEFAULT),
                               model_options_from(args), getattr(args, "subassemblies", None),
                               getattr(args, "max_components", MAX_COMPONENTS),
                               getattr(args, "interlocks", "resolve"), getattr(args, "support_contacts", "add"))


def add_product_options(parser, level: bool = True) -> None:
    """The options that turn a PRODUCT into the product a plan is made of (:func:`product_from`) and its size
    limits: technical constraints, base part, subassemblies (and, with ``level``, one level), fasteners, a CAD
    model's components; the commands that plan without a decision model (stats, intentions, sequence)."""
    add_technical(parser)
    add_base_part(parser)
    add_hierarchy(parser, level)
    add_fasteners(parser)
    add_model_options(parser)
    add_size_options(parser)
