"""The product the planner sees in an APLAN analysis (:mod:`freecad_aplan.intent`): the stored diagrams, the
designer intent and the designer's structure (fastener tags, the subassembly tree) as the product file's
entries. The export (:mod:`freecad_aplan.export`), the structure panels (:mod:`freecad_aplan.structure`) and
the workbench's commands (:mod:`freecad_aplan.workflow`) all build it here.
"""
from __future__ import annotations

from dataclasses import replace

from planner.defaults import PRODUCT_FORMAT, PRODUCT_VERSION
from planner.assembly.support_contacts import CANDIDATES_KEY
from planner.errors import ProductFormatError
from planner.product import product_from_dict

from .intent import Intent, IntentError, designer_record, product_intent, read_intent

__all__ = ["component_objects", "fastener_entries", "subassembly_entries", "structure_entries", "analysis_product",
           "analysis_base_part"]


def component_objects(intent: Intent) -> dict[str, list[str]]:
    """Component id -> the internal names of its objects, as the last detection found them."""
    return {p: list(intent.diagrams.get("objects", {}).get(p, [])) for p in intent.diagrams.get("parts", [])}


def _owner_of(objects: dict[str, list[str]]) -> dict[str, str]:
    return {name: component for component, names in objects.items() for name in names}


def fastener_entries(intent: Intent, objects: dict[str, list[str]]) -> list[dict]:
    """The product file's ``fasteners`` section for the analysis' tags, over the components ``objects``
    (component id -> its objects' internal names). Raises :class:`IntentError` naming the group when a tagged
    object or host is no component (excluded, or grouped with other objects). Cost: O(tagged objects)."""
    owner = _owner_of(objects)
    out = []
    for group in intent.fasteners:
        where = f"fastener group {group.get('id')!r}"
        parts, hosts = [], []
        roles = (("fastener", group.get("objects", []), parts), ("host", group.get("hosts", []), hosts))
        for role, names, into in roles:
            for name in names:
                component = owner.get(name)
                if component is None:
                    raise IntentError(f"{where}: the {role} object {name!r} is not a component of the product (left "
                                      "out or missing); tag it again, or untag the group")
                if role == "fastener" and not set(objects[component]) <= set(group["objects"]):
                    raise IntentError(f"{where}: {name!r} is grouped with other objects into the component "
                                      f"{component!r}; ungroup it to tag it as a fastener")
                if component not in into:
                    into.append(component)
        entry = {"id": group["id"], "parts": parts, "hosts": hosts, "source": "designer"}
        if group.get("tool"):
            entry["tool"] = group["tool"]
        out.append(entry)
    return out


def subassembly_entries(intent: Intent) -> list[dict]:
    """The product file's ``subassemblies`` section for the analysis' tree (``source: "designer"``)."""
    return [{"id": s["id"], "parts": list(s["parts"]), **({"label": s["label"]} if s.get("label") else {}),
             "source": "designer"} for s in intent.subassemblies]


def structure_entries(intent: Intent, objects: dict[str, list[str]], labels: dict[str, str] | None = None,
                      warnings: list[str] | None = None) -> dict:
    """The product-file keys the analysis' structure adds: ``fasteners`` (and their tools in ``tools``) and
    ``subassemblies``, each only when the analysis has some. With ``warnings`` (a list), entries naming what is
    no exported component are mapped or dropped, one warning each (:mod:`freecad_aplan.readback`; ``labels``:
    internal name -> label), instead of raising :class:`IntentError`."""
    out: dict = {}
    if warnings is not None:
        from .readback import fit_fasteners, fit_subassemblies

        tags, said = fit_fasteners(list(intent.fasteners), objects, labels)
        tree, more = fit_subassemblies([dict(s) for s in intent.subassemblies], objects, labels,
                                       "the analysis' subassembly tree")
        warnings.extend(said + more)
        intent = replace(intent, fasteners=tags, subassemblies=tree)
    fasteners = fastener_entries(intent, objects)
    if fasteners:
        out["fasteners"] = fasteners
        out["tools"] = [{"id": t} for t in dict.fromkeys(list(intent.tools) + [g["tool"] for g in fasteners
                                                                                   if g.get("tool")])]
    if intent.subassemblies:
        out["subassemblies"] = subassembly_entries(intent)
    return out


def analysis_product(analysis, name: str = ""):
    """The product the planner sees: the stored diagrams plus the designer intent (a ``planner.Product``).

    Raises :class:`~freecad_aplan.intent.IntentError` when nothing was detected yet or the intent does not fit.
    """
    intent = read_intent(analysis)
    diagrams = intent.diagrams
    if not diagrams.get("parts"):
        raise IntentError(f"{analysis.Label}: no contacts and obstructions yet; run APLAN > Detect contacts "
                          "and obstructions first")
    labels, volumes = diagrams.get("labels", {}), diagrams.get("volumes", {})
    parts = [{"id": p, **({"label": labels[p]} if p in labels else {}),
              **({"volume": volumes[p]} if p in volumes else {})} for p in diagrams["parts"]]
    data = {"format": PRODUCT_FORMAT, "version": PRODUCT_VERSION, "name": name or analysis.Document.Label,
            "parts": parts, "contacts": diagrams["contacts"], "obstructions": diagrams["obstructions"],
            **product_intent(intent), **structure_entries(intent, component_objects(intent))}
    record, released = designer_record(intent), diagrams.get("analysis", {}).get("designer")
    candidates = level_candidates(intent)
    found = {**({"designer": released} if released else {}), **({CANDIDATES_KEY: candidates} if candidates else {})}
    if record or found:  # the designer's directions and marks, what the marks released (aplan stats), and the
        # support rule's candidates for the levels (a product too large to judge flat), less those rejected
        data["geometry"] = {**({"designer": record} if record else {}), **({"analysis": found} if found else {})}
    try:
        return product_from_dict(data, analysis.Label)
    except ProductFormatError as exc:
        raise IntentError(f"{analysis.Label}: {exc.location}: {exc.problem}; fix it in the APLAN task panels, "
                          "or run the detection again if the components changed") from None


def level_candidates(intent) -> dict | None:
    """The support rule's candidates the last detection recorded for the levels (a product too large to judge
    flat, :mod:`planner.assembly.level_supports`), without those the designer rejected in the interlocks panel
    (:mod:`freecad_aplan.interlocks`): the levels add a contact for each one left that frees them. None when
    none is left."""
    record = intent.diagrams.get("analysis", {}).get(CANDIDATES_KEY)
    if not record:
        return None
    rejected = {frozenset(d.get("parts", ())) for d in intent.interlocks
                if d.get("rule") == "support" and d.get("decision") == "rejected"}
    kept = [c for c in record.get("contacts", []) if frozenset(c.get("parts", ())) not in rejected]
    return {**record, "contacts": kept} if kept else None


def analysis_base_part(analysis) -> str | None:
    """The analysis' base part (``BasePart``): None when empty, else ``auto`` or a component id, as the
    planner's ``base_part`` arguments take it (:func:`planner.api.base_part_of` resolves and checks it)."""
    return read_intent(analysis).base_part or None
