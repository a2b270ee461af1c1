"""The planner's application interface: what every front end (the ``aplan`` command line, the FreeCAD
workbench, batch jobs, user scripts) does with a product, in one place.

Front ends only parse their input and show results; the steps of the method live here, each a plain function:

1. :func:`resolve_product`: a PRODUCT argument (a product file, a bundle folder, a CAD file read through
   a plugin, or an embedded example) -> :class:`~planner.product.Product`, with the fastener groups to fold
   (``tagged``, ``auto``, ``none``); :func:`fastener_report`, :func:`accept_fasteners`: the designer's and
   the proposed fastener groups;
2. :func:`plan_statistics_of`: the plan of a product and its figures (``aplan stats``); :func:`base_part_of`:
   the base part every sequence starts from (paper Sec. V), ``"auto"`` for the most connected part;
3. :func:`decision_model` / :func:`lumped_model` / :func:`load_model` / :func:`save_model`: the decision model
   of Alg. 3 (over intentions, or lumped over the factored model's classes), or a POMDP read from a file, and
   writing it as POMDPX or ``.pomdp``;
4. :func:`solve`, :func:`policy_for`: a policy from a solver (the built-in point-based one, or SARSOP);
5. :func:`simulate`, :func:`evaluate`: episodes of an operator against a policy;
6. :func:`decision_maker`: the model and policy a session, a simulation or an evaluation runs: the offline
   policy on the flat model (the paper's), or the online planner on the factored model (paper Sec. V), chosen
   by :func:`choose_planner`.

>>> from planner import api
>>> model = api.decision_model("pen")
>>> model.pomdp.n_states, model.pomdp.n_actions, model.pomdp.n_observations
(69, 22, 12)
"""
from __future__ import annotations

import logging
import math
import os
import shutil
from contextlib import contextmanager, nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .assembly.explode import ExplodedView, exploded_view, first_sequences, sequence_at
from .assembly.guards import OPTIONS, SizeLimits, default_memory_budget, memory_options
from .assembly.hierarchy import (
    SUBASSEMBLY_MODES,
    Level,
    level_statistics,
    product_levels,
    propose_subassemblies,
    select_level,
    with_subassemblies,
)
from .assembly.intentions import base_part_first_edges, count_intentions, most_connected_part
from .assembly.plan import Plan, make_plan
from .assembly.stats import STAT_KEYS, PlanStatistics, plan_statistics, statistics_within
from .decision.factored_model import FactoredIntentionModel, factored_model
from .decision.deviations import Deviations
from .decision.habits import Habits, habit_weights
from .decision.parallel import check_parallel_memory, parallel_flag
from .decision.intention_model import IntentionModel, Rewards, flat_model_bytes, flat_model_fits, intention_model
from .decision.io.cassandra import read_cassandra, write_cassandra
from .decision.io.pomdpx import read_pomdpx, write_pomdpx
from .decision.io.size import model_file_bytes
from .decision.budget import (
    check_flat_solver_memory,
    check_lumped_memory,
    check_online_memory,
    check_solver_memory,
    flat_limits,
    lumped_limits,
    lumped_start_fits,
    online_limits,
)
from .decision.lumped_model import LumpedModel
from .decision.episodes import evaluate, evaluate_operator, simulate
from .decision.models import is_flat, is_lumped, solver_plan, tables
from .decision.lumped_model import lumped_model as build_lumped_model
from .decision.online import OnlinePlanner
from .decision.policy import AlphaVectorPolicy, PolicyError, read_policy
from .decision.pomdp import POMDP
from .decision.solvers import PointBasedSolver, SarsopSolver, SolveResult
from .decision.solvers.warm_start import WarmStart
from .defaults import (
    DECISION_TIME,
    DISCOUNT,
    FILE_LIMIT,
    INTENTION_LIMIT,
    MAX_COMPONENTS,
    ONLINE_EXPANSIONS,
    POLICY_TIME_LIMIT,
    SOLVE_PRECISION,
    SOLVE_TIME_LIMIT,
    SUBASSEMBLY_LIMIT,
)
from .errors import (
    DisconnectedProductError,
    FileLimitError,
    MemoryLimitError,
    PlannerError,
    SolveTimeError,
    UnknownProductError,
    gib,
)
from .interrupts import deferred_interrupts
from .product import (
    FASTENER_MODES,
    FastenerGroup,
    FastenerProposals,
    Product,
    Subassembly,
    fastener_proposals,
    fold,
    load_product,
    with_fastener_mode,
)
from .product.examples import EXAMPLES, example_path
from .runtime.logged_sequence import LoggedSequence, complete_sequence, logged_sequence
from .defaults import STRUCTURE_DEFAULT
from .validation import InputLimits, not_regular

__all__ = ["resolve_product", "DEFAULT_MODE", "fastener_report", "accept_fasteners", "FASTENER_MODES", "plan_of",
           "proposed_subassemblies", "structure_problems", "level_report", "level_table", "LEVEL_KEYS",
           "explain_disconnected", "plan_statistics_of", "base_part_of", "decision_model", "lumped_model",
           "load_model", "save_model", "check_model_file", "tables", "MODEL_SUFFIXES", "SOLVER_ENGINES", "solve",
           "check_solved", "evaluate_operator",
           "policy_for", "simulate", "evaluate", "PLANNERS", "factored_decision_model", "online_planner",
           "choose_planner", "decision_maker", "arranged", "levels_of", "level_product", "hierarchy_statistics_of",
           "sequence_choices", "plan_in_3d", "sequence_from_log", "InputLimits"]

log = logging.getLogger(__name__)

MODEL_SUFFIXES = (".pomdpx", ".pomdpx.gz", ".pomdp")
FILE_OPTION = ("--max-file", "--max-file GIB raises the file size budget")
SOLVER_ENGINES = ("builtin", "sarsop")

PLANNERS = ("offline", "online")

Model = IntentionModel | LumpedModel | POMDP

log = logging.getLogger(__name__)


#: ``--fasteners`` and ``--subassemblies`` left out: the product's own fastener groups and subassemblies, or the
#: planner's proposals (``auto``) when it has neither (:func:`resolve_product`).
DEFAULT_MODE = STRUCTURE_DEFAULT


def resolve_product(argument: str | os.PathLike | Product, tolerances=None, fasteners: str = "tagged",
                    model_options: dict | None = None, subassemblies: str | None = None,
                    max_components: int = MAX_COMPONENTS, interlocks: str = "resolve") -> Product:
    """Load PRODUCT: a product file, a bundle folder, a CAD file a plugin reads (``.FCStd``, STEP: through
    FreeCAD), or the name of an embedded example (``pen``).

    A bundle whose geometry has not been analysed yet is analysed in memory with the mesh engine.
    ``tolerances`` (a :class:`~planner.geometry.Tolerances`, e.g. ``contact="auto"``): the geometry is analysed
    with them, in memory, even when the file holds an analysis (a CAD model is exported with them); the
    product's parts need meshes then.
    ``fasteners``: the fastener groups plans fold: ``tagged`` the product's own (its ``fasteners`` section),
    ``auto`` those and the planner's proposals (:func:`~planner.product.propose_fasteners`), ``none`` none.
    ``subassemblies`` (None: left as the file has them): ``designer``, ``auto`` (at most ``max_components``
    members each) or ``none``, as :func:`~planner.assembly.hierarchy.with_subassemblies`.
    :data:`DEFAULT_MODE` for either (the command line's default): for a product drawn in CAD (every part has a
    mesh: a CAD model, a bundle) that has neither fastener groups nor subassemblies, the planner's proposals
    (``auto``), saying so in one note when they change the plan; else the product's own (``tagged``,
    ``designer``).
    ``model_options``: how a CAD model is read (``{"groups": {NAME: [labels]}, "exclude": [labels]}``, as
    ``aplan export-freecad --group/--exclude``); only for a CAD model, an error for anything else.
    ``interlocks``: pairs of parts that block each other along every direction, in a product drawn in CAD,
    are resolved from its meshes (``resolve``: one note per decision), refused (``error``) or left to the
    planner (``keep``), as :func:`~planner.assembly.interlocks.apply_interlock_mode`; before the proposals.
    """
    if fasteners not in FASTENER_MODES + (DEFAULT_MODE,):
        raise PlannerError(f"unknown fastener mode {fasteners!r}; use one of {', '.join(FASTENER_MODES)}")
    if subassemblies not in SUBASSEMBLY_MODES + (DEFAULT_MODE, None):
        raise PlannerError(f"unknown subassembly mode {subassemblies!r}; use one of {', '.join(SUBASSEMBLY_MODES)}")
    model_options = {k: v for k, v in (model_options or {}).items() if v}
    if model_options and not _is_model_file(argument):
        raise PlannerError(f"{argument}: --group and --exclude choose the components of a CAD model (.FCStd, "
                           "STEP); this product's parts are chosen already (export the model again with them)")
    from .assembly.interlocks import INTERLOCK_MODES, apply_interlock_mode, drawn_in_cad

    if interlocks not in INTERLOCK_MODES:
        raise PlannerError(f"unknown interlock mode {interlocks!r}; use one of {', '.join(INTERLOCK_MODES)}")

    def prepare(loaded: Product) -> Product:  # while a CAD model's meshes exist (its bundle is temporary)
        return apply_interlock_mode(loaded, interlocks)

    product = prepare(argument) if isinstance(argument, Product) else _load(argument, tolerances, model_options,
                                                                            prepare)
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
    the interlock rules are left to the planning)."""
    return resolve_product(product, fasteners="auto", interlocks="keep")


def _is_model_file(argument) -> bool:
    """Whether ``argument`` names a file that a plugin's loader reads (a CAD model)."""
    from .plugins import registry

    return not isinstance(argument, Product) and Path(argument).is_file() and \
        Path(argument).suffix.lower() in registry().loaders


def _load(argument: str | os.PathLike, tolerances=None, model_options: dict | None = None,
          prepare: Callable[[Product], Product] = lambda p: p) -> Product:
    """The product ARGUMENT names (:func:`resolve_product`), passed through ``prepare`` while its files (a CAD
    model's temporary bundle) exist."""
    from .geometry.bundle import PRODUCT_FILE, analyze_product, apply_report, is_analysed
    from .plugins import registry

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


def explain_disconnected(product: Product, error: DisconnectedProductError) -> DisconnectedProductError:
    """``error`` with the gaps between its groups: those the product's analysis recorded
    (``geometry.analysis.gaps``), else measured on the part meshes when the product has them; ``error`` itself
    when neither can say."""
    from .geometry.bundle import load_part_meshes
    from .geometry.clearances import explain_groups
    from .geometry.gaps import contact_tolerance_for

    if error.gaps is not None:
        return error
    report = explain_groups(error.groups, product.geometry.get("analysis", {}).get("gaps"))
    if report is None and product.parts and all(p.mesh for p in product.parts):
        try:
            report = explain_groups(error.groups, None, load_part_meshes(product))
        except PlannerError:  # unreadable meshes: the error without gaps is still right
            return error
    if report is None:
        return error
    gaps = [(g.a, g.b, g.distance, contact_tolerance_for(g.distance)) if g is not None else None
            for g in report.nearest]
    return DisconnectedProductError(error.groups, gaps, contact_tolerance_for(report.bottleneck), product.units)


@contextmanager
def _gaps_explained(product: Product):
    """Re-raise a :class:`DisconnectedProductError` with the gaps between its groups (:func:`explain_disconnected`)."""
    try:
        yield
    except DisconnectedProductError as error:
        explained = explain_disconnected(product, error)
        if not explained.source and product.source and product.source != "<memory>":  # name the file
            explained = DisconnectedProductError(explained.groups, explained.gaps, explained.tolerance,
                                                 explained.units, product.source)
        if explained is error:
            raise
        raise explained from None


def plan_of(product: str | os.PathLike | Product, technical: bool | None = None,
            limits: SizeLimits = SizeLimits()) -> Plan:
    """The plan (AND/OR graph, assembly states, tags) of a product or PRODUCT argument; ``technical``:
    ``True``/``False`` switches every technical constraint on/off, ``None`` keeps the file's; ``limits``: the
    size limits the plan is built within (past them: :class:`~planner.errors.LimitExceededError`). A product
    that falls apart is refused with the gaps between its groups (:func:`explain_disconnected`)."""
    product = product if isinstance(product, Product) else resolve_product(product)
    with _gaps_explained(product):
        return make_plan(product, technical, limits)


def _decidable(plan: Plan) -> Plan:
    """``plan`` if a decision model can be built on it: at least one assembly operation (two parts), else a
    :class:`PlannerError` saying so (a model of nothing to do would have no action to choose)."""
    if len(plan.product.parts) < 2:
        raise PlannerError(f"{plan.product.source or plan.product.name or 'the product'}: "
                           f"{len(plan.product.parts)} part, so nothing to assemble: a decision model needs a "
                           "product of at least two parts (aplan stats still describes it)")
    return plan


def arranged(product: str | os.PathLike | Product, subassemblies: str = "designer", max_components: int = MAX_COMPONENTS) -> Product:
    """The product with the subassemblies ``subassemblies`` asks for
    (:func:`~planner.assembly.hierarchy.with_subassemblies`): ``designer`` the file's, ``auto`` proposed when the
    file has none (at most ``max_components`` members each), ``none`` none."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return with_subassemblies(product, subassemblies, max_components)


def levels_of(product: str | os.PathLike | Product, subassemblies: str = "designer",
              max_components: int = MAX_COMPONENTS) -> list[Level]:
    """The workstations of a product, bottom-up (:func:`~planner.assembly.hierarchy.product_levels`) with its
    subassemblies as ``subassemblies`` asks: ``designer`` (the file's), ``auto`` (proposed when the file has
    none, at most ``max_components`` members each) or ``none`` (one level: the product flat)."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return product_levels(with_subassemblies(product, subassemblies, max_components))


def level_product(product: str | os.PathLike | Product, subassemblies: str = "designer", level: str | None = None,
                  max_components: int = MAX_COMPONENTS) -> Product:
    """The product one workstation plans: level ``level`` (a subassembly id or ``top``), or the product itself
    when it is planned flat; several levels without ``level`` is a :class:`PlannerError` naming them."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return select_level(with_subassemblies(product, subassemblies, max_components), level).product


def hierarchy_statistics_of(product: str | os.PathLike | Product, technical: bool | None = None,
                            limits: SizeLimits = SizeLimits(), subassemblies: str = "designer",
                            max_components: int = MAX_COMPONENTS, flat_limits: SizeLimits | None = None,
                            progress: Callable[[str], None] | None = None):
    """The figures of every level (``[(Level, PlanStatistics)]``, bottom-up) and of the product planned flat:
    a :class:`PlanStatistics` within ``flat_limits`` (default ``limits``), or the :class:`PlannerError` that
    stopped it (not connected, not disassemblable); None when the product is one level."""
    product = product if isinstance(product, Product) else resolve_product(product)
    arranged = with_subassemblies(product, subassemblies, max_components)
    levels = level_statistics(arranged, technical, limits, progress)
    if len(levels) == 1:
        return levels, None
    if progress is not None:
        progress("the product planned flat, for comparison")
    flat = replace(product, subassemblies=())
    try:
        _, flat_stats = statistics_within(flat, technical, None, flat_limits or limits)
    except PlannerError as error:
        return levels, error
    return levels, flat_stats


# The figures a hierarchy adds up over its levels (sequences multiply: each workstation picks its own).
LEVEL_KEYS = ("parts", "subassemblies", "operations", "states", "state_edges", "intentions", "sequences")


def proposed_subassemblies(product: Product, max_components: int = MAX_COMPONENTS) -> tuple[Subassembly, ...]:
    """The planner's subassembly tree for ``product``, ignoring any it already has
    (:func:`~planner.assembly.hierarchy.propose_subassemblies`: what ``--subassemblies auto`` plans with)."""
    return propose_subassemblies(replace(product, subassemblies=()), max_components)


def structure_problems(product: Product, limit: int = 100_000) -> list[tuple[str, str]]:
    """``(level id, reason)`` for every level of ``product`` that cannot be built on its own: a technical
    constraint it breaks, members that do not touch, or stuck members (named by the planner's error).

    Each level's AND/OR graph is tried within ``limit`` connected part sets; a level past it is not judged
    here (its plan will say). Cost: at most ``limit`` connected sets per level, plus O(levels x relations).
    """
    from .assembly.andor import and_or_graph
    from .assembly.hierarchy import check_level_constraints
    from .errors import LimitExceededError

    problems = []
    for level in product_levels(product):
        try:
            check_level_constraints(product, level)
            and_or_graph(level.product, limit=limit)
        except LimitExceededError:
            continue
        except PlannerError as error:
            problems.append((level.id, str(error)))
    return problems


def level_report(product: Product, technical: bool | None = None, limits: SizeLimits = SizeLimits(),
                 flat_limits: SizeLimits | None = None, progress: Callable[[str], None] | None = None) -> dict:
    """The figures ``aplan stats --json`` prints for a product of several levels: ``levels`` (each level's id,
    members, figures and, when it was refused or failed, ``not_computed`` or ``error``), ``total`` (sums over
    the levels; parts: the product's; sequences: the product of the levels') and ``flat`` (the product planned
    flat within ``flat_limits``, else None and ``flat_not_computed``). ``progress(text)`` is told each level as
    it is done. Cost: the levels' plans plus the flat plan within its limits."""
    flat_limits = flat_limits or SizeLimits(min(limits.subassemblies, SUBASSEMBLY_LIMIT), min(limits.memory, 2 ** 30))
    levels, flat = hierarchy_statistics_of(product, technical, limits, flat_limits=flat_limits, progress=progress)
    return level_table(product, levels, flat)


def level_table(product: Product, levels: list, flat) -> dict:
    """:func:`level_report`'s dict from :func:`hierarchy_statistics_of`'s answer ``(levels, flat)`` (each
    level's statistics or the error it ended with; the flat statistics, the reason they are missing, or None).
    Cost: O(levels x figures)."""
    rows = []
    for level, stats in levels:
        row = {"level": level.id, "members": list(level.members)}
        if isinstance(stats, PlanStatistics):
            row.update(stats.as_dict())
            if stats.refused:
                row["not_computed"] = str(stats.refused)
        else:
            row.update({key: None for key in STAT_KEYS})
            row["error"] = str(stats)
        rows.append(row)
    total: dict[str, int | None] = {}
    for key in LEVEL_KEYS:
        values = [row[key] for row in rows]
        if key == "parts":
            total[key] = len(product.parts)
        elif any(v is None for v in values):
            total[key] = None
        elif key == "sequences":
            total[key] = int(np.prod(values, dtype=object))
        else:
            total[key] = sum(values)
    out = {"levels": rows, "total": total, "flat": flat.as_dict() if isinstance(flat, PlanStatistics) else None}
    reason = (str(flat.refused) if isinstance(flat, PlanStatistics) and flat.refused else
              None if isinstance(flat, PlanStatistics) or flat is None else str(flat))
    if reason:
        out["flat_not_computed"] = reason
    return out


AUTO_BASE_PART = "auto"


def base_part_of(plan: Plan, base_part: str | None) -> str | None:
    """The base part that sequences start from (paper Sec. V): None (every sequence), ``"auto"`` (the most
    connected part, :func:`~planner.assembly.intentions.most_connected_part`) or a part id, checked: a
    :class:`PlannerError` that lists the parts when it is not one. The one place ``"auto"`` is resolved."""
    if base_part is None or base_part == "":
        return None
    base = most_connected_part(plan.product) if base_part == AUTO_BASE_PART else str(base_part)
    base_part_first_edges(plan.states, base)  # raises for a part the product does not have
    return base


def sequence_choices(plan: Plan, base_part: str | None = None, limit: int = 200) -> tuple[int, list[list[int]]]:
    """The number of full assembly sequences (from ``base_part``, ``"auto"`` resolved) and the first ``limit``
    of them by rank (:func:`~planner.assembly.explode.sequence_at`): what a sequence chooser lists; past the
    limit a chooser asks for a rank."""
    return first_sequences(plan, limit, base_part_of(plan, base_part))


def plan_in_3d(plan: Plan, sequence: int | Sequence[int], spacing: float = 1.0,
               base_part: str | None = None) -> ExplodedView:
    """The exploded view of a full assembly sequence (:mod:`planner.assembly.explode`): ``sequence`` is a rank
    (among the sequences from ``base_part``) or the operations themselves; the base part (``"auto"``
    resolved) also decides which side of each operation moves."""
    base = base_part_of(plan, base_part)
    operations = sequence_at(plan, sequence, base) if isinstance(sequence, (int, np.integer)) else list(sequence)
    return exploded_view(plan, operations, spacing, base)


def sequence_from_log(path: str | os.PathLike, plan: Plan | None = None,
                      inputs: InputLimits = InputLimits()) -> tuple[list[int], LoggedSequence]:
    """The sequence a session log recorded (:func:`~planner.runtime.logged_sequence.logged_sequence`), completed
    by the first continuation when the session stopped early, as operations of ``plan`` (default: the plan of
    the product the log stores). Raises :class:`PlannerError` when the log's operations are not operations
    of ``plan`` (a log of another product). ``inputs``: the limits the log is read within."""
    logged = logged_sequence(path, inputs)
    operations = complete_sequence(logged.plan, list(logged.operations))
    if plan is None:
        return operations, logged
    index = {frozenset(plan.andor.inputs(j)): j for j in range(len(plan.andor.operations))}
    mapped = []
    for operation in operations:
        inputs = logged.plan.andor.inputs(operation)
        if frozenset(inputs) not in index:
            raise PlannerError(f"{path}: the logged operation {logged.plan.andor.describe(operation)} is not an "
                               f"operation of {plan.product.name or 'this product'}; the log was recorded for "
                               f"{logged.product.name or 'another product'} (parts: {', '.join(logged.plan.andor.parts)})")
        mapped.append(index[frozenset(inputs)])
    return mapped, logged


def plan_statistics_of(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                       base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                       partial: bool = False) -> tuple[Plan | None, PlanStatistics]:
    """The plan and its figures (``aplan stats``). ``base_part``: count only the sequences whose first
    operation joins it, and their intentions; ``"auto"``: the most connected part (:func:`base_part_of`). With
    ``partial``, a plan past ``limits`` gives the figures that could be counted (the others None, the reason in
    ``refused``) and no plan, instead of :class:`~planner.errors.LimitExceededError`."""
    if isinstance(product, Plan) or not partial:
        plan = product if isinstance(product, Plan) else plan_of(product, technical, limits)
        return plan, plan_statistics(plan, base_part_of(plan, base_part))
    product = product if isinstance(product, Product) else resolve_product(product)
    base = most_connected_part(fold(product).product) if base_part == AUTO_BASE_PART else base_part
    with _gaps_explained(product):
        return statistics_within(product, technical, base, limits)


def decision_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                   rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                   base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                   habits: Habits | None = None, solving: bool = False,
                   deviations: Deviations | None = None) -> IntentionModel:
    """The decision model of Alg. 3 of a product, PRODUCT argument or plan; ``base_part``: only the sequences
    that start from it (``"auto"``: the most connected part, :func:`base_part_of`); refused, with the estimate,
    past ``limits`` (the plan's, and the flat model's memory:
    :func:`~planner.decision.intention_model.flat_model_bytes`); with ``solving``, also when the solver would
    not fit beside it (:func:`~planner.decision.budget.check_flat_solver_memory`), before it is built.
    ``habits``: the operator's habits in place of the uniform choice (:mod:`~planner.decision.habits`; checked
    to be this product's), None for the paper's; ``deviations``: change of mind and mistakes
    (:mod:`~planner.decision.deviations`), None for the paper's."""
    plan = product if isinstance(product, Plan) else \
        _decidable(plan_of(product, technical, flat_limits(limits, solving) if base_part is None else limits))
    base = base_part_of(plan, base_part)
    if solving:  # refused before the flat model is built when the solver would not fit beside it
        check_flat_solver_memory(plan, count_intentions(plan.states, base_part=base), limits.memory)
    return intention_model(plan, rewards, discount, base_part=base, max_bytes=limits.memory,
                           weights=habit_weights(plan, habits), deviations=deviations)


def factored_decision_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                            rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                            base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                            habits: Habits | None = None, parallel: bool = False,
                            deviations: Deviations | None = None) -> FactoredIntentionModel:
    """The same decision model without enumerating intentions (paper Sec. V): beliefs over classes;
    ``parallel``: the parallel model (docs/parallel.md); ``deviations``: change of mind and mistakes."""
    plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical, limits))
    if parallel:
        check_parallel_memory(plan, limits.memory, parallel)
    return factored_model(plan, rewards, discount, base_part_of(plan, base_part), habit_weights(plan, habits),
                          parallel, deviations)


def online_planner(model: FactoredIntentionModel, decision_time: float | None = DECISION_TIME,
                   expansions: int | None = None, lower: AlphaVectorPolicy | None = None) -> OnlinePlanner:
    """The online planner on ``model``: at most ``decision_time`` seconds and ``expansions`` expansions per
    decision. ``expansions`` alone (``decision_time`` None) is a fixed amount of work: the same actions on any
    machine. ``lower``: an offline policy over the model's classes whose value the search starts from."""
    if decision_time is None and expansions is None:
        raise PlannerError("the online planner needs a decision time or a number of expansions")
    return OnlinePlanner(model, expansions if expansions is not None else ONLINE_EXPANSIONS, decision_time,
                         lower=lower)


def choose_planner(plan: Plan, planner: str | None, policy: str | os.PathLike | None,
                   limit: int = INTENTION_LIMIT, base_part: str | None = None,
                   limits: SizeLimits = SizeLimits()) -> tuple[str, str | None]:
    """``offline`` or ``online``, and why when it was not asked for. ``planner`` None: offline with a policy
    file, else online (no policy to follow); a flat model of more than ``limit`` intentions or past
    ``limits.memory`` is never built: offline then needs a policy over the lumped model's classes, and without
    one the online planner decides."""
    if planner is not None and planner not in PLANNERS:
        raise PlannerError(f"unknown planner {planner!r}; use one of {', '.join(PLANNERS)}")
    if planner is not None:
        return planner, None
    if policy:
        return "offline", None
    intentions = count_intentions(plan.states, base_part=base_part)
    if not flat_model_fits(plan, limits.memory, limit, intentions):
        needed = flat_model_bytes(plan, intentions)
        passed = (f"about {gib(needed)}, past the memory budget of {gib(limits.memory)}" if needed > limits.memory
                  else f"past the intention limit of {limit:,}")
        return "online", (f"the flat model would hold {intentions:,} intentions ({passed}) and no --policy was "
                          "given: using the online planner")
    return "online", "no --policy: using the online planner"


def decision_maker(product: str | os.PathLike | Product | Plan, planner: str | None = None,
                   policy: str | os.PathLike | None = None, technical: bool | None = None,
                   rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                   decision_time: float | None = DECISION_TIME, expansions: int | None = None,
                   time_limit: float = POLICY_TIME_LIMIT, limit: int = INTENTION_LIMIT,
                   base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                   inputs: InputLimits = InputLimits(), habits: Habits | None = None, parallel: bool = False,
                   deviations: Deviations | None = None):
    """The model, the policy and a note (what was chosen and why, or None) that a session, a simulation or an
    evaluation runs on:

    - online: the factored model and :func:`online_planner` (with ``policy``, a policy over the classes, as
      the lower bound it starts from);
    - offline with a policy over the lumped model's classes: the factored model and that policy;
    - offline otherwise: the flat model of Alg. 3 (refused above ``limit`` intentions, naming ``--planner
      online``) and the policy file, or the built-in solver's policy after ``time_limit`` seconds.

    ``base_part``: only the sequences that start from it (``"auto"``: the most connected part); ``inputs``:
    what the policy file may hold (:class:`~planner.validation.InputLimits`); ``habits``: the operator's habits
    in every model (:mod:`~planner.decision.habits`), None for the paper's model; ``parallel``: the parallel model
    (docs/parallel.md), on the classes only: with it the flat model is refused (:func:`check_parallel_flat`);
    ``deviations``: change of mind and mistakes in every model (:mod:`~planner.decision.deviations`), None for
    the paper's.
    """
    plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical, online_limits(limits)))
    base_part = base_part_of(plan, base_part)
    weights = habit_weights(plan, habits)
    choice, note = choose_planner(plan, planner, policy, limit, base_part, limits)
    if choice == "online":
        check_online_memory(plan, limits.memory)
        if parallel:
            check_parallel_memory(plan, limits.memory, parallel)
        model = factored_model(plan, rewards, discount, base_part, weights, parallel, deviations)
        lower = read_policy(policy, limits=inputs) if policy else None
        return model, online_planner(model, decision_time, expansions, lower), note
    intentions = count_intentions(plan.states, base_part=base_part)
    vectors = read_policy(policy, limits=inputs) if policy else None
    if vectors is not None:
        classes = plan.states.n_edges + 1  # the factored model's classes: one per state edge, and finished
        length = vectors.alphas.shape[1]
        if length not in (intentions, classes):
            raise PolicyError(f"{policy}: vectors of length {length:,}, but this product's model has {intentions:,} "
                              f"intentions (flat) and {classes:,} classes (lumped): the policy belongs to "
                              "another model (check the product, --technical and --base-part)")
        if length == classes and length != intentions:
            check_online_memory(plan, limits.memory)
            if parallel:
                check_parallel_memory(plan, limits.memory, parallel)
            lumped = factored_model(plan, rewards, discount, base_part, weights, parallel, deviations)
            vectors.check_sizes(lumped.n_classes, len(lumped.actions), str(policy))
            return lumped, vectors, None
    check_parallel_flat(parallel, "--planner offline")
    # Past the limits this raises, with the estimate and the options (--planner online among them).
    model = intention_model(plan, rewards, discount, limit=limit, base_part=base_part, max_bytes=limits.memory,
                            weights=weights, deviations=deviations)
    if vectors is not None:
        vectors.check(model.pomdp, str(policy))
        return model, vectors, note
    vectors, result = policy_for(model, None, time_limit)
    note = (f"no --policy: solved for {result.seconds:.1f} s, lower bound {result.lower_bound:.5f}, upper "
            f"bound {result.upper_bound:.5f}")
    return model, vectors, note


def lumped_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                 rewards: Rewards = Rewards(), discount: float = DISCOUNT, base_part: str | None = None,
                 limits: SizeLimits = SizeLimits(), habits: Habits | None = None,
                 parallel: bool = False, deviations: Deviations | None = None) -> LumpedModel:
    """The decision model of Alg. 3 lumped onto the factored model's classes (state edges and the finished
    product; :mod:`~planner.decision.lumped_model`): the same value as the flat model, far fewer states.
    ``.factored`` filters beliefs over classes, ``.pomdp`` (named ``<product>:lumped``) is what solvers take."""
    plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical, lumped_limits(limits)))
    check_lumped_memory(plan, limits.memory)
    if parallel:
        check_parallel_memory(plan, limits.memory, parallel)
    return build_lumped_model(plan, rewards, discount, base_part_of(plan, base_part), habit_weights(plan, habits),
                              parallel, deviations)


def check_parallel_flat(parallel: bool, where: str) -> None:
    """The parallel model lives on the classes (docs/parallel.md): the flat model over intentions cannot hold
    it (a wrong parallel action would condition the distribution within a class), so ``where`` with it is a
    :class:`PlannerError` naming what helps."""
    if parallel:
        flag = parallel_flag(parallel)
        raise PlannerError(f"{flag} is a model over the factored model's classes, and {where} would build the "
                           "flat model over intentions, which cannot hold it: use the online planner (--planner "
                           f"online), or a policy over the classes (aplan solve PRODUCT {flag} -o P.policy), or "
                           f"leave out {flag}")


def _model_file_kind(path: str | os.PathLike) -> str | None:
    name = str(path).lower()
    return next((s for s in MODEL_SUFFIXES if name.endswith(s)), None)


def load_model(argument: str | os.PathLike | Product, technical: bool | None = None, rewards: Rewards = Rewards(),
               discount: float = DISCOUNT, base_part: str | None = None, limits: SizeLimits = SizeLimits(),
               lumped: bool = False, inputs: InputLimits = InputLimits(), habits: Habits | None = None,
               solving: bool = False, parallel: bool = False, deviations: Deviations | None = None) -> Model:
    """MODEL: a ``.pomdpx`` (or ``.pomdpx.gz``) or ``.pomdp`` file (a bare :class:`POMDP`, read within
    ``inputs``: :class:`~planner.validation.InputLimits`), else a PRODUCT
    (its :class:`IntentionModel`, or with ``lumped`` its :class:`LumpedModel`; ``technical``, ``rewards``,
    ``discount``, ``base_part`` and ``limits`` apply to it only: a base part with a model file is a
    :class:`PlannerError`, since the file's intentions are fixed). ``parallel``: the parallel model
    (docs/parallel.md), which is on the classes: it builds the :class:`LumpedModel` as ``lumped`` does."""
    kind = None if isinstance(argument, Product) else _model_file_kind(argument)
    if kind is not None and base_part:
        raise PlannerError(f"{argument}: a base part applies to products only, and this is a model file whose "
                           "intentions are fixed; leave out the base part (--base-part), or give the PRODUCT")
    if kind is not None and habits is not None:
        raise PlannerError(f"{argument}: --habits applies to a PRODUCT; a model file's initial belief and "
                           "transitions are fixed (give the PRODUCT, or leave out --habits)")
    if kind is not None and parallel:
        raise PlannerError(f"{argument}: {parallel_flag(parallel)} applies to a PRODUCT; a model file's transitions "
                           f"are fixed (give the PRODUCT, or leave out {parallel_flag(parallel)})")
    if kind is not None and deviations is not None:
        raise PlannerError(f"{argument}: --switch and --mistakes apply to a PRODUCT; a model file's transitions and "
                           "observations are fixed (give the PRODUCT, or leave them out)")
    if kind is not None and lumped:
        raise PlannerError(f"{argument}: --lumped builds the lumped model of a PRODUCT; a model file is solved "
                           "as it is (write the lumped model with aplan pomdp PRODUCT --lumped -o FILE)")
    if kind in (".pomdpx", ".pomdp") and os.path.isfile(argument):
        _check_model_read(argument, limits.memory)
    if kind in (".pomdpx", ".pomdpx.gz"):
        return read_pomdpx(argument, inputs)
    if kind == ".pomdp":
        return read_cassandra(argument, inputs)
    if lumped or parallel:
        return lumped_model(argument, technical, rewards, discount, base_part, limits, habits, parallel, deviations)
    return decision_model(argument, technical, rewards, discount, base_part, limits, habits, solving, deviations)


# Reading a model file peaks at about 3 bytes of memory per byte of file (bench/README.md, model files).
_READ_BYTES_PER_FILE_BYTE = 3


def _check_model_read(path: str | os.PathLike, max_bytes: int) -> None:
    """Refuse to read a model file whose reading would pass the memory budget (estimated from its size)."""
    size = os.path.getsize(path)
    needed = _READ_BYTES_PER_FILE_BYTE * size
    if needed > max_bytes:
        raise MemoryLimitError(f"reading {path}", needed, max_bytes, f"{_READ_BYTES_PER_FILE_BYTE} x its "
                               f"{gib(size)}", "A model file that large holds more than the "
                               "solvers can use; plan the product with fewer parts or a base part instead.",
                               memory_options(needed))


def check_model_file(model: Model, path: str | os.PathLike, max_bytes: int = FILE_LIMIT,
                     read_budget: int | None = None) -> int:
    """The bytes :func:`save_model` would write to ``path`` (:func:`~planner.decision.io.size.model_file_bytes`),
    after checking them against ``max_bytes`` and the free space of the target's disk: past either,
    :class:`~planner.errors.FileLimitError` with the estimate. With ``read_budget`` (bytes of memory, as
    :func:`load_model`'s ``limits.memory``): a file that :func:`load_model` would refuse to read back within it
    is refused before it is written (:class:`~planner.errors.MemoryLimitError`), so aplan reads what it writes
    with the same options. Cost: O(non-zeros) in numpy."""
    kind = _model_file_kind(path)
    if kind not in (".pomdpx", ".pomdp"):
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")
    pomdp = tables(model)
    needed = model_file_bytes(pomdp, "pomdpx" if kind == ".pomdpx" else "cassandra")
    folder = Path(path).resolve().parent
    free = shutil.disk_usage(folder).free if folder.is_dir() else None
    detail = (f"{pomdp.n_states:,} states, {pomdp.n_actions:,} actions, "
              f"{sum(t.nnz for t in pomdp.transition):,} non-zero transitions")
    hint = "A smaller model (fewer intentions) makes a smaller file."
    if free is not None and needed > free:
        raise FileLimitError(f"{path}", needed, free, detail, hint, budget_name=f"the free space in {folder}")
    if needed > max_bytes:
        raise FileLimitError(f"{path}", needed, max_bytes, detail, hint, [FILE_OPTION, OPTIONS["base_part"]])
    reading = _READ_BYTES_PER_FILE_BYTE * needed
    if read_budget is not None and reading > read_budget:
        raise MemoryLimitError(f"reading {path} back (aplan solve, evaluate)", reading, read_budget,
                               f"{_READ_BYTES_PER_FILE_BYTE} x the {gib(needed)} it would take",
                               "Refused before writing: aplan would not read the file it wrote. A POMDPX file (.pomdpx) "
                               "is smaller than a .pomdp; fewer intentions make both smaller.",
                               memory_options(reading) + [OPTIONS["base_part"]])
    return needed


def save_model(model: Model, path: str | os.PathLike, max_bytes: int = FILE_LIMIT,
               read_budget: int | None = None) -> None:
    """Write POMDPX (``.pomdpx``) or Cassandra (``.pomdp``), by the file name (atomically), after estimating
    its size (:func:`check_model_file`: refused past ``max_bytes``, the free disk space or, with
    ``read_budget``, what :func:`load_model` reads back within that memory)."""
    check_model_file(model, path, max_bytes, read_budget)
    kind = _model_file_kind(path)
    if kind == ".pomdpx":
        write_pomdpx(tables(model), path)
    elif kind == ".pomdp":
        write_cassandra(tables(model), path)
    else:
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")


def solve(model: Model, time_limit: float = SOLVE_TIME_LIMIT, precision: float = SOLVE_PRECISION,
          engine: str = "builtin", progress: Callable[[float, float, float], None] | None = None,
          iterations: int | None = None, keep_on_interrupt: bool = False, max_bytes: int | None = None,
          started: float | None = None, write_seconds: float = 0.0) -> SolveResult:
    """Solve ``model`` offline: ``engine`` ``builtin`` (:class:`PointBasedSolver`, ``progress(seconds,
    lower, upper)`` after each step) or ``sarsop`` (APPL's ``pomdpsol``, when it is on PATH). The solver
    stops at ``time_limit`` seconds (its set-up included), at a gap of ``precision``, or after ``iterations``
    trials (builtin only: a fixed amount of work gives the same policy on any machine). ``started``: the
    ``time.perf_counter()`` value the limit counts from (default: now; the command line passes its own start,
    so the model's building counts too); ``write_seconds``: seconds per policy number kept before the limit
    for writing the policy after it. ``keep_on_interrupt`` (builtin only): Ctrl-C or SIGTERM, from the warm
    start on, stops it with the policy so far (``SolveResult.interrupted``; the warm start, the bounds'
    set-up and every long step check the flag). ``max_bytes`` (builtin only; default the machine's budget):
    the memory the model and the solver may take together, estimated before the solver starts
    (:func:`~planner.decision.solvers.tables.solver_bytes`)."""
    if engine == "sarsop":
        return SarsopSolver(time_limit, precision).solve(tables(model))
    if engine != "builtin":
        raise PlannerError(f"unknown solver engine {engine!r}; use one of {', '.join(SOLVER_ENGINES)}")
    budget = default_memory_budget() if max_bytes is None else max_bytes
    check_solver_memory(tables(model), budget, solver_plan(model), is_flat(model))
    solver = PointBasedSolver(time_limit=time_limit, precision=precision, max_iterations=iterations,
                              keep_on_interrupt=keep_on_interrupt, write_seconds=write_seconds)
    started = solver.clock() if started is None else started  # the time limit counts the bounds' set-up too
    if is_lumped(model):  # relaxed bounds (the state told, or told late) start the upper bound lower
        groups, points = lumped_start_fits(model.pomdp, model.factored.plan, budget)  # optional: left out past it
        solver = replace(solver, warm_start=WarmStart(model, points=points, groups=groups))
    with deferred_interrupts() if keep_on_interrupt else nullcontext(lambda: 0) as pending:
        # the warm start checks ``pending``: an interrupt before the solver had anything stops it at once
        return solver.solve(tables(model), progress, started=started, stopped=pending)


def check_solved(result: SolveResult, precision: float, time_limit: float, what: str = "--time-limit",
                 smaller: str = "--lumped on a PRODUCT, --base-part") -> str | None:
    """Refuse a policy no better than the blind ones the solver starts from (each repeats one action, whatever
    it observes; or the floor ``min R / (1 - gamma)`` when even they did not fit: what a solver cut short by
    its time limit leaves), unless its gap is within ``precision`` anyway: :class:`~planner.errors.SolveTimeError`
    naming the bound, the time and what helps (``what``: the time option; ``smaller``: the options that make
    a smaller model). Returns a warning when the policy beats them by ``precision`` or less, else None."""
    if result.gap <= precision or result.improved(precision):
        return None
    more = (f"Give it more time ({what} {_more_time(time_limit)}), or a smaller model ({smaller})")
    if not result.improved(1e-9 * max(1.0, abs(result.blind_lower))):
        limit = f"of the {time_limit:g} s limit " if time_limit is not None else ""
        raise SolveTimeError(f"no policy written: after {result.seconds:.1f} s {limit}the "
                             f"solver's lower bound at the initial belief is still the blind policies' "
                             f"({result.lower_bound:.6f}; {result.iterations} trials): such a policy repeats one "
                             f"action whatever it observes. {more}")
    return (f"the policy is within {precision:g} of the blind policies at the initial belief (lower bound "
            f"{result.lower_bound:.6f} against {result.blind_lower:.6f}, upper bound {result.upper_bound:.6f}, "
            f"after {result.seconds:.1f} s): it does little better than one action repeated. {more}")


def _more_time(limit: float | None) -> str:
    return f"{max(2 * limit, limit + 30):g}" if limit is not None and math.isfinite(limit) else "larger"


def policy_for(model: Model, policy: str | os.PathLike | None = None, time_limit: float = POLICY_TIME_LIMIT,
               inputs: InputLimits = InputLimits()) -> tuple[AlphaVectorPolicy, SolveResult | None]:
    """The policy in the file ``policy`` (checked against the model; read within ``inputs``), or, without
    one, the built-in solver's after ``time_limit`` seconds, with its result (bounds, time); one no better
    than the blind policies is refused (:func:`check_solved`)."""
    if policy:
        return read_policy(policy, tables(model), inputs), None
    result = solve(model, time_limit, SOLVE_PRECISION)
    warning = check_solved(result, SOLVE_PRECISION, time_limit)
    if warning:
        log.warning("%s", warning)
    return result.policy, result
