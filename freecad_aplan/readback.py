"""Structure entries fitted to the components an export keeps, so that the bundle always reads back.

The designer's subassembly tree and fastener tags (stored in the APLAN analysis: :mod:`freecad_aplan.structure`)
name components as they were when they were stored. An export can keep fewer or other components since:
objects excluded, grouped into one component, folded, or left out as the input of another feature. Plain
functions over plain data (no FreeCAD), shared by the export and the tests.

Definitions
-----------
- A subassembly *member* is kept when it is an exported component or another subassembly; *mapped* to the
  component that now holds it when it names an object (internal name or label) of a component made of
  several objects (a ``--group``); else *dropped*. A subassembly left with fewer than two members is
  *dissolved*: its member, if any, takes its place in the subassembly that held it.
- A fastener tag's object that is no component of its own (left out, or grouped with others) is dropped from
  the tag; a tag left without fasteners, or joining fewer than two components, is dropped.

Each mapping, drop and dissolution is one warning naming the entry and the member. Cost: O(members x depth).
"""
from __future__ import annotations

from planner.product.fasteners import dissolve_small

__all__ = ["fit_subassemblies", "fit_fasteners"]


def _object_owner(objects: dict[str, list[str]], labels: dict[str, str]) -> dict[str, str]:
    """Internal name or label of an object -> the component made of it."""
    owner = {}
    for component, names in objects.items():
        for name in names:
            owner.setdefault(name, component)
            if labels.get(name):
                owner.setdefault(labels[name], component)
    return owner


def fit_subassemblies(entries: list[dict], objects: dict[str, list[str]], labels: dict[str, str] | None = None,
                      where: str = "the subassemblies") -> tuple[list[dict], list[str]]:
    """``entries`` (``[{id, parts, ...}]``) fitted to the components ``objects`` (component id -> internal names
    of its objects; ``labels``: internal name -> label), and one warning per change (see the module's
    definitions). ``where`` names the entries' origin in the warnings."""
    labels = labels or {}
    owner = _object_owner(objects, labels)
    ids = {e["id"] for e in entries}
    warnings: list[str] = []
    members: dict[str, list[str]] = {}
    taken: dict[str, str] = {}
    for entry in entries:
        kept: list[str] = []
        for member in entry["parts"]:
            if member in objects or member in ids:
                target = member
            elif member in owner:
                target = owner[member]
                warnings.append(f"{where}: {entry['id']!r} lists {member!r}, which the export made part of the "
                                f"component {target!r}: {target!r} stands for it")
            else:
                warnings.append(f"{where}: {entry['id']!r} lists {member!r}, which is no exported part (excluded, "
                                "folded, or the input of another feature): dropped from it")
                continue
            if target in taken and taken[target] != entry["id"]:
                warnings.append(f"{where}: {target!r} is in {taken[target]!r} already: dropped from "
                                f"{entry['id']!r}")
                continue
            if target not in kept:
                kept.append(target)
                taken[target] = entry["id"]
        members[entry["id"]] = kept
    dissolved = dissolve_small(members)
    for sid, stands in dissolved.items():
        left = f"only {stands!r}, which takes its place" if stands is not None else "empty"
        warnings.append(f"{where}: {sid!r} is dissolved: it is left {left}")
    return [dict(e, parts=members[e["id"]]) for e in entries if e["id"] not in dissolved], warnings


def fit_fasteners(groups: list[dict], objects: dict[str, list[str]],
                  labels: dict[str, str] | None = None) -> tuple[list[dict], list[str]]:
    """The analysis' fastener tags (``[{id, objects, hosts, tool?}]``, by internal object name) fitted to the
    components ``objects``: each fastener object that is no component of its own, and each host object that is
    no component, is dropped; a tag left without fasteners or with fewer than two hosts is dropped. Returns the
    kept tags and one warning per drop."""
    labels = labels or {}
    owner = {name: c for c, names in objects.items() for name in names}
    warnings: list[str] = []
    kept = []
    for group in groups:
        where = f"fastener group {group.get('id')!r}"
        fasteners, hosts = [], []
        for name in group.get("objects", []):
            component = owner.get(name)
            shown = labels.get(name, name)
            if component is None:
                warnings.append(f"{where}: {shown!r} is no exported part (left out or missing): dropped from it")
            elif not set(objects[component]) <= set(group["objects"]):
                warnings.append(f"{where}: {shown!r} is grouped with other objects into {component!r}: dropped "
                                "from it (ungroup it to tag it as a fastener)")
            else:
                fasteners.append(name)
        for name in group.get("hosts", []):
            if name in owner:
                hosts.append(name)
            else:
                warnings.append(f"{where}: its host {labels.get(name, name)!r} is no exported part: dropped")
        joined = {owner[h] for h in hosts}
        if not fasteners or len(joined) < 2:
            warnings.append(f"{where}: {'no fastener' if not fasteners else 'fewer than two hosts'} left: the "
                            "group is dropped (its parts are planned as parts)")
            continue
        kept.append(dict(group, objects=fasteners, hosts=hosts))
    return kept, warnings
