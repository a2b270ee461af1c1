"""The plan shown on the document's 3D view, and put back exactly: parts moved to their exploded offsets and
coloured by their role in an operation or a relation, then restored.

In the GUI nothing of the document changes: the parts are moved and painted in the 3D view's scene graph
only (each view provider's Coin3D transform and face materials), so no property changes, no undo step is
recorded, the document is not marked modified and nothing needs a recompute; the user's ``Placement``,
``ShapeColor``, ``DiffuseColor``, ``Transparency`` and ``Visibility`` are never written (hidden parts stay
hidden). What was there is saved first and written back by :meth:`SceneChanges.restore`. FreeCAD redraws a
part from its properties whenever one of them changes, which also ends the temporary look.

Without the GUI (FreeCADCmd: no view providers) a move sets ``Placement`` itself, with the property marked
``NoModify`` meanwhile, and the saved placement is written back bit for bit on restore; no transaction is
opened, so a move is never an undo step and nothing the user does meanwhile is rolled back with it.
The planner's exploded view (:func:`planner.api.plan_in_3d`) says which part goes where.
"""
from __future__ import annotations

from types import MappingProxyType

import FreeCAD

__all__ = ["COLOURS", "DIMMED", "SceneChanges", "bound_box", "component_objects", "extent", "face_materials",
           "orthographic_fit", "interlock_looks", "outline_points", "relation_looks", "shown_transform",
           "step_looks"]

#: Colours (RGB 0..1) and transparencies (percent) of the roles.
COLOURS = MappingProxyType({"moving": (1.0, 0.55, 0.0), "blocked": (0.85, 0.1, 0.1), "blocking": (0.1, 0.35, 0.9)})
DIMMED = MappingProxyType({"fixed": 55, "idle": 85, "blocking": 75, "holding": 50})


def component_objects(document, diagrams: dict) -> dict[str, list]:
    """Component id -> the document's objects of it: those the last detection recorded (``diagrams["objects"]``),
    else the objects labelled with the id. Components without an object in the document are left out."""
    recorded = diagrams.get("objects") or {}
    out = {}
    for part in diagrams.get("parts", []):
        objects = [document.getObject(n) for n in recorded.get(part, [])]
        objects = [o for o in objects if o is not None] or document.getObjectsByLabel(part)
        objects = [o for o in objects if hasattr(o, "Placement")]
        if objects:
            out[part] = objects
    return out


def bound_box(objects) -> FreeCAD.BoundBox:
    """The global bounding box of the shapes of ``objects`` (objects without a shape are skipped)."""
    box = FreeCAD.BoundBox()
    for obj in objects:
        shape = getattr(obj, "Shape", None)
        if shape is not None and not shape.isNull():
            box.add(shape.BoundBox)
    return box


def outline_points(objects, per_edge: int = 12) -> list:
    """Points on the edges of the shapes of ``objects`` (``per_edge`` on each edge, its vertices for a shape
    without edges; global coordinates, as :func:`bound_box`): a view fitted to them is fitted to what is drawn.
    The eight corners of a bounding box, seen at an angle, project up to about 1.7 times wider than a round
    part (the pen's head filled 7 % of the view fitted to its box). Cost: O(edges x per_edge)."""
    import Part

    points = []
    for obj in objects:
        shape = getattr(obj, "Shape", None)
        if shape is None or shape.isNull():
            continue
        for edge in shape.Edges:
            if not edge.Degenerated:  # a cone's apex, a sphere's pole: nothing to discretize
                try:
                    points += edge.discretize(Number=per_edge)
                except Part.OCCError:  # an edge OCC cannot sample: its vertices still count
                    points += [v.Point for v in edge.Vertexes]
        points += [v.Point for v in shape.Vertexes]
    return points


def extent(objects) -> float:
    """The diagonal of :func:`bound_box` (1.0 when nothing has a shape): how far an exploded part sits away."""
    box = bound_box(objects)
    return float(box.DiagonalLength) if box.isValid() and box.DiagonalLength > 0 else 1.0


def orthographic_fit(axes, corners, aspect: float, margin: float = 1.1) -> tuple[FreeCAD.Vector, float, float]:
    """An orthographic camera looking along ``-axes[2]`` (``axes``: its right, up and towards-the-viewer unit
    vectors) that shows every point of ``corners``: ``(position, focal distance, height)``. Centred on their
    extent projected on right and up, in front of all of them; the height the larger of the projected height
    and the projected width over ``aspect`` (width / height of the view), times ``margin``; on a view higher
    than wide Coin puts the height on the width (``ADJUST_CAMERA``), hence the factor ``min(1, aspect)``.
    Cost: O(len(corners))."""
    low = [min(c.dot(a) for c in corners) for a in axes]
    high = [max(c.dot(a) for c in corners) for a in axes]
    depth = max(high[2] - low[2], 1e-6)
    centre = [0.5 * (a + b) for a, b in zip(low, high)]
    position = axes[0] * centre[0] + axes[1] * centre[1] + axes[2] * (high[2] + depth)
    spans = max(high[1] - low[1], (high[0] - low[0]) / aspect) * min(1.0, aspect)
    return position, 1.5 * depth, margin * max(spans, 1e-6)


def step_looks(roles: dict[str, str]) -> dict[str, tuple]:
    """Per part of an exploded step: ``(colour or None, transparency or None)``: the moving parts highlighted,
    the side they join dimmed a little, the others dimmed more."""
    return {p: (COLOURS["moving"], 0) if r == "moving" else (None, DIMMED[r]) for p, r in roles.items()}


def relation_looks(parts, blocked: str, blocking: str) -> dict[str, tuple]:
    """Per part for an obstruction relation: the blocked part red, the blocking part blue and see-through (it
    often encloses the blocked one), the others dimmed."""
    return {p: (COLOURS["blocked"], 0) if p == blocked else (COLOURS["blocking"], DIMMED["blocking"])
            if p == blocking else (None, DIMMED["idle"]) for p in parts}


def interlock_looks(parts, leaving: str, other: str) -> dict[str, tuple]:
    """Per part for an interlock proposal with a direction: the part that leaves orange, the other blue and a
    little see-through (it often holds the first), the others dimmed."""
    return {p: (COLOURS["moving"], 0) if p == leaving else (COLOURS["blocking"], DIMMED["holding"])
            if p == other else (None, DIMMED["idle"]) for p in parts}


def _parent_rotation(obj) -> FreeCAD.Rotation:
    """The rotation from ``obj``'s own frame to the global one (its containers'), so a global offset can be
    written into its local placement (or its view provider's transform, which mirrors it)."""
    try:
        parent = obj.getGlobalPlacement().multiply(obj.Placement.inverse())
    except (RuntimeError, AttributeError):  # an object FreeCAD cannot place globally: its placement is global
        return FreeCAD.Rotation()
    return parent.Rotation


def shown_transform(obj):
    """The Coin3D transform the 3D view draws ``obj`` with (its view provider's first node), or None without a
    view."""
    view = getattr(obj, "ViewObject", None)
    root = getattr(view, "RootNode", None) if view is not None else None
    if root is None or root.getNumChildren() == 0:
        return None
    node = root.getChild(0)
    return node if node.getTypeId().getName().getString() == "Transform" else None


def face_materials(obj) -> list:
    """The Coin3D materials the 3D view paints ``obj``'s faces with: those of its view provider whose colours are
    its ``DiffuseColor`` (or ``ShapeColor``); the lines' and points' materials are left alone. Empty without a
    view."""
    view = getattr(obj, "ViewObject", None)
    root = getattr(view, "RootNode", None) if view is not None else None
    if root is None:
        return []
    from pivy import coin

    search = coin.SoSearchAction()
    search.setType(coin.SoMaterial.getClassTypeId())
    search.setInterest(coin.SoSearchAction.ALL)
    search.setSearchingAll(True)
    search.apply(root)
    paths = search.getPaths()
    faces = {tuple(round(c, 4) for c in colour[:3]) for colour in list(getattr(view, "DiffuseColor", []))
             + [tuple(getattr(view, "ShapeColor", (0, 0, 0)))]}
    out = []
    for i in range(paths.getLength()):
        material = paths[i].getTail()
        if material.diffuseColor.getNum() and tuple(round(c, 4) for c in material.diffuseColor[0]) in faces:
            out.append(material)
    return out


def _fields(material) -> tuple[list, list]:
    return ([tuple(material.diffuseColor[k]) for k in range(material.diffuseColor.getNum())],
            [material.transparency[k] for k in range(material.transparency.getNum())])


def _set_fields(material, colours: list, transparencies: list) -> None:
    material.diffuseColor.setNum(len(colours))
    material.diffuseColor.setValues(0, len(colours), colours)
    material.transparency.setNum(len(transparencies))
    material.transparency.setValues(0, len(transparencies), transparencies)


class SceneChanges:
    """Objects moved and painted for a view of the plan, and how they were before (module docstring)."""

    def __init__(self, document):
        self.document = document
        self.placements: dict[str, FreeCAD.Placement] = {}
        self.transforms: dict[str, tuple] = {}
        self.materials: dict[str, list] = {}

    def _keep(self, obj) -> None:
        if obj.Name in self.placements:
            return
        self.placements[obj.Name] = FreeCAD.Placement(obj.Placement)
        node = shown_transform(obj)
        if node is not None:
            self.transforms[obj.Name] = (node, tuple(node.translation.getValue()))
        self.materials[obj.Name] = [(m, *_fields(m)) for m in face_materials(obj)]

    def move(self, obj, offset) -> None:
        """Show ``obj`` at its saved placement shifted by the global vector ``offset``."""
        self._keep(obj)
        shift = _parent_rotation(obj).inverted().multVec(FreeCAD.Vector(*offset))
        if obj.Name in self.transforms:
            node, home = self.transforms[obj.Name]
            node.translation.setValue(*(FreeCAD.Vector(*home) + shift))
            return
        home = self.placements[obj.Name]
        _set_placement(obj, FreeCAD.Placement(home.Base + shift, home.Rotation))

    def paint(self, obj, colour, transparency) -> None:
        """Paint ``obj``'s faces ``colour`` (None: their own) with ``transparency`` percent (None: their own);
        nothing without the GUI."""
        self._keep(obj)
        for material, colours, transparencies in self.materials[obj.Name]:
            _set_fields(material, [tuple(colour)] * len(colours) if colour is not None else colours,
                        [transparency / 100.0] * len(transparencies) if transparency is not None else transparencies)

    def apply(self, objects: dict[str, list], offsets: dict[str, tuple] | None, looks: dict[str, tuple]) -> None:
        """Move every component's objects by ``offsets`` (None: leave them where they are) and paint them as
        ``looks`` says (:func:`step_looks`, :func:`relation_looks`)."""
        for part, members in objects.items():
            for obj in members:
                if offsets is not None:
                    self.move(obj, offsets.get(part, (0.0, 0.0, 0.0)))
                if part in looks:
                    self.paint(obj, *looks[part])

    def restore(self) -> None:
        """Every saved transform, material and placement back as it was. Safe to call twice."""
        for node, home in self.transforms.values():
            node.translation.setValue(*home)
        for saved in self.materials.values():
            for material, colours, transparencies in saved:
                _set_fields(material, colours, transparencies)
        for name, placement in self.placements.items():
            if name in self.transforms:  # shown moved, never moved in the document
                continue
            obj = self.document.getObject(name)
            if obj is not None and not _same(obj.Placement, placement):
                _set_placement(obj, placement)
        self.placements, self.transforms, self.materials = {}, {}, {}


def _set_placement(obj, placement) -> None:
    """Set ``Placement`` without marking the document modified or the object for recompute (headless moves)."""
    touched = _touched(obj)
    obj.setPropertyStatus("Placement", "NoModify")
    try:
        obj.Placement = placement
    finally:
        obj.setPropertyStatus("Placement", "-NoModify")
    if not touched and _touched(obj):
        obj.purgeTouched()


def _same(a, b) -> bool:
    """Exactly the same placement (no tolerance: a restored placement must be the saved one, bit for bit)."""
    return tuple(a.Base) == tuple(b.Base) and tuple(a.Rotation.Q) == tuple(b.Rotation.Q)


def _touched(obj) -> bool:
    try:
        return bool(obj.isTouched())
    except AttributeError:
        return False
