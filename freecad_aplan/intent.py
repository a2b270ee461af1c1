"""The designer's intent, stored in the FreeCAD document as an "APLAN analysis" object.

An *analysis* is an ``App::DocumentObjectGroupPython`` whose properties hold what the designer decided on
top of the geometry (everything is saved in the ``.FCStd`` and restored on reopen):

- components: ``Groups`` (``NAME=Object1,Object2``: several objects form one component) and ``Excluded``
  (objects left out, e.g. fasteners), by internal object name, so renaming a label does not break them;
  ``SplitSolids`` (one part per solid of an object holding several);
- ``TechnicalConstraints``, ``Tools`` and ``OperationTags``: one product-format JSON object per entry
  (``docs/product-format.md``: ``{"parts": [...], "requires": r, "active": b}``,
  ``{"inputs": [[...], [...]], "unfavorable": b, "robot": b, "tool": t}``), over component ids;
- ``BasePart``: the part every assembly sequence starts from (paper Sec. V) for the decision model: empty for
  none, ``auto`` for the most connected part, or a component id (an analysis saved before it existed gets
  the property, empty, when it is read or restored);
- ``Engine`` and the tolerances of the geometry engines (``ContactTolerance``, ``InterferenceVolume``,
  ``DepthTolerance``), and the exact engine's bounds (``OcctFaceWeight``, ``OcctPrismTriangles``,
  ``OcctTimeLimit``: the CLI's ``--occt-face-weight``, ``--occt-prism-triangles`` and ``--time-limit``,
  :class:`planner.geometry.Tolerances`; an analysis saved before them gets them with their defaults; Detect's
  task panel sets the engine and the time limit);
- ``Diagrams``: the connection and obstruction diagrams the last detection found (product-format JSON);
- ``DesignerDirections`` (``X,Y,Z`` per entry) and ``NotBlocking`` (one JSON mark per entry): the designer's
  motion directions, tested like the axes, and relations marked not blocking, applied after every detection
  (the product's ``geometry.designer``, :mod:`planner.product.designer`);
- ``Fasteners``: the designer's fastener tags, one JSON object per group, by internal object name
  (``{"id": g, "objects": [...], "hosts": [...], "tool"?: t}``: the objects are installed together, joining the
  hosts' components; :mod:`freecad_aplan.structure`);
- ``Interlocks``: the designer's decisions on the interlock proposals of the last detection (one JSON object
  each: ``{"parts": [a, b], "rule": r, "text": t, "decision": "accepted" or "rejected"}``,
  :mod:`freecad_aplan.interlocks`): an accepted one is written into the designer data above (directions,
  marks, diagrams, groups), a rejected one makes the planner refuse the pair (the product's
  ``geometry.designer.refused_interlocks``); and on the support contacts it proposes (rule ``support``: an
  accepted one is a contact in the diagrams, a rejected one only not added);
- ``Subassemblies``: the designer's subassembly tree, one product-format JSON object per subassembly over
  component ids (``{"id": s, "parts": [...], "label"?: l}``); empty: the document's own structure
  (``App::Part`` containers and groups) applies;
- ``FormatVersion``: an analysis written by a newer APLAN is refused (:class:`IntentError`), never guessed.

The functions here are shared by batch mode (:mod:`freecad_aplan.export`) and the GUI commands. Every
change is one undoable transaction; the user's parts are never touched.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field, fields, replace

import FreeCAD

from planner.defaults import (BLOCKING_DEPTH, CONTACT_TOLERANCE, INTERFERENCE_VOLUME, OCCT_FACE_WEIGHT,
                              OCCT_PRISM_TRIANGLES, OCCT_TIME_LIMIT)
from planner.errors import PlannerError

from .document import DocumentError

__all__ = ["FORMAT_VERSION", "ENGINES", "BASE_PART_AUTO", "Intent", "IntentError", "AnalysisProxy", "create_analysis",
           "find_analysis", "read_intent", "update_intent", "product_intent", "is_analysis", "designer_record"]

FORMAT_VERSION = 1
ENGINES = ("mesh", "occt")
BASE_PART_AUTO = "auto"  # the most connected part (planner.api.base_part_of)
_TYPE = "AplanAnalysis"


class IntentError(DocumentError):
    """The designer intent of a document cannot be read or changed (the message says where and how to fix)."""


@dataclass(frozen=True)
class Intent:
    """The designer intent held by one analysis (plain data; see the module docstring for the meaning)."""

    groups: dict[str, list[str]] = field(default_factory=dict)
    excluded: list[str] = field(default_factory=list)
    split_solids: bool = False
    technical_constraints: list[dict] = field(default_factory=list)
    tools: list[str] = field(default_factory=list)
    operations: list[dict] = field(default_factory=list)
    base_part: str = ""
    engine: str = "mesh"
    contact: float = CONTACT_TOLERANCE
    interference: float = INTERFERENCE_VOLUME
    depth: float = BLOCKING_DEPTH
    occt_face_weight: int = OCCT_FACE_WEIGHT
    occt_prism_triangles: int = OCCT_PRISM_TRIANGLES
    occt_time_limit: float = OCCT_TIME_LIMIT
    diagrams: dict = field(default_factory=dict)
    directions: list[list[float]] = field(default_factory=list)
    not_blocking: list[dict] = field(default_factory=list)
    fasteners: list[dict] = field(default_factory=list)
    subassemblies: list[dict] = field(default_factory=list)
    interlocks: list[dict] = field(default_factory=list)


# property name, FreeCAD type, property group, tooltip; in the order of Intent's fields
_PROPERTIES = (
    ("Groups", "App::PropertyStringList", "Components", "NAME=Object1,Object2: these objects form one component"),
    ("Excluded", "App::PropertyStringList", "Components",
     "objects left out of the product (internal names, labels or shell-style patterns such as wood_screw*)"),
    ("SplitSolids", "App::PropertyBool", "Components", "one part per solid of an object holding several solids"),
    ("TechnicalConstraints", "App::PropertyStringList", "Designer intent",
     'one JSON object per constraint: {"parts": [...], "requires": "part", "active": true}'),
    ("Tools", "App::PropertyStringList", "Designer intent", "tools the operator picks up (ids)"),
    ("OperationTags", "App::PropertyStringList", "Designer intent",
     'one JSON object per operation: {"inputs": [[...], [...]], "unfavorable": b, "robot": b, "tool": t}'),
    ("BasePart", "App::PropertyString", "Designer intent",
     ("the part every assembly sequence starts from (paper Sec. V): a component id, 'auto' for the most "
      "connected part, empty for none")),
    ("Engine", "App::PropertyEnumeration", "Detection", "geometry engine for contacts and obstructions"),
    ("ContactTolerance", "App::PropertyFloat", "Detection", "surfaces closer than this touch (mm)"),
    ("InterferenceVolume", "App::PropertyFloat", "Detection", "overlaps above this volume are reported (mm^3)"),
    ("DepthTolerance", "App::PropertyFloat", "Detection", "overlaps shallower than this do not block (mm)"),
    ("OcctFaceWeight", "App::PropertyInteger", "Detection",
     "occt engine: no OCCT call on a part whose heaviest face weighs more (B-spline poles x (degree + 1)^2): its "
     "pairs keep the mesh engine's answer, and the export gives it a ring hull or its closest mesh"),
    ("OcctPrismTriangles", "App::PropertyInteger", "Detection",
     "occt engine: a face swept as triangles has at most this many, else that sweep's pairs keep the mesh "
     "engine's answer"),
    ("OcctTimeLimit", "App::PropertyFloat", "Detection",
     "CPU seconds the exact engine (and OCCT on the parts without a good mesh) spends on all its pairs; the pairs "
     "left then keep the mesh engine's answer and are reported (set in Detect's task panel)"),
    ("Diagrams", "App::PropertyString", "Detection", "connection and obstruction diagrams found by the last detection"),
    ("DesignerDirections", "App::PropertyStringList", "Detection",
     "motion directions X,Y,Z tested like the axes at every detection (added in the diagrams panel)"),
    ("NotBlocking", "App::PropertyStringList", "Detection",
     'relations the designer marked not blocking, one JSON object each: {"blocked": x, "blocking": y, '
     '"direction": "+X" or [x, y, z]}; applied after every detection'),
    ("Fasteners", "App::PropertyStringList", "Structure",
     'one JSON object per fastener group: {"id": g, "objects": [...], "hosts": [...], "tool": t} (internal names)'),
    ("Subassemblies", "App::PropertyStringList", "Structure",
     'one JSON object per subassembly: {"id": s, "parts": [component or subassembly ids]}; empty: the document\'s own'),
    ("Interlocks", "App::PropertyStringList", "Detection",
     'the designer\'s decisions on the interlock proposals, one JSON object each: {"parts": [a, b], "rule": r, '
     '"text": t, "decision": "accepted" or "rejected"}, and "level" for a support contact of a workstation '
     '(made in the interlocks panel)'),
)


class AnalysisProxy:
    """Python proxy of an APLAN analysis: adds the properties; stores nothing itself."""

    def __init__(self, obj):
        obj.Proxy = self
        self.Type = _TYPE
        obj.addProperty("App::PropertyInteger", "FormatVersion", "Base", "format version of this analysis")
        obj.FormatVersion = FORMAT_VERSION
        obj.setEditorMode("FormatVersion", 1)  # read-only in the property editor
        for name, kind, group, tip in _PROPERTIES:
            obj.addProperty(kind, name, group, tip)
        obj.Engine = list(ENGINES)
        defaults = Intent()
        obj.ContactTolerance, obj.InterferenceVolume, obj.DepthTolerance = (
            defaults.contact, defaults.interference, defaults.depth)
        obj.OcctFaceWeight, obj.OcctPrismTriangles = defaults.occt_face_weight, defaults.occt_prism_triangles
        obj.OcctTimeLimit = defaults.occt_time_limit
        obj.setEditorMode("Diagrams", 2)  # hidden: edited through the task panel

    def execute(self, obj):
        pass

    def onDocumentRestored(self, obj):
        self.Type = _TYPE
        _add_missing_properties(obj)

    def __getstate__(self):  # FreeCAD 0.20 serialises the proxy through these
        return {"Type": _TYPE}

    def __setstate__(self, state):
        self.Type = _TYPE

    dumps, loads = __getstate__, __setstate__  # FreeCAD 0.21 and later


#: Defaults of properties added since an analysis may have been saved (not 0); pairs, so no module state changes.
_ADDED_DEFAULTS = (("OcctFaceWeight", OCCT_FACE_WEIGHT), ("OcctPrismTriangles", OCCT_PRISM_TRIANGLES),
                   ("OcctTimeLimit", OCCT_TIME_LIMIT))


def _add_missing_properties(obj) -> None:
    """Properties added since the analysis was saved (``BasePart``, the OCCT bounds and time limit), with their
    defaults: an older analysis reads as it did."""
    for name, kind, group, tip in _PROPERTIES:
        if name not in obj.PropertiesList:
            obj.addProperty(kind, name, group, tip)
            if name in dict(_ADDED_DEFAULTS):
                setattr(obj, name, dict(_ADDED_DEFAULTS)[name])


def is_analysis(obj) -> bool:
    """True for an APLAN analysis (also when this addon's proxy class could not be loaded)."""
    proxy = getattr(obj, "Proxy", None)
    return getattr(proxy, "Type", None) == _TYPE or (
        obj.TypeId == "App::DocumentObjectGroupPython" and "FormatVersion" in obj.PropertiesList
        and "OperationTags" in obj.PropertiesList)


def find_analysis(document):
    """The document's APLAN analysis, or None (a document holds at most one)."""
    return next((o for o in document.Objects if is_analysis(o)), None)


def _in_transaction(document, description: str, change):
    document.openTransaction(description)
    try:
        result = change()
    except BaseException:
        document.abortTransaction()
        raise
    document.commitTransaction()
    return result


def create_analysis(document, label: str = "APLAN analysis"):
    """Add an empty APLAN analysis to ``document`` (one undoable step) and return it.

    Raises :class:`IntentError` when the document already has one.
    """
    existing = find_analysis(document)
    if existing is not None:
        raise IntentError(f"{_where(document)}: already holds the APLAN analysis {existing.Label!r}; "
                          "edit that one (a document holds one analysis)")

    def add():
        obj = document.addObject("App::DocumentObjectGroupPython", "AplanAnalysis")
        AnalysisProxy(obj)
        obj.Label = label
        if FreeCAD.GuiUp:
            from .viewproviders import AnalysisViewProvider

            AnalysisViewProvider(obj.ViewObject)
        return obj

    return _in_transaction(document, "Create APLAN analysis", add)


def _where(document) -> str:
    return document.FileName or document.Label


def _check_version(analysis) -> None:
    version = getattr(analysis, "FormatVersion", None)
    if not isinstance(version, int):
        raise IntentError(f"{_where(analysis.Document)}: {analysis.Label!r} has no FormatVersion; it is not an "
                          "APLAN analysis")
    if version > FORMAT_VERSION:
        raise IntentError(f"{_where(analysis.Document)}: the APLAN analysis {analysis.Label!r} has format version "
                          f"{version}, written by a newer APLAN (this one reads version {FORMAT_VERSION}); "
                          "update the APLAN workbench to use it")


def _json_entries(analysis, prop: str) -> list[dict]:
    entries = []
    for k, text in enumerate(getattr(analysis, prop)):
        try:
            value = json.loads(text)
        except json.JSONDecodeError as exc:
            raise IntentError(f"{analysis.Label}.{prop}[{k}]: not valid JSON ({exc.msg}): {text!r}") from None
        if not isinstance(value, dict):
            raise IntentError(f"{analysis.Label}.{prop}[{k}]: expected a JSON object, got {text!r}")
        entries.append(value)
    return entries


def _bound(analysis, prop: str) -> int:
    """The OCCT bound ``prop`` of ``analysis`` (its default when the analysis predates it); IntentError below 1."""
    value = int(getattr(analysis, prop, dict(_ADDED_DEFAULTS)[prop]))
    if value < 1:
        raise IntentError(f"{analysis.Label}.{prop} must be a whole number >= 1, got {value} (default "
                          f"{dict(_ADDED_DEFAULTS)[prop]:,}); set it in the analysis' properties (Detection)")
    return value


def read_intent(analysis) -> Intent:
    """The designer intent held by ``analysis``; raises :class:`IntentError` for a newer format or bad entries."""
    _check_version(analysis)
    groups: dict[str, list[str]] = {}
    for k, text in enumerate(analysis.Groups):
        name, sep, members = text.partition("=")
        if not sep or not name.strip() or not members.strip():
            raise IntentError(f"{analysis.Label}.Groups[{k}]: expected NAME=Object1,Object2, got {text!r}")
        groups[name.strip()] = [m.strip() for m in members.split(",") if m.strip()]
    try:
        diagrams = json.loads(analysis.Diagrams) if analysis.Diagrams else {}
    except json.JSONDecodeError as exc:
        raise IntentError(f"{analysis.Label}.Diagrams: not valid JSON ({exc.msg}); run the detection again") from None
    directions = []
    for k, text in enumerate(getattr(analysis, "DesignerDirections", [])):
        try:
            directions.append([float(c) for c in text.split(",")])
        except ValueError:
            raise IntentError(f"{analysis.Label}.DesignerDirections[{k}]: expected X,Y,Z, got {text!r}") from None
    not_blocking = _json_entries(analysis, "NotBlocking") if "NotBlocking" in analysis.PropertiesList else []
    return Intent(groups=groups, excluded=list(analysis.Excluded), split_solids=bool(analysis.SplitSolids),
                  technical_constraints=_json_entries(analysis, "TechnicalConstraints"), tools=list(analysis.Tools),
                  operations=_json_entries(analysis, "OperationTags"),
                  base_part=str(getattr(analysis, "BasePart", "")).strip(), engine=str(analysis.Engine),
                  contact=float(analysis.ContactTolerance), interference=float(analysis.InterferenceVolume),
                  depth=float(analysis.DepthTolerance),
                  occt_face_weight=_bound(analysis, "OcctFaceWeight"),
                  occt_prism_triangles=_bound(analysis, "OcctPrismTriangles"),
                  occt_time_limit=float(getattr(analysis, "OcctTimeLimit", OCCT_TIME_LIMIT)),
                  diagrams=diagrams, directions=directions,
                  not_blocking=not_blocking,
                  fasteners=_json_entries(analysis, "Fasteners") if "Fasteners" in analysis.PropertiesList else [],
                  subassemblies=(_json_entries(analysis, "Subassemblies")
                                 if "Subassemblies" in analysis.PropertiesList else []),
                  interlocks=_json_entries(analysis, "Interlocks") if "Interlocks" in analysis.PropertiesList else [])


def _write(analysis, intent: Intent) -> None:
    for name in intent.groups:
        if "=" in name or "," in name or not name.strip():
            raise IntentError(f"component name {name!r}: use a non-empty name without '=' or ','")
    if intent.engine not in ENGINES:
        raise IntentError(f"unknown engine {intent.engine!r}; use one of {', '.join(ENGINES)}")
    for name in ("contact", "interference", "depth"):
        if not getattr(intent, name) >= 0:
            raise IntentError(f"tolerance {name} must be >= 0, got {getattr(intent, name)!r}")
    for name, prop in (("occt_face_weight", "OcctFaceWeight"), ("occt_prism_triangles", "OcctPrismTriangles")):
        value = getattr(intent, name)
        if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
            raise IntentError(f"{analysis.Label}.{prop} must be a whole number >= 1, got {value!r}")
    from .hybrid import checked_time_limit  # the task panel's check, and the command line's

    try:
        checked_time_limit(intent.occt_time_limit)
    except PlannerError as exc:
        raise IntentError(f"{analysis.Label}.OcctTimeLimit: {exc}") from None
    parts = intent.diagrams.get("parts") or []
    base = intent.base_part.strip()
    if base not in ("", BASE_PART_AUTO) and parts and base not in parts:
        raise IntentError(f"{analysis.Label}.BasePart: {base!r} is not a component; use one of {', '.join(parts)}, "
                          f"'{BASE_PART_AUTO}' (the most connected part) or leave it empty (no base part)")
    _add_missing_properties(analysis)
    values = {
        "Groups": [f"{n}={','.join(m)}" for n, m in intent.groups.items()],
        "Excluded": list(intent.excluded),
        "SplitSolids": bool(intent.split_solids),
        "TechnicalConstraints": [json.dumps(c, sort_keys=True) for c in intent.technical_constraints],
        "Tools": list(intent.tools),
        "OperationTags": [json.dumps(t, sort_keys=True) for t in intent.operations],
        "BasePart": base,
        "Engine": intent.engine,
        "ContactTolerance": float(intent.contact),
        "InterferenceVolume": float(intent.interference),
        "DepthTolerance": float(intent.depth),
        "OcctFaceWeight": int(intent.occt_face_weight),
        "OcctPrismTriangles": int(intent.occt_prism_triangles),
        "OcctTimeLimit": float(intent.occt_time_limit),
        "Diagrams": json.dumps(intent.diagrams, sort_keys=True) if intent.diagrams else "",
        "DesignerDirections": [",".join(f"{c:.9g}" for c in v) for v in intent.directions],
        "NotBlocking": [json.dumps(m, sort_keys=True) for m in intent.not_blocking],
        "Fasteners": [json.dumps(g, sort_keys=True) for g in intent.fasteners],
        "Subassemblies": [json.dumps(g, sort_keys=True) for g in intent.subassemblies],
        "Interlocks": [json.dumps(d, sort_keys=True) for d in intent.interlocks],
    }
    for name, value in values.items():
        if getattr(analysis, name) != value:  # unchanged properties stay untouched (no needless undo steps)
            setattr(analysis, name, value)


def update_intent(analysis, description: str, **changes) -> Intent:
    """Replace fields of the analysis' intent (names of :class:`Intent`) in one undoable transaction.

    Example: ``update_intent(a, "Exclude screw", excluded=["Screw"])``. Nothing changes when the analysis is
    from a newer format or a value is invalid (:class:`IntentError`). Returns the new intent.
    """
    known = {f.name for f in fields(Intent)}
    unknown = sorted(set(changes) - known)
    if unknown:
        raise TypeError(f"update_intent: unknown fields {unknown}; known: {sorted(known)}")
    intent = replace(read_intent(analysis), **changes)
    _in_transaction(analysis.Document, f"APLAN: {description}", lambda: _write(analysis, intent))
    return intent


def designer_record(intent: Intent) -> dict:
    """The product's ``geometry.designer`` (:mod:`planner.product.designer`): the designer's directions and
    not-blocking marks the analysis holds, and the interlock proposals the designer rejected
    (``refused_interlocks``, :mod:`planner.assembly.interlock_proposals`); empty when it holds none."""
    # A rejected support contact is only not added (freecad_aplan.interlocks): no refusal for the planner (one
    # of a workstation's is left out of the candidates instead: freecad_aplan.analysis.level_candidates).
    refused = [{k: d[k] for k in ("parts", "rule", "text") if k in d} for d in intent.interlocks
               if d.get("decision") == "rejected" and d.get("rule") != "support"]
    return {**({"directions": [list(v) for v in intent.directions]} if intent.directions else {}),
            **({"not_blocking": [dict(m) for m in intent.not_blocking]} if intent.not_blocking else {}),
            **({"refused_interlocks": refused} if refused else {})}


def product_intent(intent: Intent) -> dict:
    """The product-file keys (``technical_constraints``, ``tools``, ``operations``) the intent adds."""
    out: dict = {}
    if intent.technical_constraints:
        out["technical_constraints"] = [dict(c) for c in intent.technical_constraints]
    if intent.tools:
        out["tools"] = [{"id": t} for t in intent.tools]
    if intent.operations:
        out["operations"] = [dict(t) for t in intent.operations]
    return out
