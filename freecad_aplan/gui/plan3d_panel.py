"""The "Plan in 3D" task panel: a full assembly sequence (listed, chosen by rank, or the one a session log
recorded) stepped through in the 3D view, Back, Forward, Play; for a product of several workstations, of
the level chosen in its level selector (each level's plan: its members, a subassembly moving as one block).
What the view shows is :class:`~freecad_aplan.gui.plan3d.PlanView`'s; closing the panel restores it.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from ..sessions import base_part_in, level_choices, level_of, member_parts
from .layout import button_rows, narrow_combo, panel_layout
from .plan3d import PlanView, redraw, restore_when_gone

__all__ = ["OVERVIEW_WIDTH", "PLAY_INTERVAL", "SEQUENCE_LIST_LIMIT", "Plan3DPanel"]

#: Up to this many full sequences the panel lists them; past it, a spin box over the rank.
SEQUENCE_LIST_LIMIT = 200
#: Milliseconds between steps when playing.
PLAY_INTERVAL = 900
#: Pixels across of each step's overview as rendered (shown at the panel's width).
OVERVIEW_WIDTH = 480


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


class _Picture(QtGui.QLabel):
    """A picture at the label's width, scaled again when the label is resized (a scroll bar appearing in the
    task view narrows it); it never asks for more width than the panel has."""

    def __init__(self):
        super().__init__()
        self.image = None
        self.setSizePolicy(QtGui.QSizePolicy.Ignored, QtGui.QSizePolicy.Fixed)

    def show_image(self, image, width: int) -> None:
        """Show ``image`` (a ``QImage``; None: nothing) ``width`` pixels wide at most."""
        self.image = image
        if image is None:
            self.clear()
            self.setFixedHeight(0)
            return
        picture = QtGui.QPixmap.fromImage(image).scaledToWidth(max(1, min(width, image.width())),
                                                                QtCore.Qt.SmoothTransformation)
        self.setPixmap(picture)
        self.setFixedHeight(picture.height())

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        shown = self.pixmap()
        if self.image is not None and shown is not None and shown.width() != min(self.width(), self.image.width()):
            self.show_image(self.image, self.width())


class Plan3DPanel:
    """The "Plan in 3D" task panel (module docstring) of ``product`` (the analysis' resolved product)."""

    def __init__(self, analysis, product, base_part: str | None = None):
        from ..intent import read_intent

        self.analysis, self.product, self.base_part = analysis, product, base_part
        self.diagrams = read_intent(analysis).diagrams
        self.levels = level_choices(product)
        self.view, self.exploded, self.k, self.title = None, None, 0, ""
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanPlan3DPanel")
        self.form.setWindowTitle("APLAN: plan in 3D")
        self.layout = layout = panel_layout(self.form)
        self.level = None
        if len(self.levels) > 1:  # several workstations: one level's plan at a time, bottom-up
            self.level = narrow_combo(QtGui.QComboBox())
            self.level.setObjectName("AplanPlan3DLevel")
            self.level.setToolTip("The workstation (level) whose plan is shown: its members, a subassembly as one "
                                  "block")
            for choice in self.levels:
                self.level.addItem(choice.label, choice.id)
            self.level.currentIndexChanged.connect(lambda index: self.set_level(self.level.itemData(int(index))))
            layout.addWidget(self.level)
        self.intro = _text_box("AplanPlan3DIntro", 4)
        layout.addWidget(self.intro)
        self.chooser = QtGui.QWidget()
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
        self.overview = _Picture()  # where the moving parts go: the view fitted to both sides of the operation
        self.overview.setObjectName("AplanStepOverview")
        self.overview.setToolTip("Where it goes: the operation's two sides, the moving parts orange, the side "
                                 "they join see-through in its own colours, the arrow the way they go in")
        self.overview.setAlignment(QtCore.Qt.AlignHCenter | QtCore.Qt.AlignTop)
        layout.addWidget(self.overview)
        layout.addStretch(1)
        self.timer = QtCore.QTimer(self.form)
        self.timer.setInterval(PLAY_INTERVAL)
        self.timer.timeout.connect(self._tick)
        self.set_level(self.levels[0].id)

    def set_level(self, level: str | None) -> None:
        """Plan level ``level`` (None: the product planned flat) and show its first sequence from step 0."""
        from planner import api

        self.timer.stop()
        level_product = level_of(self.product, level)
        base = self.base_part if level is None else base_part_in(level_product, self.base_part)
        self.level_id, self.level_base = level, base
        self.plan = api.plan_of(level_product)
        self.count, self.sequences = api.sequence_choices(self.plan, base, SEQUENCE_LIST_LIMIT)
        members = None if level is None else member_parts(self.product, level)
        if self.view is None:
            self.view = PlanView(self.analysis.Document, self.diagrams, members)
            restore_when_gone(self.form, self.view)
        else:  # the same view (restore_when_gone holds it) and the user's camera it keeps
            self.view.use_members(members)
        where = f"Level {level}: " if level is not None else ""
        self.intro.setPlainText(f"{where}{self.count:,} full assembly sequences"
                                + (f" from the base part {base}" if base else "")
                                + ". Orange: the parts that move; the arrow: the way they go in. Closing restores "
                                  "the view.")
        chooser = self._chooser()
        self.layout.replaceWidget(self.chooser, chooser)
        self.chooser.setParent(None)  # off the panel now: a hidden child would still be laid out by nobody
        self.chooser.deleteLater()
        self.chooser = chooser
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
        self.use(api.plan_in_3d(self.plan, listed, self.view.spacing, self.level_base), f"sequence {rank}")

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
            exploded = api.plan_in_3d(self.plan, operations, self.view.spacing, self.level_base)
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
        self.view.show_step(exploded, self.k, OVERVIEW_WIDTH)
        self._show_overview()
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
        redraw(self.analysis.Document)

    def _show_overview(self) -> None:
        """The step's overview (:attr:`PlanView.overview`) at the panel's width, or nothing (assembled)."""
        self.overview.show_image(self.view.overview, self.overview.width() if self.form.isVisible() else 218)

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
