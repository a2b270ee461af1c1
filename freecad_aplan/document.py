"""Read the parts of a FreeCAD document (or a STEP file) as solids in global coordinates.

Which objects are parts:

- ``Part::Feature`` and everything derived from it that holds solids: plain features, ``Part::FeaturePython``
  (A2plus assemblies such as the pen and the truck), ``PartDesign::Body``, STEP imports;
- ``App::Link`` objects (also to other documents), with the link's placement; a link array (``ElementCount``
  elements) gives one part per element, named by the element's label (``Bolt_i0`` ...);
- objects inside ``App::Part`` containers, with the containers' placements.

The document's structure (``App::Part`` containers nesting parts, groups, and compounds of whole parts that
nothing else uses: :func:`is_grouping`) becomes the product's subassemblies (:func:`freecad_aplan.containers.document_subassemblies`).

Objects whose shape another feature consumes (boolean operands, the features inside a body, the profile
of an extrusion: a link property of the feature names them, :func:`consuming_properties`) are skipped, as
are hidden objects that an ``App::Link`` shows elsewhere; those holding solids are named in one warning.
Being in another object's InList is not enough: an Assembly4-style part attached to another (Attacher's
``Support``/``AttachmentSupport``, or an expression on its placement) is a part. Objects with faces
but no solid are read as the solids their shells bound when every shell is closed (with a warning), else
reported and skipped. Shapes are always copies: the document's placements and geometry
are never changed.
"""
from __future__ import annotations

import contextlib
import fnmatch
import os
from dataclasses import dataclass, field
from typing import Iterator

import FreeCAD
import Part

from planner.errors import PlannerError

from .arrays import array_element_solids, link_elements, outward, parent_placement

__all__ = ["Component", "ReadResult", "open_model", "read_components", "matching",
           "consuming_properties", "is_grouping", "DocumentError"]

_IMPORT_PREFERENCES = "User parameter:BaseApp/Preferences/Mod/Import"


class DocumentError(PlannerError):
    """A model cannot be read: missing or unreadable file, unsupported type, no solids."""


@dataclass
class Component:
    """One part of the product: its solids (a copy, in global coordinates) and where they came from."""

    id: str
    label: str
    shape: "Part.Shape"
    objects: list[str] = field(default_factory=list)
    material: str | None = None


@dataclass
class ReadResult:
    components: list[Component]
    warnings: list[str]
    document: "FreeCAD.Document"


def open_model(path: str) -> "FreeCAD.Document":
    """Open an ``.FCStd`` document or import a STEP file into a new, hidden document."""
    if not os.path.isfile(path):
        raise DocumentError(f"{path}: no such file")
    extension = os.path.splitext(path)[1].lower()
    if extension == ".fcstd":
        try:
            return FreeCAD.openDocument(path, True)
        except Exception as exc:  # FreeCAD raises plain exceptions for corrupt archives
            raise DocumentError(f"{path}: FreeCAD cannot open it ({exc}); is it a FreeCAD document?") from None
    if extension in (".step", ".stp"):
        return _import_step(path)
    raise DocumentError(f"{path}: unsupported file type {extension!r}; use a FreeCAD document (.FCStd) or STEP (.step, .stp)")


def _import_step(path: str) -> "FreeCAD.Document":
    import Import

    name = "aplan_" + "".join(c if c.isalnum() else "_" for c in os.path.splitext(os.path.basename(path))[0])
    document = FreeCAD.newDocument(name, hidden=True)
    try:
        with _without_link_groups():
            Import.insert(path, document.Name)
    except Exception as exc:
        FreeCAD.closeDocument(document.Name)
        raise DocumentError(f"{path}: the STEP file cannot be read ({exc})") from None
    document.recompute()
    return document


@contextlib.contextmanager
def _without_link_groups() -> Iterator[None]:
    """The import preference ``UseLinkGroup`` off for the duration, then as the user had it (unset when it
    was): ``Import.insert`` with link groups can crash FreeCADCmd (checked on FreeCAD 0.20.2), and the
    preference belongs to the user."""
    group = FreeCAD.ParamGet(_IMPORT_PREFERENCES)
    was_set = "UseLinkGroup" in group.GetBools()
    before = group.GetBool("UseLinkGroup")
    group.SetBool("UseLinkGroup", False)
    try:
        yield
    finally:
        if was_set:
            group.SetBool("UseLinkGroup", before)
        else:
            group.RemBool("UseLinkGroup")


# Link properties that place an object relative to another (Attacher) without using its shape.
_PLACING_PROPERTIES = frozenset({"Support", "AttachmentSupport", "MapPathParameter"})
_LINK_TYPES = ("App::PropertyLink", "App::PropertyLinkList", "App::PropertyLinkSub", "App::PropertyLinkSubList")


def _linked_objects(value) -> Iterator:
    """The document objects in the value of a link property (link, list, (object, subs) or lists of those)."""
    if value is None:
        return
    if hasattr(value, "TypeId"):
        yield value
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _linked_objects(item)


def _same(a, b) -> bool:
    return a is b or (a.Name == b.Name and a.Document.Name == b.Document.Name)


def consuming_properties(user, obj) -> list[str]:
    """The link properties of ``user`` through which it builds its shape from ``obj``'s shape.

    A feature consumes an object when one of its link properties (``Base``/``Tool`` of a boolean, ``Shapes``
    of a multi-fuse, ``Base`` of an extrusion or a chamfer, the ``Group`` of a body, ...) names it. An
    attachment (``Support``/``AttachmentSupport``, properties of the ``Attachment`` group) or an expression
    only places ``user`` relative to ``obj``: Assembly4-style parts attached to each other are all parts.
    Links (``App::Link``) do not consume what they show. Cost: one pass over ``user``'s properties.
    """
    if not obj.isDerivedFrom("Part::Feature") and not obj.isDerivedFrom("App::Link"):
        return []
    if not user.isDerivedFrom("Part::Feature") or user.isDerivedFrom("App::Link") or is_grouping(user):
        return []
    names = []
    for name in user.PropertiesList:
        if name in _PLACING_PROPERTIES:
            continue
        try:
            if user.getGroupOfProperty(name) == "Attachment" or \
                    not user.getTypeIdOfProperty(name).startswith(_LINK_TYPES):
                continue
            value = getattr(user, name)
        except Exception:  # a property a Python feature failed to restore
            continue
        if any(_same(linked, obj) for linked in _linked_objects(value)):
            names.append(name)
    return names


def is_grouping(obj) -> bool:
    """Whether ``obj`` is a compound (``Part::Compound``) that groups whole parts as the authors did, and that
    no other feature consumes: its members are parts, and it is a subassembly of them (a container), not a
    part of its own. A compound a boolean or another feature uses is a shape like any other. Cost: one pass
    over the properties of the objects using it."""
    if not obj.isDerivedFrom("Part::Compound"):
        return False
    users = {user.Name: user for user in obj.InList}.values()
    return not any(consuming_properties(user, obj) for user in users)


def _closed_shell_solids(shape) -> list:
    """The solids bounded by ``shape``'s shells when it has faces but no solid and every shell is closed
    (STEP imports and meshes turned into shapes often come so); [] otherwise."""
    shells = shape.Shells
    if not shells or not all(shell.isClosed() for shell in shells):
        return []
    solids = []
    for shell in shells:
        try:
            solid = Part.Solid(shell)
        except Exception:  # OCCT refuses the shell
            return []
        if solid.Volume < 0:
            solid = Part.Solid(shell.reversed())
        if not solid.isValid() or not solid.Volume > 0:
            return []
        solids.append(solid)
    return solids


def _solids_of(obj) -> tuple["Part.Shape | None", str | None]:
    """A copy of the object's solids in global coordinates, or (None, reason); (shape, note) when the solids
    were made from closed shells."""
    if obj.isDerivedFrom("App::Link"):
        shape = Part.getShape(obj, "", needSubElement=False, transform=True)
    else:
        shape = obj.Shape
    if shape is None or shape.isNull():
        return None, None
    solids = [outward(s.copy()) for s in shape.Solids]
    note = None
    if not solids:
        solids = _closed_shell_solids(shape)
        note = (f"has {len(shape.Faces)} faces in closed shells but no solid; read as the solid they bound "
                "(make it a solid in FreeCAD to silence this)") if solids else None
    if not solids:
        if shape.Faces:
            return None, f"has {len(shape.Faces)} faces but no solid (an open or unsewn shell)"
        return None, None
    compound = solids[0] if len(solids) == 1 else Part.makeCompound(solids)
    compound = compound.copy()
    parent = parent_placement(obj)
    if not parent.isIdentity():
        compound.Placement = parent.multiply(compound.Placement)
    return compound, note


def _holds_solid(obj) -> bool:
    """True when ``obj``'s own shape holds a solid, or ``obj`` is a link (sketches and datums are not named
    when left out)."""
    try:
        return bool(obj.Shape.Solids)
    except Exception:  # objects without a shape, links
        return obj.isDerivedFrom("App::Link")


def _material(obj) -> str | None:
    value = getattr(obj, "Material", None)
    if isinstance(value, str) and value:
        return value
    if isinstance(value, dict):
        return value.get("Name") or value.get("CardName")
    return None


def read_components(document, groups: dict[str, list[str]] | None = None,
                    exclude: list[str] | None = None, split_solids: bool = False) -> ReadResult:
    """The components of ``document``: one per part object, or one per group of ``groups``.

    ``groups`` maps a component name to the labels (or names) of the objects it fuses; ``exclude`` lists
    labels (or names) to leave out (fasteners to be treated later, say). Both take shell-style patterns
    (``wood_screw*``, ``bolt_00[1-4]``; :func:`fnmatch.fnmatchcase`). With ``split_solids``, an object
    holding several solids (a STEP file exported as one product) gives one part per solid; a Draft array
    always gives one part per element, and a link array one per element (its elements' labels); the document's
    only part, when it holds several solids, one part per solid. Raises
    :class:`DocumentError` when a group or exclusion matches no object, when an object matches two groups, or
    when nothing with a solid is left.
    """
    groups = groups or {}
    warnings: list[str] = []
    objects = list(document.Objects)
    linked_hidden = {o.LinkedObject.Name for o in objects
                     if o.isDerivedFrom("App::Link") and o.LinkedObject is not None
                     and o.LinkedObject.Document == document and not o.LinkedObject.Visibility}
    excluded, group_of = _selection(document, objects, groups, exclude or ())

    singles: list[Component] = []
    left_out: list[tuple[str, str]] = []
    compounds = [o for o in objects if is_grouping(o)]
    if compounds:
        many = len(compounds) > 1
        warnings.append(f"{len(compounds)} compound{'s' * many} ({', '.join(o.Label for o in compounds)}) "
                        f"group{'' if many else 's'} parts as the authors did: each member is a part, each "
                        "compound a subassembly of them")
    skipped = {o.Name for o in compounds}
    grouped: dict[str, list[tuple[object, "Part.Shape"]]] = {g: [] for g in groups}
    for obj in objects:
        if not (obj.isDerivedFrom("Part::Feature") or obj.isDerivedFrom("App::Link")):
            continue
        if obj.Name in excluded or obj.Name in skipped:
            continue
        users = {user.Name: user for user in obj.InList}.values()  # an object can be in an InList twice
        consumers = [f"{user.Label}.{name}" for user in users for name in consuming_properties(user, obj)]
        if consumers or obj.Name in linked_hidden:
            if _holds_solid(obj):
                why = f"used by {', '.join(consumers)}" if consumers else "shown by an App::Link"
                left_out.append((obj.Label, why))
            continue
        elements = link_elements(obj)
        if elements:  # a link array: one part per element, as the tree shows them
            for label, name, shape in elements:
                if name in excluded:
                    continue
                if group_of.get(name) is not None:  # --group names elements by their labels
                    grouped[group_of[name]].append((obj, shape))
                else:
                    singles.append(Component(label, label, shape, [obj.Name], _material(obj)))
            continue
        shape, problem = _solids_of(obj)
        if problem and shape is None:
            warnings.append(f"{obj.Label}: {problem}; skipped (make it a solid in FreeCAD to include it)")
        elif problem:
            warnings.append(f"{obj.Label}: {problem}")
        if shape is None:
            continue
        if shape.Volume <= 0:
            warnings.append(f"{obj.Label}: its solid has no volume ({shape.Volume:g}); skipped")
            continue
        group = group_of.get(obj.Name)
        if group is not None:
            grouped[group].append((obj, shape))
        elif len(shape.Solids) > 1 and (split_solids or array_element_solids(obj, shape)):
            pieces = array_element_solids(obj, shape) or [[s] for s in shape.Solids]
            for k, solids in enumerate(pieces, start=1):
                piece = solids[0].copy() if len(solids) == 1 else Part.makeCompound([s.copy() for s in solids])
                singles.append(Component(f"{obj.Label}_{k:03d}", f"{obj.Label} {k}", piece, [obj.Name],
                                         _material(obj)))
        else:
            if len(shape.Solids) > 1:
                warnings.append(f"{obj.Label}: {len(shape.Solids)} solids are read as one part "
                                "(use split_solids / --split-solids for one part per solid)")
            singles.append(Component(obj.Label, obj.Label, shape, [obj.Name], _material(obj)))

    if left_out:
        warnings.append("not parts of their own (inputs of another feature, or shown by a link): "
                        + "; ".join(f"{label} ({why})" for label, why in left_out)
                        + "; the features and links using them are the parts")
    if len(singles) == 1 and not groups and len(singles[0].shape.Solids) > 1:
        singles = _split_the_only_part(singles[0], warnings)
    components = list(singles)
    for group, members in grouped.items():
        if not members:
            raise DocumentError(f"{document.FileName or document.Name}: group {group!r} holds no solid")
        solids = [s for _, shape in members for s in shape.Solids]
        components.append(Component(group, group, Part.makeCompound(solids), [o.Name for o, _ in members]))
    if not components:
        raise DocumentError(_nothing_left(document, objects, excluded))
    _unique_ids(components, warnings)
    return ReadResult(components, warnings, document)


def _split_the_only_part(only: Component, warnings: list[str]) -> list[Component]:
    """One component per solid of ``only``, the document's one part (a STEP file exported as one body of many
    solids): one part leaves nothing to assemble, so it is split as ``split_solids`` would, and the warning that
    it was read as one part says so instead."""
    count = len(only.shape.Solids)
    said = f"{only.label}: {count} solids are read as one part (use split_solids / --split-solids for one part " \
        "per solid)"
    warnings[:] = [w for w in warnings if w != said]
    warnings.append(f"{only.label}: the document's only part holds {count} solids: read as one part per solid "
                    "(one part leaves nothing to assemble); group them in FreeCAD to plan them otherwise")
    return [Component(f"{only.label}_{k:03d}", f"{only.label} {k}", solid.copy(), list(only.objects), only.material)
            for k, solid in enumerate(only.shape.Solids, start=1)]


def _nothing_left(document, objects: list, excluded: dict[str, str]) -> str:
    """Why no component is left: the exclusions that left out every solid (each pattern, how many objects and
    the first of them), or a document without solids."""
    where = document.FileName or document.Name
    left_out: dict[str, list[str]] = {}
    for obj in objects:
        if obj.Name in excluded and (obj.isDerivedFrom("Part::Feature") or obj.isDerivedFrom("App::Link")) \
                and _holds_solid(obj):
            left_out.setdefault(excluded[obj.Name], []).append(obj.Label)
    if not left_out:
        return f"{where}: the document has no solids to plan with"
    said = "; ".join(f"--exclude {pattern!r} leaves out {len(labels)} ({', '.join(labels[:3])}"
                     f"{', ...' if len(labels) > 3 else ''})" for pattern, labels in left_out.items())
    return f"{where}: no solid is left to plan with: {said}; exclude fewer objects (patterns match labels)"


def matching(objects: list, pattern: str) -> list:
    """The objects whose label or internal name is ``pattern``, or else whose label matches it as a shell-style
    pattern (``wood_screw*``: :func:`fnmatch.fnmatchcase`, case-sensitive as labels are). Patterns never match
    internal names: an A2plus document names its parts ``b_LABEL_``, so ``b*`` would match every part."""
    exact = [o for o in objects if pattern in (o.Label, o.Name)]
    if exact:
        return exact
    return [o for o in objects if fnmatch.fnmatchcase(o.Label, pattern)]


def _selection(document, objects: list, groups: dict[str, list[str]],
               exclude: list[str]) -> tuple[dict[str, str], dict[str, str]]:
    """Object name -> the ``exclude`` pattern that leaves it out, and object name -> its group;
    :class:`DocumentError` when a pattern matches no object or an object matches two groups."""
    where = document.FileName or document.Name
    excluded: dict[str, str] = {}
    for pattern in exclude:
        found = matching(objects, pattern)
        if not found:
            raise DocumentError(f"{where}: exclude {pattern!r} matches no object (labels, or an exact internal "
                                "name; patterns such as 'wood_screw*' are shell-style)")
        excluded.update((o.Name, pattern) for o in found if o.Name not in excluded)
    group_of: dict[str, str] = {}
    for group, members in groups.items():
        for member in members:
            found = matching(objects, member)
            if not found:
                raise DocumentError(f"{where}: group {group!r}: {member!r} matches no object (labels, or an exact "
                                    "internal name; patterns such as 'bolt_*' are shell-style)")
            for obj in found:
                if group_of.get(obj.Name, group) != group:
                    raise DocumentError(f"{where}: {obj.Label!r} is in groups {group_of[obj.Name]!r} and {group!r} "
                                        f"({member!r}); put it in one group")
                group_of[obj.Name] = group
    return excluded, group_of


def _unique_ids(components: list[Component], warnings: list[str]) -> None:
    seen: dict[str, int] = {}
    for component in components:
        base = component.id
        if base in seen:
            seen[base] += 1
            component.id = f"{base}_{seen[base]}"
            warnings.append(f"{base}: label used by several parts; this one is called {component.id!r}")
        else:
            seen[base] = 1
