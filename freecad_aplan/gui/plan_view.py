"""A plan shown in the 3D view (:class:`PlanView`): the parts of a step moved, coloured and dimmed through
:class:`freecad_aplan.plan3d.SceneChanges` (the view providers' Coin3D transforms and face materials, saved
first and put back exactly: the document itself never changes) and a temporary Coin3D arrow (never a document
object), restored on :meth:`PlanView.restore`: when the selection changes, when a panel closes, when its
widget goes away. The panels of :mod:`freecad_aplan.gui.plan3d` and the diagrams panel drive it.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui

from ..diagrams import relation_direction
from ..plan3d import (COLOURS, DIMMED, SceneChanges, bound_box, component_objects, extent, orthographic_fit,
                      relation_looks, step_looks)

__all__ = ["ARROW_NAME", "PlanView", "restore_when_gone"]

#: The name of the arrow's Coin3D node (tests look for it in the scene graph).
ARROW_NAME = "AplanArrow"
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
    :class:`~freecad_aplan.plan3d.SceneChanges`) and at most one arrow; :meth:`restore` undoes all of it."""

    def __init__(self, document, diagrams: dict):
        self.document = document
        self.objects = component_objects(document, diagrams)
        self.spacing = extent([o for members in self.objects.values() for o in members])
        self.scene: SceneChanges | None = None
        self.arrow = None
        self.camera: str | None = None  # the user's camera, while :meth:`fit` has changed it

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

    def show_step(self, exploded, k: int) -> None:
        """Step ``k`` of an :class:`~planner.assembly.explode.ExplodedView`: every part at its offset, the moving
        ones highlighted, the rest dimmed, an arrow along the insertion direction, the view fitted to the
        operation (the moving side, the side it joins and the arrow); after the last step the assembled product
        as it is, fitted whole."""
        done = k >= len(exploded.steps)  # the assembled product, in its own colours
        looks = {p: (None, None) for p in self.objects} if done else step_looks(exploded.roles(k))
        self._begin().apply(self.objects, exploded.offsets[k], looks)
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
        # Fitted to what the step is about: fitted to every part, the exploded product is a long thin line in
        # which the moving part is a few pixels (issue 22); the dimmed idle parts may leave the view.
        self.fit(exploded.offsets[k], set(step.moving) | set(step.fixed), [start, start + reverse])

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

    def fit(self, offsets: dict[str, tuple], parts=None, points=()) -> None:
        """Fit the 3D view to ``parts`` (default: all) moved by ``offsets`` and to ``points`` (FreeCAD vectors),
        keeping the view's direction: an orthographic camera by :func:`~freecad_aplan.plan3d.orthographic_fit`
        (their projected extent, 10 % more), a perspective one by Coin's ``viewBoundingBox`` (the bounding
        sphere). The user's camera is kept for :meth:`restore_camera`. Cost: eight corners per part."""
        from pivy import coin

        view = _view(self.document)
        corners = list(points)
        for part in self.objects if parts is None else parts:
            box = bound_box(self.objects.get(part, []))
            if box.isValid():
                shift = FreeCAD.Vector(*offsets.get(part, (0.0, 0.0, 0.0)))
                corners += [box.getPoint(i) + shift for i in range(8)]
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


def restore_when_gone(widget, view: PlanView) -> None:
    """Restore ``view`` when ``widget`` is destroyed (a task panel closed by another command)."""
    widget.destroyed.connect(lambda *_: (view.restore(), view.restore_camera()))


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
