"""The designer's structure of a product in the analysis: fastener tags and the subassembly tree.

Plain functions over an APLAN analysis (:mod:`freecad_aplan.intent`), shared by the workbench's panels
(:mod:`freecad_aplan.gui.structure`), the export and the tests (no Qt; FreeCAD only through the analysis).

- *Fastener tags* (``Fasteners``): one group per entry, ``{"id", "objects", "hosts", "tool"?}``, by internal
  object name, like ``Groups`` and ``Excluded``: the objects (screws, nuts, ...) are installed together by
  the operation that joins the hosts' components, with the tool. Tagging needs the detected diagrams: the
  hosts are the components the fasteners touch that are no fasteners, and a group that joins fewer than two
  is refused, naming its parts. The planner's proposals (the call behind ``aplan fasteners``) can be accepted
  as they are.
- *Subassemblies* (``Subassemblies``): product-format entries over component ids; empty means the document's
  own structure (``App::Part`` containers and groups, :func:`~freecad_aplan.containers.document_subassemblies`).
  Every change is checked by the planner first (a cycle, a member in two subassemblies, an unknown member, a
  subassembly that cannot be built on its own: the message names the parts) and stored as one undo step.
- :func:`structure_entries` turns both into the product file's ``fasteners`` and ``subassemblies`` sections
  (``source: "designer"``), so ``--fasteners tagged`` and ``--subassemblies designer`` (the defaults) use them.
"""
from __future__ import annotations

from dataclasses import replace

from planner.defaults import MAX_COMPONENTS
from planner.errors import PlannerError, ProductFormatError

from .analysis import (
    _owner_of,
    analysis_product,
    component_objects,
    fastener_entries,
    structure_entries,
    subassembly_entries,
)
from .intent import Intent, IntentError, read_intent, update_intent

__all__ = ["component_objects", "fastener_entries", "subassembly_entries", "structure_entries", "tag_fasteners",
           "untag_fasteners", "fastener_report", "accept_fastener_proposals", "proposed_structure",
           "document_structure", "current_structure", "check_structure", "set_subassemblies", "move_member",
           "add_subassembly", "delete_subassembly"]


def _detected(analysis) -> Intent:
    intent = read_intent(analysis)
    if not intent.diagrams.get("parts"):
        raise IntentError(f"{analysis.Label}: no contacts and obstructions yet; run APLAN > Detect contacts and "
                          "obstructions first (fastener hosts and subassemblies are checked on them)")
    return intent


def _hosts(intent: Intent, parts: set[str], others: set[str]) -> list[str]:
    """The components the fastener components ``parts`` touch that are no fasteners (``others``: those of
    other groups), in component order."""
    touching = {b for a, b in intent.diagrams.get("contacts", []) if a in parts} | {
        a for a, b in intent.diagrams.get("contacts", []) if b in parts}
    return [p for p in intent.diagrams["parts"] if p in touching and p not in parts and p not in others]


def _group_id(hosts: list[str], taken: set[str]) -> str:
    base = "fasteners_" + "+".join(hosts)
    name, k = base, 1
    while name in taken:
        k += 1
        name = f"{base}_{k}"
    return name


def tag_fasteners(analysis, names: list[str], tool: str | None = None) -> Intent:
    """Tag the objects ``names`` (internal names) as one fastener group, installed with ``tool`` (one undo step).

    Objects already in a group move to the new one. The hosts are the components the group's fasteners touch
    that are no fasteners. Raises :class:`IntentError` (nothing changes) for an unknown object, an object that
    is no component of its own, or a group that joins nothing or only one component (named, with its parts).
    Cost: O(contacts + tagged objects).
    """
    intent = _detected(analysis)
    document = analysis.Document
    unknown = [n for n in names if document.getObject(n) is None]
    if unknown or not names:
        raise IntentError(f"cannot tag {', '.join(map(repr, unknown)) or 'nothing'} as fasteners: "
                          f"{'no such object in ' + document.Label if unknown else 'select the fasteners first'}")
    objects = component_objects(intent)
    owner = _owner_of(objects)
    parts = []
    for name in names:
        component = owner.get(name)
        if component is None:
            raise IntentError(f"cannot tag {document.getObject(name).Label!r} as a fastener: it is not a component "
                              "of the last detection (excluded, or added since); include it and detect again")
        if not set(objects[component]) <= set(names):
            raise IntentError(f"cannot tag {document.getObject(name).Label!r} as a fastener: it is grouped with "
                              f"other objects into the component {component!r}; ungroup it first")
        parts.append(component)
    kept = [dict(g, objects=[o for o in g["objects"] if o not in names]) for g in intent.fasteners]
    kept = [g for g in kept if g["objects"]]
    others = {owner[o] for g in kept for o in g["objects"] if o in owner}
    hosts = _hosts(intent, set(parts), others)
    if len(hosts) < 2:
        joined = f"only {hosts[0]}" if hosts else "nothing"
        raise IntentError(f"the fasteners {', '.join(dict.fromkeys(parts))} join {joined}: a fastener that joins "
                          "nothing or only one part is left as a part (check its contacts in the diagrams panel)")
    group = {"id": _group_id(hosts, {g["id"] for g in kept}), "objects": list(names),
             "hosts": [objects[h][0] for h in hosts]}
    if tool:
        group["tool"] = tool.strip()
    tools = list(intent.tools) + ([group["tool"]] if tool and group["tool"] not in intent.tools else [])
    return update_intent(analysis, f"tag fasteners {group['id']}", fasteners=kept + [group], tools=tools)


def untag_fasteners(analysis, names: list[str]) -> Intent:
    """Remove the objects ``names`` from their fastener groups (a group left empty goes); one undo step.
    Raises :class:`IntentError` when none of them is tagged."""
    intent = read_intent(analysis)
    if not any(n in g["objects"] for g in intent.fasteners for n in names):
        raise IntentError(f"none of {', '.join(names) or 'the selection'} is tagged as a fastener")
    kept = [dict(g, objects=[o for o in g["objects"] if o not in names]) for g in intent.fasteners]
    return update_intent(analysis, "untag fasteners", fasteners=[g for g in kept if g["objects"]])


def _product(analysis):
    return analysis_product(analysis)


def fastener_report(analysis):
    """The designer's fastener groups (hosts resolved) and the planner's proposals for the other components, on
    the analysis' product: the same call as ``aplan fasteners`` (:func:`planner.api.fastener_report`)."""
    from planner import api

    return api.fastener_report(_product(analysis))


def accept_fastener_proposals(analysis, ids: list[str] | None = None, keep: list[str] | None = None,
                              tools: dict[str, str] | None = None, kept_tools: dict[str, str] | None = None) -> Intent:
    """Add the planner's proposed groups ``ids`` (default: all) to the tags, as designer groups with the
    proposals' hosts, keeping the tagged groups ``keep`` (default: all); one undo step. ``tools`` (proposal id ->
    tool) and ``kept_tools`` (tagged group id -> tool; empty: none) set the tool each group is installed with;
    new tools join the analysis' ``Tools``. Raises :class:`IntentError` for an id that is not proposed."""
    intent = _detected(analysis)
    kept = [dict(g) for g in intent.fasteners if keep is None or g["id"] in keep]
    for group in kept:
        tool = (kept_tools or {}).get(group["id"], group.get("tool") or "").strip()
        group.pop("tool", None)
        if tool:
            group["tool"] = tool
    _, proposals = fastener_report(analysis)
    chosen = [g for g in proposals.groups if ids is None or g.id in ids]
    missing = sorted(set(ids or ()) - {g.id for g in chosen})
    if missing:
        raise IntentError(f"not proposed: {', '.join(missing)}; proposed: "
                          f"{', '.join(g.id for g in proposals.groups) or 'none'}")
    objects = component_objects(intent)
    taken = {g["id"] for g in kept}
    added = []
    for group in chosen:
        entry = {"id": group.id if group.id not in taken else _group_id(sorted(group.hosts), taken),
                 "objects": [o for p in group.parts for o in objects[p]],
                 "hosts": [objects[h][0] for h in sorted(group.hosts)]}
        tool = ((tools or {}).get(group.id) or group.tool or "").strip()
        if tool:
            entry["tool"] = tool
        taken.add(entry["id"])
        added.append(entry)
    fasteners = kept + added
    if fasteners == intent.fasteners:
        return intent
    new_tools = list(intent.tools) + [t for t in dict.fromkeys(g["tool"] for g in fasteners if g.get("tool"))
                                      if t not in intent.tools]
    return update_intent(analysis, f"accept {len(added)} proposed fastener groups" if added else "edit fasteners",
                         fasteners=fasteners, tools=new_tools)


def proposed_structure(analysis, max_components: int = MAX_COMPONENTS) -> list[dict]:
    """The planner's subassembly tree for the analysis' product, its fasteners folded
    (:func:`planner.api.proposed_subassemblies`, as ``--subassemblies auto``), as entries."""
    from planner import api

    return [{"id": s.id, "parts": list(s.parts), "label": s.label}
            for s in api.proposed_subassemblies(_product(analysis), max_components)]


def document_structure(analysis) -> list[dict]:
    """The document's own structure (``App::Part`` containers and groups) over the detected components."""
    from .containers import document_subassemblies
    from .document import Component

    intent = _detected(analysis)
    components = [Component(id=p, label=p, shape=None, objects=tuple(o))
                  for p, o in component_objects(intent).items()]
    return [{"id": s["id"], "parts": s["parts"], "label": s.get("label", "")}
            for s in document_subassemblies(analysis.Document, components, set(intent.tools))]


def check_structure(analysis, entries: list[dict]):
    """The analysis' product with the subassemblies ``entries``, checked by the planner: a cycle, a member in
    two subassemblies or an unknown member (the product format's checks), and every level buildable on its own
    (:func:`planner.api.structure_problems`: stuck members named). Raises :class:`IntentError` saying which."""
    from planner import api
    from planner.product import Subassembly

    product = _product(analysis)
    try:
        product = replace(product, subassemblies=tuple(
            Subassembly(str(s["id"]), tuple(s["parts"]), s.get("label", "")) for s in entries))
    except ProductFormatError as exc:
        raise IntentError(f"subassemblies: {exc.location}: {exc.problem}") from None
    except (KeyError, TypeError) as exc:
        raise IntentError(f"subassemblies: each needs an id and a list of parts ({exc})") from None
    problems = api.structure_problems(product)
    if problems:
        raise IntentError("; ".join(f"subassembly {level} cannot be built on its own: {reason}"
                                    for level, reason in problems))
    return product


def set_subassemblies(analysis, entries: list[dict], description: str = "edit subassemblies") -> Intent:
    """Store the subassembly tree ``entries`` (``[]``: back to the document's own) after
    :func:`check_structure`; one undo step."""
    entries = [{"id": str(s["id"]), "parts": list(s["parts"]), **({"label": s["label"]} if s.get("label") else {})}
               for s in entries]
    if entries:
        try:
            check_structure(analysis, entries)
        except PlannerError as exc:
            raise IntentError(f"{exc}; nothing was changed") from None
    return update_intent(analysis, description, subassemblies=entries)


def current_structure(analysis) -> tuple[list[dict], str]:
    """The subassembly tree the export uses now, and where it comes from: the analysis' own (``analysis``), else
    the document's containers (``document``)."""
    stored = [dict(s) for s in read_intent(analysis).subassemblies]
    return (stored, "analysis") if stored else (document_structure(analysis), "document")


def move_member(entries: list[dict], member: str, target: str | None) -> list[dict]:
    """``entries`` with ``member`` (a component or subassembly id) taken out of its subassembly and put into
    ``target`` (None: the top level). Plain data; the result is checked when stored."""
    out = [dict(s, parts=[m for m in s["parts"] if m != member]) for s in entries]
    if target is not None:
        found = [s for s in out if s["id"] == target]
        if not found:
            raise IntentError(f"no subassembly {target!r}; there are: {', '.join(s['id'] for s in out) or 'none'}")
        found[0]["parts"].append(member)
    return out


def add_subassembly(entries: list[dict], name: str, members: list[str]) -> list[dict]:
    """``entries`` with a new subassembly ``name`` of ``members`` (taken out of the subassemblies they were in)."""
    name = name.strip()
    if not name or name in {s["id"] for s in entries}:
        raise IntentError(f"subassembly name {name!r}: use a new, non-empty name")
    out = [dict(s, parts=[m for m in s["parts"] if m not in members]) for s in entries]
    return out + [{"id": name, "parts": list(members), "label": name}]


def delete_subassembly(entries: list[dict], name: str) -> list[dict]:
    """``entries`` without the subassembly ``name``: its members go to the subassembly that held it (or the top)."""
    gone = next((s for s in entries if s["id"] == name), None)
    if gone is None:
        raise IntentError(f"no subassembly {name!r}")
    out = []
    for s in entries:
        if s is gone:
            continue
        parts = []
        for m in s["parts"]:
            parts.extend(gone["parts"] if m == name else [m])
        out.append(dict(s, parts=parts))
    return out
