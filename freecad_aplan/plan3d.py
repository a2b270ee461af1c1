"""The plan shown on the document itself, and put back exactly: parts moved to their exploded offsets, coloured
by their role in an operation or a relation, then restored.

What changes is kept in a :class:`SceneChanges`: before an object is first moved or painted, its
``Placement`` and, in the GUI, its view properties (:data:`VIEW_PROPERTIES`) are saved as they are;
:meth:`SceneChanges.restore` writes them back in an order that reproduces them exactly, clears the
recompute marks the moves left on objects that had none, and gives the document its modified flag back.
No transaction is opened: a move never becomes an undo step, and whatever the user does meanwhile is not
rolled back with it (an aborted transaction would take it too, and does nothing when undo is off).
The planner's exploded view (:func:`planner.api.plan_in_3d`) says which part goes where.
"""
from __future__ import annotations

import FreeCAD

__all__ = ["VIEW_PROPERTIES", "COLOURS", "SceneChanges", "component_objects", "extent", "bound_box",
           "step_looks", "relation_looks"]

#: The view properties saved before painting, in the order they are restored (ShapeColor resets DiffuseColor
#: and Transparency rewrites its alpha: DiffuseColor comes after both).
VIEW_PROPERTIES = ("ShapeColor", "Transparency", "DiffuseColor", "Visibility")

#: Colours (RGB 0..1) and transparencies (percent) of the roles.
COLOURS = {"moving": (1.0, 0.55, 0.0), "blocked": (0.85, 0.1, 0.1), "blocking": (0.1, 0.35, 0.9)}
DIMMED = {"fixed": 55, "idle": 85}


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


def bound_box(objects) -> "FreeCAD.BoundBox":
    """The global bounding box of the shapes of ``objects`` (objects without a shape are skipped)."""
    box = FreeCAD.BoundBox()
    for obj in objects:
        shape = getattr(obj, "Shape", None)
        if shape is not None and not shape.isNull():
            box.add(shape.BoundBox)
    return box


def extent(objects) -> float:
    """The diagonal of :func:`bound_box` (1.0 when nothing has a shape): how far an exploded part sits away."""
    box = bound_box(objects)
    return float(box.DiagonalLength) if box.isValid() and box.DiagonalLength > 0 else 1.0


def step_looks(roles: dict[str, str]) -> dict[str, tuple]:
    """Per part of an exploded step: ``(colour or None, transparency or None)``: the moving parts highlighted,
    the side they join dimmed a little, the others dimmed more."""
    return {p: (COLOURS["moving"], 0) if r == "moving" else (None, DIMMED[r]) for p, r in roles.items()}


def relation_looks(parts, blocked: str, blocking: str) -> dict[str, tuple]:
    """Per part for an obstruction relation: the blocked part red, the blocking part blue, the others dimmed."""
    return {p: (COLOURS["blocked"], 0) if p == blocked else (COLOURS["blocking"], 0) if p == blocking
            else (None, DIMMED["idle"]) for p in parts}


def _parent_rotation(obj) -> "FreeCAD.Rotation":
    """The rotation from ``obj``'s own frame to the global one (its containers'), so a global offset can be
    written into its local placement."""
    try:
        parent = obj.getGlobalPlacement().multiply(obj.Placement.inverse())
    except Exception:  # an object FreeCAD cannot place globally: take its placement as global
        return FreeCAD.Rotation()
    return parent.Rotation


class SceneChanges:
    """Objects moved and painted for a view of the plan, and how they were before (module docstring)."""

    def __init__(self, document):
        self.document = document
        self.placements: dict[str, FreeCAD.Placement] = {}
        self.views: dict[str, dict] = {}
        self.touched = {o.Name for o in document.Objects if _touched(o)}
        self.modified = _modified(document)

    def _keep(self, obj) -> None:
        if obj.Name not in self.placements:
            self.placements[obj.Name] = FreeCAD.Placement(obj.Placement)
            view = getattr(obj, "ViewObject", None)
            if view is not None:
                self.views[obj.Name] = {p: _copy(getattr(view, p)) for p in VIEW_PROPERTIES if hasattr(view, p)}

    def move(self, obj, offset) -> None:
        """Put ``obj`` at its saved placement shifted by the global vector ``offset``."""
        self._keep(obj)
        home = self.placements[obj.Name]
        shift = _parent_rotation(obj).inverted().multVec(FreeCAD.Vector(*offset))
        moved = FreeCAD.Placement(home.Base + shift, home.Rotation)
        if not _same(moved, obj.Placement):
            obj.Placement = moved

    def paint(self, obj, colour, transparency) -> None:
        """Give ``obj`` a colour (None: its own, as saved) and a transparency (None: its own); GUI only."""
        self._keep(obj)
        view = getattr(obj, "ViewObject", None)
        if view is None:
            return
        saved = self.views.get(obj.Name, {})
        if colour is not None:
            view.ShapeColor = tuple(colour)
        elif "ShapeColor" in saved:
            view.ShapeColor = saved["ShapeColor"]
            if "DiffuseColor" in saved:
                view.DiffuseColor = saved["DiffuseColor"]
        if hasattr(view, "Transparency"):
            view.Transparency = int(saved.get("Transparency", 0) if transparency is None else transparency)
        if hasattr(view, "Visibility"):
            view.Visibility = True

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
        """Every saved placement and view property back as it was; recompute marks and the document's modified
        flag as they were before the first change. Safe to call twice."""
        for name, placement in self.placements.items():
            obj = self.document.getObject(name)
            if obj is None:  # deleted meanwhile: nothing to put back
                continue
            if not _same(obj.Placement, placement):
                obj.Placement = placement
            view = getattr(obj, "ViewObject", None)
            for prop, value in self.views.get(name, {}).items():
                if view is not None and _copy(getattr(view, prop)) != value:
                    setattr(view, prop, value)
        for name in self.placements:
            obj = self.document.getObject(name)
            if obj is not None and name not in self.touched and _touched(obj):
                obj.purgeTouched()
        self.placements, self.views = {}, {}
        _set_modified(self.document, self.modified)


def _same(a, b) -> bool:
    """Exactly the same placement (no tolerance: a restored placement must be the saved one, bit for bit)."""
    return tuple(a.Base) == tuple(b.Base) and tuple(a.Rotation.Q) == tuple(b.Rotation.Q)


def _copy(value):
    """A view property's value as plain data (lists of tuples), comparable and safe to keep."""
    if isinstance(value, list):
        return [tuple(v) if isinstance(v, tuple) else v for v in value]
    return value


def _touched(obj) -> bool:
    try:
        return bool(obj.isTouched())
    except AttributeError:
        return False


def _modified(document) -> bool | None:
    """The GUI document's modified flag (None without the GUI)."""
    if not FreeCAD.GuiUp:
        return None
    import FreeCADGui

    gui = FreeCADGui.getDocument(document.Name)
    return bool(gui.Modified) if gui is not None else None


def _set_modified(document, modified: bool | None) -> None:
    if modified is None or not FreeCAD.GuiUp:
        return
    import FreeCADGui

    gui = FreeCADGui.getDocument(document.Name)
    if gui is not None and bool(gui.Modified) != modified:
        gui.Modified = modified
