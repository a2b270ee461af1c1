"""The plan in the 3D view: what the "Plan in 3D" task panel shows (:mod:`.plan3d_panel`: an assembly sequence
as an exploded view that collapses step by step), a relation of the diagrams panel shown in 3D, the parts of
an operation or a state of the plan dialog highlighted.

The planner says what goes where (:func:`planner.api.plan_in_3d`); :class:`PlanView` shows it with
:class:`freecad_aplan.plan3d.SceneChanges` (the view providers' Coin3D transforms and face materials, saved
first and put back exactly: the document itself never changes) and a temporary Coin3D arrow (never a
document object), and restores everything on :meth:`PlanView.restore`: when the selection changes, when a
panel closes, when its widget goes away.
"""
from __future__ import annotations

import os
import tempfile

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from ..diagrams import relation_direction
from ..plan3d import (COLOURS, DIMMED, SceneChanges, bound_box, component_objects, extent, orthographic_fit,
                      outline_points, relation_looks, step_looks)

__all__ = ["ARROW_NAME", "PARTS_TAB_LIMIT", "PlanView", "add_parts_tab", "redraw", "restore_when_gone"]

#: The name of the arrow's Coin3D node (tests look for it in the scene graph).
ARROW_NAME = "AplanArrow"
#: Rows of the plan dialog's operations-and-states tab at most (a large plan lists its first ones).
PARTS_TAB_LIMIT = 2000
#: Colours of the blocks of a state (multi-part subassemblies), in turn.
PALETTE = ((1.0, 0.55, 0.0), (0.1, 0.35, 0.9), (0.15, 0.65, 0.2), (0.75, 0.2, 0.75), (0.85, 0.1, 0.1))


def _arrow(start, vector, colour):
    """A Coin3D arrow (an ``SoSeparator`` named :data:`ARROW_NAME`) from ``start`` along ``vector`` (its
    length): a line and a cone at the tip."""
    from pivy import coin

    start, vector = FreeCAD.Vector(*start), FreeCAD.Vector(*vector)
    length = vector.Length
    unit = FreeCAD.Vector(vector).normalize()
    head = min(0.25 * length, 0.06 * length + 4.0)
    tip_base = start + unit * (length - head)
    root = coin.SoSeparator()
    root.setName(ARROW_NAME)
    if hasattr(coin, "SoDepthBuffer"):  # drawn over the parts: it often runs through one
        depth = coin.SoDepthBuffer()
        depth.test = False
        root.addChild(depth)
    colour_node = coin.SoBaseColor()
    colour_node.rgb.setValue(*colour)
    root.addChild(colour_node)
    style = coin.SoDrawStyle()
    style.lineWidth = 4
    root.addChild(style)
    points = coin.SoCoordinate3()
    points.point.setValues(0, 2, [tuple(start), tuple(tip_base)])
    root.addChild(points)
    root.addChild(coin.SoLineSet())
    move = coin.SoTransform()
    move.translation.setValue(*(tip_base + unit * (head / 2)))
    move.rotation.setValue(coin.SbRotation(coin.SbVec3f(0, 1, 0), coin.SbVec3f(*unit)))
    root.addChild(move)
    cone = coin.SoCone()
    cone.height, cone.bottomRadius = head, head / 3
    root.addChild(cone)
    return root


class PlanView:
    """What the 3D view shows of the plan, on one document: moved and painted parts (a
    :class:`~freecad_aplan.plan3d.SceneChanges`) and at most one arrow; :meth:`restore` undoes all of it.
    ``members``: the plan is of one level (:func:`freecad_aplan.sessions.member_parts`)."""

    def __init__(self, document, diagrams: dict, members: dict[str, tuple[str, ...]] | None = None):
        self.document, self.diagrams = document, diagrams
        self.scene: SceneChanges | None = None
        self.arrow = None
        self.camera: str | None = None  # the user's camera, while :meth:`fit` has changed it
        self.overview = None  # the last step's picture of where the moving parts go (a QImage), if asked for
        self.use_members(members)

    def use_members(self, members: dict[str, tuple[str, ...]] | None) -> None:
        """Show the plan of one level: ``members`` maps each member to the components it stands for (a
        subassembly moves as one block; the components of other levels stay where they are, dimmed); None:
        the product planned flat, one member per component."""
        self.restore()
        components = component_objects(self.document, self.diagrams)
        self.objects, self.others = components, {}
        if members is not None:
            self.objects = {m: [o for p in parts for o in components.get(p, [])] for m, parts in members.items()}
            self.objects = {m: objects for m, objects in self.objects.items() if objects}
            held = {p for parts in members.values() for p in parts}
            self.others = {p: objects for p, objects in components.items() if p not in held}
        self.spacing = extent([o for members in self.objects.values() for o in members])

    def _begin(self) -> SceneChanges:
        global _SHOWING
        self.restore()
        if _SHOWING is not None:  # another panel's view (the plan dialog beside a task panel): one at a time
            _SHOWING.restore()
        self.scene = SceneChanges(self.document)
        _SHOWING = self
        return self.scene

    def _add_arrow(self, start, vector, colour) -> None:
        view = _view(self.document)
        if view is None or FreeCAD.Vector(*vector).Length == 0:
            return
        self.arrow = _arrow(start, vector, colour)
        view.getSceneGraph().addChild(self.arrow)

    def _centre(self, parts) -> FreeCAD.Vector:
        return bound_box([o for p in parts for o in self.objects.get(p, [])]).Center

    def show_step(self, exploded, k: int, overview_width: int | None = None) -> None:
        """Step ``k`` of an :class:`~planner.assembly.explode.ExplodedView`: every part at its offset, the moving
        ones highlighted, the rest dimmed, an arrow along the insertion direction, the view fitted to the
        moving parts; after the last step the assembled product as it is, fitted whole.

        ``overview_width``: also render, ``overview_width`` pixels wide at the view's aspect, the same scene
        fitted to both sides of the operation (:attr:`overview`, a ``QImage``; None after the last step): the
        parts the moving ones join, which the view fitted to the moving parts leaves out (the exploded offsets
        put them about a product's length away). Cost: one more off-screen rendering."""
        self.overview = None
        done = k >= len(exploded.steps)  # the assembled product, in its own colours
        looks = {p: (None, None) for p in self.objects} if done else step_looks(exploded.roles(k))
        self._begin().apply({**self.others, **self.objects}, exploded.offsets[k],
                            {**{p: (None, DIMMED["idle"]) for p in self.others}, **looks})
        if done:
            self.fit(exploded.offsets[k])
            return
        step = exploded.steps[k]
        # The moving parts sit together (they were joined before), shifted by one offset from where their
        # shapes are.
        shift = FreeCAD.Vector(*exploded.offsets[k][next(iter(step.moving))])
        start = self._centre(step.moving) + shift
        reverse = FreeCAD.Vector(*(-c * 0.8 * exploded.spacing for c in step.direction.vector))
        self._add_arrow(start, tuple(reverse), COLOURS["moving"])
        # Fitted to the parts that move: fitted to every part, the exploded product is a long thin line in which
        # the moving part is a few pixels (issue 22), and fitted to the side they join too, a small part still
        # was (issue 24); the arrow and the other parts may leave the view, its start stays in. Where they go (the
        # side they join, in its own colours) is the overview's, fitted to the operation.
        if overview_width:
            self.fit(exploded.offsets[k], set(step.moving) | set(step.fixed), [start], outline=True)
            self.overview = _render(self.document, overview_width)
        self.fit(exploded.offsets[k], set(step.moving), [start], outline=True)

    def show_relation(self, kind: str, first: str, second: str) -> None:
        """A row of the diagrams table: ``first`` (blocked, red) and ``second`` (blocking, blue), the others
        dimmed, an arrow from the blocked part along the direction; a contact: the two parts, no arrow."""
        self._begin().apply(self.objects, None, relation_looks(self.objects, first, second))
        direction = relation_direction(kind)
        if direction is not None:
            self._add_arrow(self._centre([first]), tuple(0.5 * self.spacing * c for c in direction),
                            COLOURS["blocked"])

    def show_parts(self, groups: list[frozenset[str]]) -> None:
        """Highlight each group of parts in its own colour (an operation's two inputs, a state's subassemblies
        of two or more parts) and dim the others."""
        looks = {p: (None, DIMMED["idle"]) for p in self.objects}
        for colour, group in zip(PALETTE * (len(groups) // len(PALETTE) + 1), groups):
            looks.update({p: (colour, 0) for p in group})
        self._begin().apply(self.objects, None, looks)

    def fit(self, offsets: dict[str, tuple], parts=None, points=(), outline: bool = False) -> None:
        """Fit the 3D view to ``parts`` (default: all) moved by ``offsets`` and to ``points`` (FreeCAD vectors),
        keeping the view's direction: an orthographic camera by :func:`~freecad_aplan.plan3d.orthographic_fit`
        (their projected extent, 10 % more), a perspective one by Coin's ``viewBoundingBox`` (the bounding
        sphere). ``outline``: fitted to points on the parts' edges (:func:`~freecad_aplan.plan3d.outline_points`)
        rather than their bounding boxes' corners. The user's camera is kept for :meth:`restore_camera`. Cost:
        eight corners per part, or a dozen points per edge with ``outline``."""
        from pivy import coin

        view = _view(self.document)
        corners = list(points)
        for part in self.objects if parts is None else parts:
            objects = self.objects.get(part, [])
            box = bound_box(objects)
            if box.isValid():
                shift = FreeCAD.Vector(*offsets.get(part, (0.0, 0.0, 0.0)))
                drawn = outline_points(objects) if outline else []
                corners += [p + shift for p in drawn] or [box.getPoint(i) + shift for i in range(8)]
        if view is None or not corners:
            return
        if self.camera is None:
            self.camera = view.getCamera()
        _end_camera_animation(view)
        width, height = view.getSize()
        aspect = width / max(height, 1)
        camera = view.getCameraNode()
        if not camera.isOfType(coin.SoOrthographicCamera.getClassTypeId()):
            box = FreeCAD.BoundBox()
            for corner in corners:
                box.add(corner)
            camera.viewBoundingBox(coin.SbBox3f(box.XMin, box.YMin, box.ZMin, box.XMax, box.YMax, box.ZMax),
                                   aspect, 1.0)
            return
        rotation = camera.orientation.getValue()
        axes = [FreeCAD.Vector(*rotation.multVec(coin.SbVec3f(*a)).getValue())
                for a in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]  # right, up, towards the viewer
        position, focal, height = orthographic_fit(axes, corners, aspect)
        camera.position.setValue(*position)
        camera.focalDistance, camera.height = focal, height
        # The viewer sets the clipping planes at its next redraw; until then (a picture saved at once) the old
        # ones would clip what the camera now looks at. The fitted parts lie from 2/3 to 4/3 of the focal
        # distance in front of it: planes far around them.
        camera.nearDistance, camera.farDistance = 1e-3 * focal, 1e3 * focal

    def restore_camera(self) -> None:
        """The user's camera back, if :meth:`fit` changed it."""
        view = _view(self.document)
        if view is not None and self.camera is not None:
            view.setCamera(self.camera)
        self.camera = None

    def restore(self) -> None:
        """Everything back as it was: placements, colours, the arrow removed. Safe to call at any time."""
        global _SHOWING
        if _SHOWING is self:
            _SHOWING = None
        if self.arrow is not None:
            view = _view(self.document)
            if view is not None:
                view.getSceneGraph().removeChild(self.arrow)
            self.arrow = None
        if self.scene is not None:
            scene, self.scene = self.scene, None
            try:
                scene.restore()
            except ReferenceError:  # the document was closed: nothing left to put back
                pass


#: The :class:`PlanView` showing something now, if any: two views never paint at once (each saves what it finds).
_SHOWING: PlanView | None = None


def _view(document):
    """The 3D view of ``document`` (None when it has none)."""
    try:
        gui = FreeCADGui.getDocument(document.Name)
        return gui.ActiveView if gui is not None and hasattr(gui.ActiveView, "getSceneGraph") else None
    except (ReferenceError, RuntimeError, NameError, AttributeError):  # a closed document
        return None


def _render(document, width: int):
    """The 3D view of ``document`` rendered off screen, ``width`` pixels wide at the view's aspect, on white (a
    ``QImage``; None without a view). The view's own picture does not change. Cost: one rendering."""
    view = _view(document)
    if view is None:
        return None
    size = view.getSize()
    handle, path = tempfile.mkstemp(prefix="aplan-overview-", suffix=".png")
    os.close(handle)
    try:
        view.saveImage(path, int(width), max(1, int(width * size[1] / max(size[0], 1))), "White")
        image = QtGui.QImage(path)
        return None if image.isNull() else image
    finally:
        os.remove(path)


def restore_when_gone(widget, view: PlanView) -> None:
    """Restore ``view`` when ``widget`` is destroyed (a task panel closed by another command)."""
    widget.destroyed.connect(lambda *_: (view.restore(), view.restore_camera()))


def redraw(document) -> None:
    view = _view(document)
    if view is not None:
        view.redraw()


def add_parts_tab(dialog, plan, analysis) -> QtGui.QTableWidget:
    """Add to the plan dialog a tab listing the plan's operations and assembly states; selecting a row
    highlights its parts in the 3D view (an operation: its two inputs; a state: its subassemblies), restored
    on the next selection and when the dialog closes."""
    from ..intent import read_intent

    view = PlanView(analysis.Document, read_intent(analysis).diagrams)
    andor, states = plan.andor, plan.states
    operations = range(min(len(andor.operations), PARTS_TAB_LIMIT))
    rows = [("operation", andor.describe(j), [frozenset(s) for s in andor.inputs(j)]) for j in operations]
    rows += [("state", states.describe(s), [andor.parts_of(b) for b in states.subassemblies_of(s)
                                            if len(andor.parts_of(b)) > 1])
             for s in range(min(states.n_states, PARTS_TAB_LIMIT - len(rows)))]
    left = len(andor.operations) + states.n_states - len(rows)
    if left:
        rows.append(("...", f"{left:,} more operations and states, not listed", []))
    table = QtGui.QTableWidget(len(rows), 2)
    table.setObjectName("AplanPlanPartsTable")
    table.setHorizontalHeaderLabels(["kind", "parts"])
    table.horizontalHeader().setStretchLastSection(True)
    table.verticalHeader().setVisible(False)
    table.setWordWrap(True)
    table.setSelectionBehavior(QtGui.QAbstractItemView.SelectRows)
    table.setSelectionMode(QtGui.QAbstractItemView.SingleSelection)
    for row, (kind, text, _) in enumerate(rows):
        for column, value in enumerate((kind, text)):
            item = QtGui.QTableWidgetItem(value)
            item.setFlags(item.flags() & ~QtCore.Qt.ItemIsEditable)
            table.setItem(row, column, item)

    def selected() -> None:
        chosen = table.selectionModel().selectedRows()
        if not chosen:
            view.restore()
        else:
            view.show_parts(rows[chosen[0].row()][2])
        redraw(analysis.Document)

    table.itemSelectionChanged.connect(selected)
    tabs = dialog.findChild(QtGui.QTabWidget)
    tabs.addTab(table, "Operations and states (3D)")
    dialog.finished.connect(lambda *_: view.restore())
    restore_when_gone(table, view)
    dialog.plan_view = view  # kept with the dialog
    return table


def _end_camera_animation(view) -> None:
    """End a camera animation still running (a standard view just chosen turns the camera over a few tenths of
    a second): it would go on moving the camera after a fit. Setting the orientation it has reached with the
    animation off stops it there (FreeCAD's navigation unschedules a running turn first)."""
    try:
        if not view.isAnimationEnabled():
            return
        view.setAnimationEnabled(False)
        try:
            view.setCameraOrientation(view.getCameraOrientation())
        finally:
            view.setAnimationEnabled(True)
    except (AttributeError, RuntimeError):  # a view without animations (another FreeCAD): nothing runs
        return
