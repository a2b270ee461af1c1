"""The interlock rules' proposals of the last detection, decided on by the designer (the interlocks panel).

The workbench's detection records, while the meshes exist, what the interlock rules would do to each pair
of parts that block each other along every direction (:func:`planner.assembly.interlock_proposals.
record_proposals`, in the stored diagrams' ``analysis``). Here the designer accepts or rejects each one, on
the analysis only (:mod:`freecad_aplan.intent`; the user's geometry and placements are never touched):

- *accepted*: written into the designer data the command line's options stand for: an insertion direction
  that is no axis into ``DesignerDirections``, the pair's relations the overlap adds into ``NotBlocking``
  (so every later detection applies them), a one-component proposal into ``Groups``; and the stored diagrams
  changed as the rule changes them, so the plan uses it at once;
- *rejected*: kept in ``Interlocks``; the product the planner sees then carries the refusal
  (``geometry.designer.refused_interlocks``) and planning raises the ``--interlocks error`` message for the
  pair while it is interlocked: nothing is applied that the designer did not accept.

The support contacts the detection proposes (:func:`planner.assembly.support_contacts.record_support_proposals`:
a part that would float inside the part whose cavity holds it) are listed after them, with the rule
``support``: *accepted*, the contact is added to the stored diagrams (as ``--support-contacts add`` adds it:
:func:`~planner.assembly.support_contacts.apply_support_proposal`); *rejected*, nothing is added, as with
``--support-contacts keep``: the plan names the parts that would float. A new detection drops an accepted
contact from the diagrams; its proposal reads *not decided* again then.

A product too large for the support rule to judge flat (:data:`~planner.assembly.support_contacts.CHECK_LIMIT`)
gets the rule's candidates recorded by the detection instead, and its levels (the designer's subassemblies)
judge them when it is planned (:mod:`planner.assembly.level_supports`). The report lists what they would add,
each with its ``level`` (:func:`planner.api.level_support_proposals`, on the product the planner sees), after
the flat ones: *accepted*, the contact is added to the stored diagrams as above; *rejected*, the candidate is
left out of the product the planner sees (:func:`freecad_aplan.analysis.level_candidates`), so the level's plan
names the parts that would float; not decided, planning adds it, saying so in one line, as the command line does.

Every decision is recorded in ``Interlocks`` (``{"parts", "rule", "text", "decision"}``, and ``level``). One OK
is one undo step. Plain functions (no Qt), shared by the panel (:mod:`freecad_aplan.gui.interlocks`) and the tests.
"""
from __future__ import annotations

from planner.assembly.interlock_proposals import PROPOSALS_KEY, apply_proposal
from planner.assembly.support_contacts import CANDIDATES_KEY, SUPPORT_PROPOSALS_KEY, apply_support_proposal
from planner.errors import PlannerError

from .intent import IntentError, read_intent, update_intent

__all__ = ["interlock_report", "decide_interlocks", "DECISIONS"]

DECISIONS = ("accepted", "rejected")


def _key(entry: dict) -> tuple[bool, frozenset]:
    return entry.get("rule") == "support", frozenset(entry.get("parts", ()))


def _decision(proposal: dict, decided: dict, contacts: set):
    """The stored decision on ``proposal``; an accepted support contact the diagrams lack (a new detection) none."""
    decision = decided.get(_key(proposal))
    missing = proposal.get("rule") == "support" and frozenset(proposal["parts"]) not in contacts
    return None if decision == "accepted" and missing else decision


def interlock_report(analysis) -> tuple[list[dict], list[str]]:
    """The proposals of the last detection, the interlock rules' then the support contacts' (module docstring),
    each with ``decision`` (``accepted``, ``rejected`` or None: not decided yet, from the analysis'
    ``Interlocks``), and the lines of the pairs no rule frees. Raises
    :class:`IntentError` before any detection."""
    intent = read_intent(analysis)
    if not intent.diagrams.get("parts"):
        raise IntentError(f"{analysis.Label}: no contacts and obstructions yet; run APLAN > Detect contacts and "
                          "obstructions first (it finds the interlocked pairs and what would free them)")
    record = intent.diagrams.get("analysis", {})
    decided = {_key(d): d.get("decision") for d in intent.interlocks}
    contacts = {frozenset(c) for c in intent.diagrams.get("contacts", [])}
    proposals = [{**p, "decision": _decision(p, decided, contacts)}
                 for p in record.get(PROPOSALS_KEY, []) + record.get(SUPPORT_PROPOSALS_KEY, [])]
    unresolved = list(record.get("interlock_unresolved", []))
    if record.get(CANDIDATES_KEY):
        try:
            levels = _level_proposals(analysis, intent)
        except PlannerError as exc:  # IntentError too: the structure does not fit (its own panel says why)
            levels = []
            unresolved.append(f"the support contacts of the workstations are not judged: {exc}")
        proposals += [{**p, "decision": _decision(p, decided, contacts)} for p in levels]
    return proposals, unresolved


def _level_proposals(analysis, intent) -> list[dict]:
    """The support contacts the levels would add (module docstring), then those decided earlier that they no
    longer list (an accepted contact frees its level; a rejected one is no candidate any more)."""
    from planner import api

    from .analysis import analysis_product

    live = api.level_support_proposals(analysis_product(analysis))
    listed = {frozenset(p["parts"]) for p in live}
    earlier = [{k: d[k] for k in ("rule", "parts", "level", "text")} for d in intent.interlocks
               if d.get("rule") == "support" and d.get("level") and frozenset(d["parts"]) not in listed]
    return live + earlier


def _merged_component(diagrams: dict, groups: dict, proposal: dict) -> None:
    """The stored diagrams' objects, labels and volumes, and the groups, for a one-component proposal (in place)."""
    name, (a, b) = proposal["component"], proposal["parts"]
    objects = dict(diagrams.get("objects", {}))
    members = list(objects.pop(a, [])) + list(objects.pop(b, []))
    if not members:
        raise IntentError(f"the components {a} and {b} have no objects recorded; run the detection again")
    objects[name] = members
    for old in (a, b):  # a component that was a group already: its objects are in the new one
        groups.pop(old, None)
    groups[name] = members
    volumes = dict(diagrams.get("volumes", {}))
    if a in volumes and b in volumes:
        volumes[name] = volumes[a] + volumes[b]
    for old in (a, b):
        volumes.pop(old, None)
    diagrams.update(objects=objects, volumes=volumes,
                    labels={k: v for k, v in diagrams.get("labels", {}).items() if k not in (a, b)})


def decide_interlocks(analysis, decisions: dict[int, str]) -> list[str]:
    """Store the designer's ``decisions`` (index in :func:`interlock_report`'s proposals -> ``accepted`` or
    ``rejected``) in one undoable transaction (module docstring); returns one line per change (``interlock
    accepted: ...``, ``support contact rejected: ...``). A proposal
    accepted already is left as it is (undo the step to take it back). Raises :class:`IntentError` naming the
    proposal (an unknown index or decision, components that changed since the detection: detect again), and
    nothing changes then. Cost: O(size of the product) per accepted proposal."""
    from planner.product import product_to_dict

    from .designer_edits import _designer_product

    proposals, _ = interlock_report(analysis)
    intent = read_intent(analysis)
    for k, decision in decisions.items():
        if not 0 <= k < len(proposals) or decision not in DECISIONS:
            raise IntentError(f"interlock proposal {k}: unknown, or decision {decision!r} not one of "
                              f"{', '.join(DECISIONS)}")
    chosen = {k: d for k, d in decisions.items() if proposals[k]["decision"] != "accepted" and
              proposals[k]["decision"] != d}
    if not chosen:
        return []
    product, _ = _designer_product(analysis)
    diagrams, groups = dict(intent.diagrams), dict(intent.groups)
    subassemblies = [dict(s) for s in intent.subassemblies]
    record = [d for d in intent.interlocks if _key(d) not in {_key(proposals[k]) for k in chosen}]
    lines = []
    for k, decision in sorted(chosen.items()):
        proposal = proposals[k]
        pair = " and ".join(proposal["parts"])
        support = proposal["rule"] == "support"
        if decision == "accepted":
            try:
                product = (apply_support_proposal if support else apply_proposal)(product, proposal)
            except PlannerError as exc:
                raise IntentError(f"interlock proposal for {pair}: {exc}") from None
            if proposal["rule"] == "component":
                inside = set(proposal["parts"])
                marked = [m for m in intent.not_blocking if {m.get("blocked"), m.get("blocking")} & inside]
                if marked:
                    raise IntentError(f"interlock proposal for {pair}: the designer marks "
                                      f"{', '.join(m['blocked'] + ' - ' + m['blocking'] for m in marked)} name these "
                                      "parts; unmark them in the diagrams panel first")
                _merged_component(diagrams, groups, proposal)
                for entry in subassemblies:  # the designer's tree names the component now
                    entry["parts"] = list(dict.fromkeys(proposal["component"] if p in inside else p
                                                        for p in entry["parts"]))
        record.append({"parts": list(proposal["parts"]), "rule": proposal["rule"], "text": proposal["text"],
                       "decision": decision, **({"level": proposal["level"]} if proposal.get("level") else {})})
        said = (proposal["text"] if decision == "accepted" else f"{pair} ({proposal['rule']}): " +
                ("not added; the plan names the parts that would float" if support else "refused when planning"))
        lines.append(f"{'support contact' if support else 'interlock'} {decision}: {said}")
    data = product_to_dict(product)
    designer = product.geometry.get("designer", {})
    diagrams.update(parts=list(product.part_ids), contacts=data["contacts"], obstructions=data["obstructions"],
                    analysis=product.geometry.get("analysis", {}))
    (first, decision), = list(chosen.items())[:1]
    verb = {"accepted": "accept", "rejected": "reject"}[decision]
    kind = "support contact" if proposals[first]["rule"] == "support" else "interlock"
    what = (f"{verb} {kind} {' and '.join(proposals[first]['parts'])}" if len(chosen) == 1 else
            f"decide {len(chosen)} interlocks and support contacts")
    update_intent(analysis, what, groups=groups, subassemblies=subassemblies, diagrams=diagrams, interlocks=record,
                  directions=[list(v) for v in designer.get("directions", [])],
                  not_blocking=[dict(m) for m in designer.get("not_blocking", [])])
    return lines
