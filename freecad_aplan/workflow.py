"""What the workbench's commands do, as plain functions (no Qt): the GUI, batch jobs and tests share them.

From an open document with an APLAN analysis (:mod:`freecad_aplan.intent`):

1. :func:`export_for_detection` writes the document's components into a bundle folder, and a background
   job (:func:`worker_command`: ``batch.py analyze``, i.e. :func:`analyze_bundle`) runs a geometry engine on
   it; :func:`store_detection` keeps the connection and obstruction diagrams in the analysis;
2. :func:`analysis_product` is the product the planner sees: those diagrams plus the designer intent;
   :func:`analysis_base_part` the base part the decision model starts from (the analysis' ``BasePart``);
3. :func:`plan_report` gives the statistics (the figures of ``aplan stats``) and the graph pictures; for a
   product of several workstations (:func:`has_levels`), :func:`level_statistics_report` (a background job)
   the figures per level;
4. :func:`export_analysis_bundle`, :func:`export_decision_model`, :func:`solve_product` (a background job)
   and :func:`simulate_sequence` write the bundle, the POMDPX/``.pomdp`` model, the policy and the belief plot.

Functions that need FreeCAD import it themselves, so the background jobs also run in a plain Python.
Every write is atomic; the user's parts are never touched.
"""
from __future__ import annotations

import json
import os
import re
from dataclasses import replace
from pathlib import Path

from planner import api
from planner.decision.policy import write_policy
from planner.defaults import (
    BLOCKING_DEPTH,
    CONFIDENCE,
    CONTACT_TOLERANCE,
    INTERFERENCE_VOLUME,
    OCCT_FACE_WEIGHT,
    OCCT_PRISM_TRIANGLES,
    OCCT_TIME_LIMIT,
    PRODUCT_FILE,
    SOLVE_PRECISION,
    WORKBENCH_SOLVE_TIME_LIMIT,
)
from planner.errors import PlannerError
from planner.files import building_folder
from planner.product import fold, product_to_dict, save_product

from .dependencies import MESH_ENGINE, installed
from .dependencies import mesh_python as _mesh_python  # the name the commands and tests use
from .designer_edits import add_analysis_direction, edit_analysis_diagrams, mark_not_blocking, unmark_not_blocking
from .diagrams import stored_analysis
from .protocol import BATCH_SCRIPT
from .runner import FreeCADError, find_freecadcmd
from .sessions import base_part_in, level_model, level_of

__all__ = ["require_analysis", "export_for_detection", "check_detection", "detection_copy", "worker_command",
           "analyze_bundle", "detection_settings", "detection_job", "store_detection", "edit_analysis_diagrams",
           "add_analysis_direction", "mark_not_blocking",
           "unmark_not_blocking", "analysis_product", "analysis_base_part", "analysis_diagrams", "plan_report",
           "has_levels", "level_statistics_report",
           "export_analysis_bundle", "export_decision_model",
           "solve_product", "simulate_sequence", "SIMULATE_EPISODE", "analysis_spec", "spec_fields", "BATCH_SCRIPT"]



def require_analysis(document):
    """The document's APLAN analysis; :class:`~freecad_aplan.intent.IntentError` when there is none (or it is
    from a newer format)."""
    from .intent import IntentError, find_analysis, read_intent

    if document is None:
        raise IntentError("no document is open: open an assembly first")
    analysis = find_analysis(document)
    if analysis is None:
        raise IntentError(f"{document.Label}: no APLAN analysis; create one first (APLAN > Create analysis)")
    read_intent(analysis)  # refuses a newer format before anything else happens
    return analysis


def export_for_detection(document, folder: str) -> dict:
    """Export the document's components (with its intent, without stored diagrams) into the bundle folder
    ``folder``; returns the product as written (with ``x-freecad-objects``: component id -> its objects'
    names)."""
    from .export import export_document

    product, _ = export_document(document, folder, document.FileName or document.Label, redetect=True)
    return product


def check_detection(document) -> int:
    """The quick checks of a detection (no tessellation): the document's components (an error such as a document
    without solids) and the analysis' structure over them; raised here, before any panel or job. Returns the
    number of components."""
    from .document import read_components
    from .intent import find_analysis, read_intent

    analysis = find_analysis(document)
    intent = read_intent(analysis) if analysis is not None else None
    result = read_components(document, intent.groups if intent else None, intent.excluded if intent else None,
                             intent.split_solids if intent else False)
    if intent is not None:  # the structure must fit the components before the long export starts
        from .structure import structure_entries

        structure_entries(intent, {c.id: list(c.objects) for c in result.components})
    return len(result.components)


def detection_copy(document, folder: str) -> tuple[str, int]:
    """Check the document (:func:`check_detection`) and save a copy of it into ``folder`` for a background export
    (FreeCADCmd: ``batch.py export``; the document itself is neither saved nor changed). Returns the copy's
    path and the number of components."""
    count = check_detection(document)
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", document.Label).strip("._") or "model"
    path = os.path.join(folder, name + ".FCStd")
    document.saveCopy(path)
    return path, count


def worker_command(action: str, engine: str | None = None) -> list[str]:
    """The program and arguments of a background job running ``batch.py`` (``action``: export, analyze,
    level-stats, solve, session, habits).

    The solver runs in FreeCADCmd; the mesh engine needs trimesh and manifold3d, so it runs in
    :func:`_mesh_python`, else in FreeCADCmd when FreeCAD's Python has them; so does the occt engine, which
    settles the easy pairs on the meshes (else FreeCADCmd alone, OCCT deciding every pair). Raises
    :class:`~freecad_aplan.runner.FreeCADError` saying what to install when none can.
    """
    if action in ("level-stats", "session", "habits") and _mesh_python() is not None:  # the planner alone: no FreeCAD
        return [_mesh_python(), BATCH_SCRIPT]
    if action == "analyze" and engine in ("mesh", "occt"):
        python = _mesh_python()  # the occt engine settles the easy pairs on the meshes too (hybrid)
        if python is not None:
            return [python, BATCH_SCRIPT]
        if engine == "mesh" and not all(installed(m) for m in MESH_ENGINE):
            raise FreeCADError("the mesh engine needs the Python packages trimesh and manifold3d, which FreeCAD's "
                               "Python does not have: install them for FreeCAD (pip), set APLAN_PYTHON to a Python "
                               "that has them, or choose the occt engine (analysis property Engine)")
    return [find_freecadcmd(), BATCH_SCRIPT]


def detection_settings(engine: str, time_limit) -> dict:
    """The :class:`~freecad_aplan.intent.Intent` fields Detect's task panel sets: ``engine`` (its choice, one of
    :data:`~freecad_aplan.intent.ENGINES`, which storing it checks) and ``occt_time_limit``
    (:func:`freecad_aplan.hybrid.checked_time_limit` of the field's text). Raises
    :class:`~planner.errors.PlannerError` naming the field, so that the panel shows it and runs nothing."""
    from .hybrid import checked_time_limit

    try:
        seconds = checked_time_limit(time_limit)
    except PlannerError as exc:
        raise PlannerError(f"Time limit: {exc}; nothing was detected") from None
    return {"engine": engine, "occt_time_limit": seconds}


def detection_job(folder: str, engine: str, intent) -> dict:
    """The ``analyze`` job (:func:`analyze_bundle`) of the bundle ``folder`` with ``engine`` and the analysis'
    tolerances, OCCT bounds and time limit (``intent``: its :class:`~freecad_aplan.intent.Intent`): what Detect
    runs in the background."""
    return {"action": "analyze", "folder": folder, "engine": engine, "contact": intent.contact,
            "interference": intent.interference, "depth": intent.depth,
            "face_weight": intent.occt_face_weight, "prism_triangles": intent.occt_prism_triangles,
            "time_limit": intent.occt_time_limit}


def analyze_bundle(folder: str, engine: str = "mesh", contact: float = CONTACT_TOLERANCE,
                   interference: float = INTERFERENCE_VOLUME, depth: float = BLOCKING_DEPTH,
                   face_weight: int = OCCT_FACE_WEIGHT, prism_triangles: int = OCCT_PRISM_TRIANGLES,
                   time_limit: float = OCCT_TIME_LIMIT, progress=None) -> dict:
    """Run a geometry engine on the bundle ``folder`` and write the result into its ``product.json``
    (``face_weight``, ``prism_triangles``, ``time_limit``: the occt engine's bounds, the analysis'
    ``OcctFaceWeight``, ``OcctPrismTriangles`` and ``OcctTimeLimit``), through the engines ``aplan analyze`` runs
    (:func:`freecad_aplan.plugin.geometry_engines`): with ``occt``, the meshes settle the easy pairs and a
    relation OCCT leaves undecided (its bounds, the time limit) keeps the mesh engine's answer
    (:mod:`freecad_aplan.hybrid`), or counts as blocking where the mesh engine cannot run (FreeCADCmd's Python
    without trimesh and manifold3d).

    ``progress(text)``, when given, is told the exact engine's progress lines as it goes (those ``aplan
    analyze`` prints on standard error: the pairs it decides, then every few seconds the pairs done and
    undecided), then one line per pair OCCT left undecided, with the answer used
    (:func:`freecad_aplan.hybrid.undecided_notes`, the time limit's stop first). Returns the counts (parts,
    contacts, interferences, seconds), ``undecided`` (those lines) and ``summary`` (one line:
    :func:`freecad_aplan.hybrid.undecided_summary`). The interlock rules' and the support contacts' proposals
    are recorded with the diagrams (:func:`planner.api.record_detection_proposals`). Runs in a background job.
    """
    from planner.geometry import Tolerances
    from planner.geometry.bundle import PRODUCT_FILE, analyse_bundle, load_bundle

    from .hybrid import undecided_notes, undecided_summary
    from .plugin import geometry_engines

    product = load_bundle(folder)
    tolerances = Tolerances(contact=contact, interference=interference, depth=depth, face_weight=face_weight,
                            prism_triangles=prism_triangles, time_limit=time_limit)
    # The interlock and support-contact proposals, while the meshes are here: the interlocks panel lists them.
    _, report = analyse_bundle(product, Path(folder) / PRODUCT_FILE, engine, tolerances,
                               then=api.record_detection_proposals,
                               engines=geometry_engines(progress))
    notes = undecided_notes(report.tolerances)
    for note in notes if progress is not None else ():
        progress(note)
    return {"parts": len(report.parts), "contacts": len(report.contacts),
            "interferences": len(report.interferences), "seconds": round(report.seconds, 3), "undecided": notes,
            "summary": undecided_summary(report.tolerances)}


def store_detection(analysis, folder: str):
    """Keep the diagrams of the analysed bundle ``folder`` in the analysis (one undoable step)."""
    from planner.geometry.bundle import load_bundle
    from .intent import update_intent

    raw = json.loads((Path(folder) / PRODUCT_FILE).read_text(encoding="utf-8"))
    data = product_to_dict(load_bundle(folder))
    diagrams = {"parts": [p["id"] for p in data["parts"]], "objects": raw.get("x-freecad-objects", {}),
                # labels and volumes: the planner's fastener proposals look at them (freecad_aplan.structure)
                "labels": {p["id"]: p["label"] for p in data["parts"] if p.get("label")},
                "volumes": {p["id"]: p["volume"] for p in data["parts"] if p.get("volume") is not None},
                "contacts": data["contacts"], "obstructions": data["obstructions"],
                "analysis": data.get("geometry", {}).get("analysis", {})}
    return update_intent(analysis, "detect contacts and obstructions", diagrams=diagrams)


def analysis_product(analysis, name: str = ""):
    """The product the planner sees in ``analysis`` (:func:`freecad_aplan.analysis.analysis_product`); imported
    here, not at the top, because the analysis reads FreeCAD objects and the background jobs import this module
    in a plain Python."""
    from .analysis import analysis_product as product_of

    return product_of(analysis, name)


def analysis_base_part(analysis) -> str | None:
    """The analysis' base part (:func:`freecad_aplan.analysis.analysis_base_part`)."""
    from .analysis import analysis_base_part as base_part_of

    return base_part_of(analysis)


def analysis_spec(analysis, technical: bool | None = None):
    """The decision model the workbench's commands build for ``analysis``: a
    :class:`~planner.api.specs.ModelSpec` with its base part (:func:`analysis_base_part`) and the paper's
    rewards and discount, built once per command and passed to :func:`export_decision_model`,
    :func:`simulate_sequence` and the solve job (whose JSON carries its fields: :func:`spec_fields`)."""
    return api.ModelSpec(technical=technical, base_part=analysis_base_part(analysis))


def spec_fields(spec) -> dict:
    """The fields of ``spec`` the workbench sets (technical constraints, base part), as a background job's
    JSON carries them to :func:`solve_product`."""
    return {"technical": spec.technical, "base_part": spec.base_part}


def _spec(spec, technical: bool | None, base_part: str | None):
    """``spec``, or the :class:`~planner.api.specs.ModelSpec` of ``technical`` and ``base_part`` (callers that
    pass the two fields, as tests and scripts do)."""
    return spec if spec is not None else api.ModelSpec(technical=technical, base_part=base_part)


def plan_report(product, folder: str | None = None, technical: bool | None = None, base_part: str | None = None):
    """The plan of ``product``, its statistics (``aplan stats``'s figures; with ``base_part``, the sequences that
    start from it and their intentions) and, with ``folder``, the pictures of its AND/OR, state and intention
    graphs (:func:`planner.assembly.figures.draw_plan`)."""
    plan, statistics = api.plan_statistics_of(product, technical, base_part)
    images = {}
    if folder is not None:
        from planner.assembly.figures import draw_plan

        images = draw_plan(plan, folder)
    return plan, statistics, images


def has_levels(product) -> bool:
    """True when ``product`` is planned as several workstations (its ``subassemblies``, with the designer's mode)."""
    return len(api.levels_of(product)) > 1


def level_statistics_report(product: str, technical: bool | None = None, progress=None) -> dict:
    """The per-level figures of the product file ``product`` (a background job): those ``aplan stats --json``
    prints for a product of several workstations (:func:`planner.api.level_report`), plus ``fasteners``: the
    folded groups (id, parts, hosts, tool). ``progress(text)`` is told each level as it starts."""
    loaded = api.resolve_product(product)
    report = api.level_report(loaded, technical, progress=progress)
    report["fasteners"] = [{"id": g.id, "parts": list(g.parts), "hosts": sorted(g.hosts), "tool": g.tool}
                           for g in fold(loaded).groups]
    report["name"] = loaded.name
    return report


def export_analysis_bundle(document, analysis, bundle: str) -> None:
    """Write the bundle folder ``bundle`` (meshes, B-reps, product.json with the stored diagrams and intent);
    it appears only when everything succeeded, replacing an existing one."""
    from planner.geometry.bundle import PRODUCT_FILE, load_bundle
    product = analysis_product(analysis)
    with building_folder(os.path.abspath(bundle)) as work:  # renamed into place when everything succeeded
        export_for_detection(document, str(work))
        exported = load_bundle(work)
        if sorted(exported.part_ids) != sorted(product.part_ids):
            raise PlannerError(f"the components {sorted(exported.part_ids)} differ from those of the last detection "
                               f"{sorted(product.part_ids)}; run the detection again")
        save_product(replace(exported, contacts=product.contacts, obstructions=product.obstructions,
                             geometry={**exported.geometry, "analysis": analysis_diagrams(analysis)}),
                     os.path.join(work, PRODUCT_FILE))


def analysis_diagrams(analysis) -> dict:
    """The ``geometry.analysis`` of a product from the stored diagrams: the engine summary of the last
    detection (engine, tolerances, interferences, warnings), where the diagrams came from and their edits."""
    from .intent import read_intent

    return stored_analysis(read_intent(analysis).diagrams)


def export_decision_model(product, path: str, technical: bool | None = None, base_part: str | None = None,
                          level: str | None = None, spec=None) -> dict:
    """Write the POMDP of ``product`` (Alg. 3; with ``base_part``, over the sequences that start from it, or
    the base part of ``spec``: :func:`analysis_spec`; of workstation ``level`` for a product of several;
    lumped where the flat model does not fit: :func:`freecad_aplan.sessions.level_model`) as POMDPX or
    ``.pomdp`` (by the file name); returns its sizes and ``model`` (flat or lumped)."""
    spec = _spec(spec, technical, base_part)
    model, choice = level_model(product, level, spec.technical, spec.base_part)
    api.save_model(model, path)
    return {"states": model.pomdp.n_states, "actions": model.pomdp.n_actions,
            "observations": model.pomdp.n_observations, "model": choice.kind}


def solve_product(product: str, output: str, time_limit: float = WORKBENCH_SOLVE_TIME_LIMIT,
                  precision: float = SOLVE_PRECISION, technical: bool | None = None, progress=None,
                  base_part: str | None = None, level: str | None = None) -> dict:
    """Solve the decision model of the product file ``product`` (with ``base_part``: over the sequences that
    start from it; ``level`` as :func:`export_decision_model`) and write the policy to ``output`` (a
    background job)."""
    model, choice = level_model(product, level, technical, base_part)
    result = api.solve(model, time_limit, precision, progress=progress)
    # A policy no better than the blind ones is refused (a PlannerError naming the bound and what helps);
    # one barely better is written with the warning.
    warning = api.check_solved(result, precision, time_limit, what="the solve time limit (SolveTimeLimit)")
    write_policy(result.policy, output, model.name)
    return {"lower_bound": result.lower_bound, "upper_bound": result.upper_bound,
            "alpha_vectors": int(result.policy.alphas.shape[0]), "seconds": round(result.seconds, 2),
            "model": choice.kind,
            **({"warning": warning} if warning else {})}


#: The episode Simulate plays by default: the first full sequence, the operator taking turns with the robot as in
#: the paper's experiment (the command line's ``aplan simulate PRODUCT --operator turns``).
SIMULATE_EPISODE = api.EpisodeChoice(operator="turns", what="sequence")


def simulate_sequence(product, policy_path: str, stem: str, choice=SIMULATE_EPISODE, technical: bool | None = None,
                      base_part: str | None = None, level: str | None = None, spec=None) -> dict:
    """Play the operator through the one full sequence ``choice`` lists (an :class:`~planner.api.specs.EpisodeChoice`
    built from the command's input; default :data:`SIMULATE_EPISODE`) against the policy file ``policy_path``, and
    write the belief plot ``stem.png``/``stem.svg``. The policy decides as ``aplan simulate --policy`` makes it
    (:func:`planner.api.decision_maker`): one over intentions on the flat model, one over the lumped model's
    classes (what Solve writes where the flat model does not fit) on the factored model, whose sequences are
    numbered by rank from 0 and whose plot is summed over assembly states. ``base_part`` (or ``spec``,
    :func:`analysis_spec`): the model's, as the policy was solved for; ``level``: that workstation's model.
    Returns ``sequence`` (the intention number, or the rank), ``model`` (``flat`` or ``lumped``), ``operations``,
    the ``steps`` (action, observation, belief on the truth), ``confident_after`` and the ``plots``."""
    from planner.decision.belief_plot import episode_trace, path_trace, plot_beliefs
    from planner.decision.models import is_flat

    if choice.every or choice.random is not None or len(choice.sequences) > 1:
        raise PlannerError("Simulate plays one full sequence: give one sequence number, or none for the first")
    spec = _spec(spec, technical, base_part)
    level_product = level_of(product, level)
    base = base_part_in(level_product, spec.base_part) if level is not None else spec.base_part
    model, policy, _ = api.decision_maker(level_product, replace(spec, base_part=base),
                                          api.PlannerChoice("offline", policy_path))
    episode, = api.simulate(model, policy, choice)
    flat = is_flat(model)
    operations = model.describe_operations(episode.start if flat else episode.path)
    sequence = episode.start if flat else (choice.sequences or (0,))[0]
    title = f"sequence {sequence}: " + " ; ".join(operations)
    trace = episode_trace(model, episode, title) if flat else path_trace(model, episode, title)
    written = plot_beliefs([trace], stem, model.plan.product.name or model.name)
    return {"sequence": sequence, "model": "flat" if flat else "lumped", "operations": operations,
            "steps": [(model.actions[s.action], str(model.observations[s.observation]), round(s.p_true, 3))
                      for s in episode.steps],
            "confident_after": episode.first_confident(CONFIDENCE), "plots": written}
