"""Task panels and dialogs of the workbench: the intent tables, the plan report (and the diagrams table:
:mod:`freecad_aplan.gui.diagrams_panel`).

Each panel edits a copy of the analysis' intent and writes it back on OK as one undoable transaction
(:func:`freecad_aplan.intent.update_intent`); Cancel changes nothing.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui
from PySide import QtGui

from ..diagrams import relation_rows
from ..intent import BASE_PART_AUTO, IntentError, read_intent, update_intent
from .diagrams_panel import DiagramsPanel
from .layout import button_rows, narrow_combo, panel_layout, wrapped_label
from .tables import _check, _checked, _item, _table

__all__ = ["DiagramsPanel", "IntentPanel", "PlanDialog", "ImageDialog", "relation_rows"]


class IntentPanel:
    """Technical constraints and operation tags, as two tables, and the base part.

    Constraints: parts (comma-separated), the part they require, active. Operation tags: every operation of
    the plan without technical constraints, with its resolved tags; rows the designer changes are stored as
    tags, the others keep following the defaults. Base part (paper Sec. V): the part every assembly sequence
    of the decision model starts from; empty for none, ``auto`` for the most connected part, or a component.
    """

    def __init__(self, analysis, plan):
        self.analysis, self.plan = analysis, plan
        intent = read_intent(analysis)
        self.intent = intent
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanIntentPanel")
        self.form.setWindowTitle("APLAN: constraints, tags")
        layout = panel_layout(self.form)
        layout.addWidget(wrapped_label("Technical constraints: these parts only together with 'requires'"))
        self.constraints = _table(["parts", "requires", "active"], "AplanConstraintsTable", fit=(2,),
                                  tips={0: "parts, comma-separated"})
        for c in intent.technical_constraints:
            self._add_constraint(", ".join(c.get("parts", [])), c.get("requires", ""), c.get("active", True))
        layout.addWidget(self.constraints)
        add, remove = QtGui.QPushButton("Add constraint"), QtGui.QPushButton("Remove constraint")
        add.clicked.connect(lambda: self._add_constraint("", "", True))
        remove.clicked.connect(lambda: self.constraints.removeRow(self.constraints.currentRow()))
        layout.addWidget(button_rows(add, remove))
        layout.addWidget(wrapped_label("Operation tags: U unfavorable to humans, R robot-capable, and the tool"))
        self.tags = _table(["operation", "U", "R", "tool"], "AplanTagsTable", fit=(1, 2, 3),
                           tips={1: "unfavorable to humans", 2: "robot-capable", 3: "the tool the operation needs"})
        andor, tags = plan.andor, plan.tags
        self.defaults = []
        for j in range(len(andor.operations)):
            self.tags.insertRow(j)
            self.tags.setItem(j, 0, _item(andor.describe(j)))
            self.tags.setItem(j, 1, _check(bool(tags.unfavorable[j])))
            self.tags.setItem(j, 2, _check(bool(tags.robot[j])))
            self.tags.setItem(j, 3, _item(tags.tool[j] or "", editable=True))
            self.defaults.append((bool(tags.unfavorable[j]), bool(tags.robot[j]), tags.tool[j] or ""))
        layout.addWidget(self.tags)
        row = QtGui.QFormLayout()
        self.base_part = narrow_combo(QtGui.QComboBox())
        self.base_part.setObjectName("AplanBasePart")
        self.base_part.setEditable(True)
        self.base_part.setToolTip("The part every assembly sequence starts from (paper Sec. V): empty for none, "
                                  "auto for the most connected part, or a component")
        self.base_part.addItems(["", BASE_PART_AUTO, *plan.andor.parts])
        self.base_part.setEditText(intent.base_part)
        row.addRow("Base part", self.base_part)
        layout.addLayout(row)

    def _add_constraint(self, parts: str, requires: str, active: bool) -> None:
        row = self.constraints.rowCount()
        self.constraints.insertRow(row)
        self.constraints.setItem(row, 0, _item(parts, editable=True))
        self.constraints.setItem(row, 1, _item(requires, editable=True))
        self.constraints.setItem(row, 2, _check(active))

    def values(self) -> dict:
        """The intent fields the panel holds (technical_constraints, operations, tools, base_part)."""
        constraints = []
        for row in range(self.constraints.rowCount()):
            parts = [p.strip() for p in self.constraints.item(row, 0).text().split(",") if p.strip()]
            requires = self.constraints.item(row, 1).text().strip()
            if parts or requires:
                constraints.append({"parts": parts, "requires": requires,
                                    "active": _checked(self.constraints.item(row, 2))})
        andor = self.plan.andor
        shown = {frozenset(andor.inputs(j)) for j in range(len(andor.operations))}
        operations = [t for t in self.intent.operations  # tags of operations not shown here stay as they are
                      if frozenset(frozenset(s) for s in t.get("inputs", [])) not in shown]
        for j, default in enumerate(self.defaults):
            now = (_checked(self.tags.item(j, 1)), _checked(self.tags.item(j, 2)), self.tags.item(j, 3).text().strip())
            stored = next((t for t in self.intent.operations
                           if frozenset(frozenset(s) for s in t.get("inputs", [])) == frozenset(andor.inputs(j))), None)
            if now != default or stored is not None:
                tag = {"inputs": [sorted(s) for s in andor.inputs(j)], "unfavorable": now[0], "robot": now[1]}
                if now[2]:
                    tag["tool"] = now[2]
                operations.append(tag)
        tools = sorted({t["tool"] for t in operations if t.get("tool")} | set(self.intent.tools))
        return {"technical_constraints": constraints, "operations": operations, "tools": tools,
                "base_part": self.base_part.currentText().strip()}

    def accept(self) -> bool:
        from ..workflow import analysis_product

        try:
            update_intent(self.analysis, "edit constraints and tags", **self.values())
        except IntentError as exc:
            FreeCAD.Console.PrintError(f"APLAN: {exc}\n")
            return False
        try:
            analysis_product(self.analysis)
        except IntentError as exc:  # names a part that is not a component: take the change back, keep the panel
            self.analysis.Document.undo()
            FreeCAD.Console.PrintError(f"APLAN: {exc}\n")
            return False
        FreeCADGui.Control.closeDialog()
        return True

    def reject(self) -> bool:
        FreeCADGui.Control.closeDialog()
        return True


def _image_tab(path_or_reason: str) -> QtGui.QWidget:
    scroll = QtGui.QScrollArea()
    if path_or_reason.endswith(".png"):
        label = QtGui.QLabel()
        label.setPixmap(QtGui.QPixmap(path_or_reason))
    else:
        label = wrapped_label(path_or_reason)
        scroll.setWidgetResizable(True)  # the reason wraps at the dialog's width
    scroll.setWidget(label)
    return scroll


class PlanDialog(QtGui.QDialog):
    """The statistics of the plan (the figures of ``aplan stats``) and pictures of its three graphs."""

    def __init__(self, title: str, statistics: dict, images: dict, parent=None):
        super().__init__(parent)
        self.setObjectName("AplanPlanDialog")
        self.setWindowTitle(f"APLAN plan: {title}")
        self.resize(900, 650)
        layout = QtGui.QVBoxLayout(self)
        tabs = QtGui.QTabWidget()
        table = _table(["figure", "value"], "AplanStatisticsTable", fit=(0,))
        for row, (key, value) in enumerate(statistics.items()):
            table.insertRow(row)
            table.setItem(row, 0, _item(key))
            table.setItem(row, 1, _item(f"{value:,}" if isinstance(value, int) else str(value)))
        tabs.addTab(table, "Statistics")
        for key, name in (("andor", "AND/OR graph"), ("states", "State graph"), ("intentions", "Intention graph")):
            if key in images:
                tabs.addTab(_image_tab(images[key]), name)
        layout.addWidget(tabs)
        close = QtGui.QPushButton("Close")
        close.clicked.connect(self.close)
        layout.addWidget(close)


class ImageDialog(QtGui.QDialog):
    """A picture (the belief plot) with a caption."""

    def __init__(self, title: str, caption: str, path: str, parent=None):
        super().__init__(parent)
        self.setObjectName("AplanImageDialog")
        self.setWindowTitle(title)
        layout = QtGui.QVBoxLayout(self)
        layout.addWidget(wrapped_label(caption))
        layout.addWidget(_image_tab(path))
        self.resize(700, 600)
