"""Stage 1 of the API: a PRODUCT argument (a product file, a bundle folder, a CAD model read through a plugin, an
embedded example) resolved into a :class:`~planner.product.Product` with the fastener groups and subassemblies to
plan, and the designer's and the proposed fastener groups."""
from __future__ import annotations

import logging
import os
from dataclasses import replace
from pathlib import Path
from typing import Callable

from ..assembly.level_supports import with_level_supports
from ..assembly.subassembly_proposals import SUBASSEMBLY_MODES, with_subassemblies
from ..defaults import MAX_COMPONENTS
from ..errors import PlannerError, UnknownProductError
from ..product import (
    FASTENER_MODES,
    FastenerGroup,
    FastenerProposals,
    Product,
    fastener_proposals,
    fold,
    load_product,
    with_fastener_mode,
)
from ..product.examples import EXAMPLES, example_path
from ..defaults import STRUCTURE_DEFAULT
from ..validation import not_regular

__all__ = ["resolve_product", "DEFAULT_MODE", "fastener_report", "accept_fasteners", "FASTENER_MODES",
           "record_detection_proposals"]

log = logging.getLogger(__name__)


#: ``--fasteners`` and ``--subassemblies`` left out: the product's own fastener groups and subassemblies, or the
#: planner's proposals (``auto``) when it has neither (:func:`resolve_product`).
DEFAULT_MODE = STRUCTURE_DEFAULT


def resolve_product(argument: str | os.PathLike | Product, tolerances=None, fasteners: str = "tagged",
                    model_options: dict | None = None, subassemblies: str | None = None,
                    max_components: int = MAX_COMPONENTS, interlocks: str = "resolve",
                    supports: str = "add") -> Product:
    """Load PRODUCT: a product file, a bundle folder, a CAD file a plugin reads (``.FCStd``, STEP: through
    FreeCAD), or the name of an embedded example (``pen``).

    A bundle whose geometry has not been analysed yet is analysed in memory with the mesh engine.
    ``tolerances`` (a :class:`~planner.geometry.Tolerances`, e.g. ``contact="auto"``): the geometry is analysed
    with them, in memory, even when the file holds an analysis (a CAD model is exported with them); the
    product's parts need meshes then.
    ``fasteners``: the fastener groups plans fold: ``tagged`` the product's own (its ``fasteners`` section),
    ``auto`` those and the planner's proposals (:func:`~planner.product.propose_fasteners`), ``none`` none.
    ``subassemblies`` (None: left as the file has them): ``designer``, ``auto`` (at most ``max_components``
    members each) or ``none``, as :func:`~planner.assembly.subassembly_proposals.with_subassemblies`.
    :data:`DEFAULT_MODE` for either (the command line's default): for a product drawn in CAD (every part has a
    mesh: a CAD model, a bundle) that has neither fastener groups nor subassemblies, the planner's proposals
    (``auto``), saying so in one note when they change the plan; else the product's own (``tagged``,
    ``designer``).
    ``model_options``: how a CAD model is read (``{"groups": {NAME: [labels]}, "exclude": [labels]}``, as
    ``aplan export-freecad --group/--exclude``); only for a CAD model, an error for anything else.
    ``interlocks``: pairs of parts that block each other along every direction, in a product drawn in CAD,
    are resolved from its meshes (``resolve``: one note per decision), refused (``error``) or left to the
    planner (``keep``), as :func:`~planner.assembly.interlocks.apply_interlock_mode`; before the proposals.
    ``supports``: parts of a product drawn in CAD that would float inside the part whose cavity holds them once
    what holds them is out (a gear in a closed housing) get a support contact with it (``add``: one note),
    are refused (``error``) or left to the planner (``keep``), as
    :func:`~planner.assembly.support_contacts.apply_support_mode`; after the interlocks. A product too large to
    judge flat is judged per level once its subassemblies are chosen
    (:func:`~planner.assembly.level_supports.with_level_supports`: here when they are, else by the first
    :func:`~planner.assembly.subassembly_proposals.with_subassemblies` that chooses them).
    """
    if fasteners not in FASTENER_MODES + (DEFAULT_MODE,):
        raise PlannerError(f"unknown fastener mode {fasteners!r}; use one of {', '.join(FASTENER_MODES)}")
    if subassemblies not in SUBASSEMBLY_MODES + (DEFAULT_MODE, None):
        raise PlannerError(f"unknown subassembly mode {subassemblies!r}; use one of {', '.join(SUBASSEMBLY_MODES)}")
    model_options = {k: v for k, v in (model_options or {}).items() if v}
    if model_options and not _is_model_file(argument):
        raise PlannerError(f"{argument}: --group and --exclude choose the components of a CAD model (.FCStd, "
                           "STEP); this product's parts are chosen already (export the model again with them)")
    from ..assembly.interlocks import INTERLOCK_MODES, apply_interlock_mode, drawn_in_cad
    from ..assembly.loose_containers import connected_structure
    from ..assembly.support_contacts import SUPPORT_MODES, apply_support_mode

    if interlocks not in INTERLOCK_MODES:
        raise PlannerError(f"unknown interlock mode {interlocks!r}; use one of {', '.join(INTERLOCK_MODES)}")
    if supports not in SUPPORT_MODES:
        raise PlannerError(f"unknown support-contact mode {supports!r}; use one of {', '.join(SUPPORT_MODES)}")

    def prepare(loaded: Product) -> Product:  # while a CAD model's meshes exist (its bundle is temporary)
        return apply_support_mode(apply_interlock_mode(loaded, interlocks), supports)

    product = prepare(argument) if isinstance(argument, Product) else _load(argument, tolerances, model_options,
                                                                            prepare)
    product = connected_structure(product)  # containers of parts that do not touch are no subassemblies
    # The designer's structure, before any proposal; a product not drawn in CAD (no meshes: synthetic, written
    # by hand) is planned as written, as the paper's products are.
    own = bool(product.fasteners or product.subassemblies) or not drawn_in_cad(product)
    fastener_mode = ("tagged" if own else "auto") if fasteners == DEFAULT_MODE else fasteners
    proposals = fastener_proposals(product).groups if fastener_mode == "auto" else ()
    resolved = with_fastener_mode(product, fastener_mode, proposals)
    _note_structure_folded(product, resolved)
    if subassemblies is not None:
        mode = ("designer" if own else "auto") if subassemblies == DEFAULT_MODE else subassemblies
        resolved = with_subassemblies(resolved, mode, max_components)
    elif resolved.subassemblies:  # its levels known already: judged once here, not at every later look
        resolved = with_level_supports(resolved)
    _note_proposals(product, resolved, fasteners == DEFAULT_MODE, subassemblies == DEFAULT_MODE)
    return resolved


def _note_structure_folded(product: Product, resolved: Product) -> None:
    """One warning per proposed fastener group that folds members of the designer's subassemblies (the
    document's structure): the group, the members and their subassembly, and the option that keeps them."""
    listed = {m: s.id for s in product.subassemblies if s.source == "designer" for m in s.parts}
    for group in resolved.fasteners[len(product.fasteners):]:
        members = [p for p in group.parts if p in listed]
        if members:
            where = ", ".join(sorted({listed[p] for p in members}))
            log.warning("the proposed fastener group %s folds %s, member%s of the designer's subassembl%s %s; "
                        "--fasteners tagged keeps them parts", group.id, ", ".join(members),
                        "s" if len(members) > 1 else "", "ies" if "," in where else "y", where)


def _note_proposals(product: Product, resolved: Product, fasteners: bool, subassemblies: bool) -> None:
    """One note when the default modes (``fasteners``, ``subassemblies``: left to the default) planned
    ``product`` with the planner's proposals: how many, and the options that plan it as the file has it."""
    folded = len(resolved.fasteners) - len(product.fasteners) if fasteners else 0
    proposed = len(resolved.subassemblies) - len(product.subassemblies) if subassemblies else 0
    if not folded and not proposed:
        return
    found = ([f"{folded} fastener group{'s' if folded > 1 else ''}"] if folded else []) + \
        ([f"{proposed} subassembl{'ies' if proposed > 1 else 'y'}"] if proposed else [])
    off = " ".join((["--fasteners tagged"] if folded else []) + (["--subassemblies designer"] if proposed else []))
    log.info("%s has no fastener groups or subassemblies of its own: planning with the planner's proposals (%s); "
             "%s turns this off", product.name or "the product", ", ".join(found), off)


def fastener_report(product: Product) -> tuple[tuple[FastenerGroup, ...], FastenerProposals]:
    """The product's own fastener groups (hosts resolved) and the planner's proposals for its other parts."""
    return fold(product).groups, fastener_proposals(product)


def accept_fasteners(product: Product) -> Product:
    """``product`` with the proposed fastener groups added to its ``fasteners`` section (its diagrams as they are:
    the interlock and support-contact rules are left to the planning)."""
    return resolve_product(product, fasteners="auto", interlocks="keep", supports="keep")


def _is_model_file(argument) -> bool:
    """Whether ``argument`` names a file that a plugin's loader reads (a CAD model)."""
    from ..plugins import registry

    return not isinstance(argument, Product) and Path(argument).is_file() and \
        Path(argument).suffix.lower() in registry().loaders


def _load(argument: str | os.PathLike, tolerances=None, model_options: dict | None = None,
          prepare: Callable[[Product], Product] = lambda p: p) -> Product:
    """The product ARGUMENT names (:func:`resolve_product`), passed through ``prepare`` while its files (a CAD
    model's temporary bundle) exist."""
    from ..geometry.bundle import PRODUCT_FILE, analyze_product, apply_report, is_analysed
    from ..plugins import registry

    def analysed(product: Product) -> Product:
        if tolerances is None and is_analysed(product):
            return product
        return apply_report(product, analyze_product(product, "mesh", *(() if tolerances is None else (tolerances,))))

    path = Path(argument)
    if path.is_dir():
        if not (path / PRODUCT_FILE).is_file():
            raise UnknownProductError(f"{argument}: is a folder without {PRODUCT_FILE}, so not a product bundle")
        return prepare(analysed(load_product(path / PRODUCT_FILE)))
    if path.is_file():
        loader = registry().loaders.get(path.suffix.lower())
        if loader is not None:
            return loader(path, **({} if tolerances is None else {"tolerances": tolerances}), **(model_options or {}),
                          prepare=prepare)
        if path.suffix.lower() in (".fcstd", ".step", ".stp"):
            raise UnknownProductError(f"{argument}: reading {path.suffix} files needs APLAN's FreeCAD side "
                                      "(install the project with `pip install -e .` and FreeCAD)")
        product = load_product(path)
        return prepare(product if tolerances is None else analysed(product))
    if str(argument) in EXAMPLES:
        product = load_product(example_path(str(argument)))
        return prepare(product if tolerances is None else analysed(product))
    if path.exists():  # a device, a FIFO, a socket: reading it would never end or block
        raise UnknownProductError(not_regular(path, "product") or f"{argument}: not a regular file")
    raise UnknownProductError(
        f"{argument}: no such file, and no embedded example of that name (embedded: {', '.join(EXAMPLES)})")


def record_detection_proposals(product: Product, meshes=None) -> Product:
    """``product`` (its diagrams as they are) with what ``--interlocks resolve`` and then ``--support-contacts
    add`` would do to it recorded as proposals in ``geometry.analysis``
    (:func:`~planner.assembly.interlock_proposals.record_proposals`,
    :func:`~planner.assembly.support_contacts.record_support_proposals`): the workbench's detection calls this
    while the meshes exist, its interlocks panel lists them (a product too large to judge flat: the support
    rule's candidates, for its levels, :func:`level_support_proposals`). The support contacts are those of the product
    with every interlock proposal applied, as the command line orders the two rules (a merged component has
    no mesh: no support contact is proposed then). Cost: that of the two rules."""
    from ..assembly.interlock_proposals import PROPOSALS_KEY, apply_proposal, record_proposals
    from ..assembly.support_contacts import CANDIDATES_KEY, SUPPORT_PROPOSALS_KEY, record_support_proposals

    recorded = record_proposals(product, meshes)
    resolved = product
    for proposal in recorded.geometry.get("analysis", {}).get(PROPOSALS_KEY, []):
        resolved = apply_proposal(resolved, proposal)
    found = record_support_proposals(resolved, meshes).geometry.get("analysis", {})
    kept = {key: found[key] for key in (SUPPORT_PROPOSALS_KEY, CANDIDATES_KEY) if found.get(key)}
    if not kept:
        return recorded
    analysis = {**recorded.geometry.get("analysis", {}), **kept}
    return replace(recorded, geometry={**recorded.geometry, "analysis": analysis})
