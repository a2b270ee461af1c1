"""The plan in the 3D view: the "Plan in 3D" task panel (an assembly sequence as an exploded view that
collapses step by step), a relation of the diagrams panel shown in 3D, the parts of an operation or a state
of the plan dialog highlighted.

The planner says what goes where (:func:`planner.api.plan_in_3d`); :class:`PlanView` shows it with
:class:`freecad_aplan.plan3d.SceneChanges` (the view providers' Coin3D transforms and face materials, saved
first and put back exactly: the document itself never changes) and a temporary Coin3D arrow (never a
document object), and restores everything on :meth:`PlanView.restore`: when the selection changes, when a
panel closes, when its widget goes away.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from ..diagrams import relation_direction
from ..plan3d import (COLOURS, DIMMED, SceneChanges, bound_box, component_objects, extent, orthographic_fit,
                      relation_looks, step_looks)
from .layout import button_rows, narrow_combo, panel_layout

__all__ = ["ARROW_NAME", "PARTS_TAB_LIMIT", "SEQUENCE_LIST_LIMIT", "Plan3DPanel", "PlanView", "add_parts_tab",
           "restore_when_gone"]

#: The name of the arrow's Coin3D node (tests look for it in the scene graph).
ARROW_NAME = "AplanArrow"
#: Up to this many full sequences the panel lists them; past it, a spin box over the rank.
SEQUENCE_LIST_LIMIT = 200
#: Rows of the plan dialog's operations-and-states tab at most (a large plan lists its first ones).
PARTS_TAB_LIMIT = 2000
#: Milliseconds between steps when playing.
PLAY_INTERVAL = 900
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


def _text_box(name: str, lines: int) -> QtGui.QPlainTextEdit:
    """Read-only text wrapped to the panel's width, ``lines`` high (a scroll bar if it needs more): unlike a
    word-wrapped label it never asks the task view for more room than it has."""
    box = QtGui.QPlainTextEdit()
    box.setObjectName(name)
    box.setReadOnly(True)
    box.setLineWrapMode(QtGui.QPlainTextEdit.WidgetWidth)
    box.setFrameShape(QtGui.QFrame.NoFrame)
    box.viewport().setAutoFillBackground(False)
    margins = box.contentsMargins().top() + box.contentsMargins().bottom() + 2 * box.document().documentMargin()
    box.setFixedHeight(int(lines * box.fontMetrics().lineSpacing() + margins + 4))
    box.setMinimumWidth(0)
    return box


class Plan3DPanel:
    """The "Plan in 3D" task panel: a full assembly sequence (listed, chosen by rank, or the one a session log
    recorded) stepped through in the 3D view: Back, Forward, Play. Closing it restores the document's view."""

    def __init__(self, analysis, product, base_part: str | None = None):
        from planner import api

        from ..intent import read_intent

        self.analysis, self.base_part = analysis, base_part
        self.plan = api.plan_of(product)
        self.count, self.sequences = api.sequence_choices(self.plan, base_part, SEQUENCE_LIST_LIMIT)
        self.view = PlanView(analysis.Document, read_intent(analysis).diagrams)
        self.exploded, self.k, self.title = None, 0, ""
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanPlan3DPanel")
        self.form.setWindowTitle("APLAN: plan in 3D")
        layout = panel_layout(self.form)
        intro = _text_box("AplanPlan3DIntro", 4)
        intro.setPlainText(f"{self.count:,} full assembly sequences"
                           + (f" from the base part {base_part}" if base_part else "")
                           + ". Orange: the parts that move; the arrow: the way they go in. Closing restores "
                             "the view.")
        layout.addWidget(intro)
        self.chooser = self._chooser()
        layout.addWidget(self.chooser)
        log = QtGui.QPushButton("From a session log...")
        log.setObjectName("AplanSequenceFromLog")
        log.clicked.connect(lambda: self.ask_log())
        layout.addWidget(log)
        self.buttons = {}
        for name, text, action in (("Back", "Back", self.back), ("Forward", "Forward", self.forward),
                                   ("Play", "Play", self.play)):
            button = QtGui.QPushButton(text)
            button.setObjectName(f"AplanStep{name}")
            button.clicked.connect(lambda checked=False, act=action: act())
            self.buttons[name] = button
        layout.addWidget(button_rows(*self.buttons.values()))  # above the step text: in view when the view is short
        self.label = _text_box("AplanStepLabel", 7)
        layout.addWidget(self.label)
        layout.addStretch(1)
        self.timer = QtCore.QTimer(self.form)
        self.timer.setInterval(PLAY_INTERVAL)
        self.timer.timeout.connect(self._tick)
        restore_when_gone(self.form, self.view)
        self.choose(0)

    def _chooser(self) -> QtGui.QWidget:
        if self.count <= SEQUENCE_LIST_LIMIT:
            combo = QtGui.QComboBox()
            combo.setObjectName("AplanSequenceChooser")
            describe = self.plan.andor.describe
            for rank, operations in enumerate(self.sequences):
                combo.addItem(f"{rank}: " + " ; ".join(describe(o) for o in operations))
            combo.currentIndexChanged.connect(lambda rank: self.choose(int(rank)))
            # The operations are long: the closed box shows what fits (its tooltip and the list show all), so
            # that the panel keeps the task view's width.
            narrow_combo(combo)
            combo.setToolTip("Full assembly sequences by rank: their operations in order")
            return combo
        spin = QtGui.QSpinBox()
        spin.setObjectName("AplanSequenceRank")
        spin.setRange(0, min(self.count - 1, 2**31 - 1))
        spin.setPrefix("sequence rank ")
        spin.valueChanged.connect(lambda rank: self.choose(int(rank)))
        return spin

    def choose(self, rank: int) -> None:
        """Show the sequence of rank ``rank`` from its first step."""
        from planner import api

        listed = self.sequences[rank] if 0 <= rank < len(self.sequences) else int(rank)  # listed: no ranking again
        self.use(api.plan_in_3d(self.plan, listed, self.view.spacing, self.base_part), f"sequence {rank}")

    def use(self, exploded, title: str) -> None:
        self.timer.stop()
        self.exploded, self.title = exploded, title
        self.show(0)  # each step fits the view to its operation

    def load_log(self, path: str) -> bool:
        """Show the sequence the session log ``path`` recorded; say why not in the panel otherwise."""
        from planner import api
        from planner.errors import PlannerError

        try:
            operations, logged = api.sequence_from_log(path, self.plan)
            exploded = api.plan_in_3d(self.plan, operations, self.view.spacing, self.base_part)
        except PlannerError as exc:
            self.label.setPlainText(f"cannot show that log: {exc}")
            FreeCAD.Console.PrintError(f"APLAN: {exc}\n")
            return False
        notes = []
        if not logged.complete:
            notes.append(f"the session stopped after {len(logged.operations)} operations; the rest is the first "
                         "way to finish")
        if logged.ambiguous:
            notes.append("another sequence explains the log too")
        self.use(exploded, "the logged sequence" + (f" ({'; '.join(notes)})" if notes else ""))
        return True

    def ask_log(self) -> None:
        path, _ = QtGui.QFileDialog.getOpenFileName(FreeCADGui.getMainWindow(), "Session log", "",
                                                    "Session log (*.jsonl *.log);;All files (*)")
        if path:
            self.load_log(path)

    def show(self, k: int) -> None:
        """Step ``k`` (0 .. the number of operations: the assembled product)."""
        exploded = self.exploded
        self.k = max(0, min(int(k), len(exploded.steps)))
        self.view.show_step(exploded, self.k)
        total = len(exploded.steps)
        if self.k == total:
            text = f"{self.title}: assembled ({total} operations)."
        else:
            step = exploded.steps[self.k]
            moving = ", ".join(sorted(step.moving))
            verb = "moves" if len(step.moving) == 1 else "move"
            text = (f"{self.title}, step {self.k + 1} of {total}: {step.description}. {moving} {verb} in along "
                    f"{step.direction.reverse.name} (it leaves freely along {step.direction.name}).")
        self.label.setPlainText(text)
        self.buttons["Back"].setEnabled(self.k > 0)
        self.buttons["Forward"].setEnabled(self.k < total)
        _redraw(self.analysis.Document)

    def forward(self) -> None:
        self.show(self.k + 1)

    def back(self) -> None:
        self.show(self.k - 1)

    def play(self) -> None:
        """From the first step (or where it is, unless at the end), one step every :data:`PLAY_INTERVAL` ms."""
        if self.timer.isActive():
            self.timer.stop()
            return
        if self.k >= len(self.exploded.steps):
            self.show(0)
        self.timer.start()

    def _tick(self) -> None:
        if self.k >= len(self.exploded.steps):
            self.timer.stop()
            return
        self.forward()

    def close(self) -> bool:
        self.timer.stop()
        self.view.restore()
        self.view.restore_camera()
        FreeCADGui.Control.closeDialog()
        return True

    def accept(self) -> bool:
        return self.close()

    def reject(self) -> bool:
        return self.close()


def _redraw(document) -> None:
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
        _redraw(analysis.Document)

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
