"""The document's own structure as the product's subassemblies: ``App::Part`` containers nesting parts, groups
(``App::DocumentObjectGroup``) and compounds of whole parts that nothing else uses
(:func:`~freecad_aplan.document.is_grouping`), over the components :func:`~freecad_aplan.document.read_components`
found (:func:`document_subassemblies`). The document is only read.
"""
from __future__ import annotations

from dataclasses import dataclass

from .document import Component, is_grouping

__all__ = ["document_subassemblies"]


_CONTAINERS = ("App::Part", "App::DocumentObjectGroup")


def _container_parents(document) -> dict[str, object]:
    """Object name -> the ``App::Part`` container or group that holds it directly."""
    parents: dict[str, object] = {}
    for obj in document.Objects:
        if obj.TypeId in _CONTAINERS or any(obj.isDerivedFrom(t) for t in _CONTAINERS):
            for child in getattr(obj, "Group", None) or ():
                parents.setdefault(child.Name, obj)
        elif is_grouping(obj):  # the authors' compound of parts (read_components reads its members)
            for child in getattr(obj, "Links", None) or ():
                parents.setdefault(child.Name, obj)
    return parents


def document_subassemblies(document, components: list[Component], taken: set[str] = frozenset()) -> list[dict]:
    """The structure of ``document`` as the product file's ``subassemblies`` (``[{id, parts, label, source}]``).

    Definition: a container (``App::Part``, or a group) is a subassembly whose members are the components
    directly in it (a component is where its first object is) and the containers below it that hold a
    component. An object split into several components (``split_solids``: an A2plus sub-assembly import, a
    link to another document's assembly, a STEP product read as one object) is a subassembly of them, in the
    object's container. A container with one member is skipped (its member counts in its place), and so is a single
    outermost container holding every component (the whole product). Ids are the containers' labels, made
    unique against the component ids and ``taken``. Cost: O(objects + components x depth).
    """
    parents = _container_parents(document)
    ids = {c.id for c in components} | set(taken)
    members: dict[str, list[str]] = {}  # container name -> member ids (components or container names)
    order: list[object] = []

    def place(member: str, container) -> None:
        # Register ``member`` in ``container``, and the container in its own parent, once.
        if container.Name not in members:
            members[container.Name] = []
            order.append(container)
            parent = parents.get(container.Name)
            if parent is not None:
                place("\0" + container.Name, parent)
        if member not in members[container.Name]:
            members[container.Name].append(member)

    sources: dict[str, int] = {}
    for component in components:
        if component.objects:
            sources[component.objects[0]] = sources.get(component.objects[0], 0) + 1
    for component in components:
        first = document.getObject(component.objects[0]) if component.objects else None
        container = parents.get(first.Name) if first is not None else None
        if first is not None and sources[first.Name] > 1:  # its solids, split: a subassembly of its own
            split = _Split("\1" + first.Name, first.Label)
            if container is not None:
                parents[split.Name] = container
            container = split
        if container is not None:
            place(component.id, container)
    if not members:
        return []

    def resolve(member: str) -> str | None:
        # A container with one member stands for that member; None for a container left out.
        if not member.startswith("\0"):
            return member
        name = member[1:]
        inner = [m for m in (resolve(x) for x in members[name]) if m is not None]
        return inner[0] if len(inner) == 1 else names.get(name) if inner else None

    names: dict[str, str] = {}
    for container in order:
        base, k = container.Label, 1
        name = base
        while name in ids:
            k += 1
            name = f"{base}_{k}"
        ids.add(name)
        names[container.Name] = name
    roots = [c for c in order if c.Name not in parents or parents[c.Name].Name not in members]
    whole = len(roots) == 1 and sum(1 for c in components if c.id in _held(roots[0].Name, members)) == len(components)
    found = []
    for container in order:
        inner = [m for m in (resolve(x) for x in members[container.Name]) if m is not None]
        if len(inner) < 2 or (whole and container is roots[0]):
            continue
        found.append({"id": names[container.Name], "parts": inner, "label": container.Label, "source": "designer"})
    return found


@dataclass(frozen=True)
class _Split:
    """Stands for an object split into several components, as a container of them."""

    Name: str
    Label: str


def _held(name: str, members: dict[str, list[str]]) -> set[str]:
    """The component ids a container holds, at any depth."""
    held: set[str] = set()
    for member in members[name]:
        held |= _held(member[1:], members) if member.startswith("\0") else {member}
    return held
