"""The plan in the 3D view: the "Plan in 3D" task panel (an assembly sequence as an exploded view that
collapses step by step), a relation of the diagrams panel shown in 3D, the parts of an operation or a state
of the plan dialog highlighted.

The planner says what goes where (:func:`planner.api.plan_in_3d`); :class:`~freecad_aplan.gui.plan_view.PlanView`
shows it and restores everything when the selection changes, when a panel closes, when its widget goes away.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from .layout import button_rows, narrow_combo, panel_layout
from .plan_view import ARROW_NAME, PlanView, _view, restore_when_gone

__all__ = ["ARROW_NAME", "PARTS_TAB_LIMIT", "SEQUENCE_LIST_LIMIT", "Plan3DPanel", "PlanView", "add_parts_tab",
           "restore_when_gone"]

#: Up to this many full sequences the panel lists them; past it, a spin box over the rank.
SEQUENCE_LIST_LIMIT = 200
#: Rows of the plan dialog's operations-and-states tab at most (a large plan lists its first ones).
PARTS_TAB_LIMIT = 2000
#: Milliseconds between steps when playing.
PLAY_INTERVAL = 900


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
