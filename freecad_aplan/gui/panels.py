"""Task panels and dialogs of the workbench: the diagrams table, the intent tables, the plan report.

Each panel edits a copy of the analysis' intent and writes it back on OK as one undoable transaction
(:func:`freecad_aplan.intent.update_intent`); Cancel changes nothing.
"""
from __future__ import annotations

import json

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from ..diagrams import RELATION_KINDS, RelationError, describe_relation, edited_diagrams, relation_rows
from ..intent import BASE_PART_AUTO, IntentError, read_intent, update_intent
from .layout import button_rows, fit_columns, narrow_combo, panel_layout, stacked_field, wrapped_label

__all__ = ["DiagramsPanel", "IntentPanel", "PlanDialog", "ImageDialog", "relation_rows"]


def _direction_name(direction) -> str:
    """A direction as the diagrams table names it: ``+X``, or the vector as JSON."""
    return direction if isinstance(direction, str) else json.dumps(direction)


def _table(headers: list[str], name: str, fit: tuple[int, ...] = (), tips: dict[int, str] | None = None
           ) -> QtGui.QTableWidget:
    """A table whose columns share the panel's width (:func:`.layout.fit_columns`); ``tips``: header tooltips
    (the long name of a column whose header is kept short)."""
    table = QtGui.QTableWidget(0, len(headers))
    table.setObjectName(name)
    table.setHorizontalHeaderLabels(headers)
    for column, tip in (tips or {}).items():
        table.horizontalHeaderItem(column).setToolTip(tip)
    fit_columns(table, fit)
    table.verticalHeader().setVisible(False)
    return table


def _item(text: str, editable: bool = False) -> QtGui.QTableWidgetItem:
    item = QtGui.QTableWidgetItem(text)
    item.setToolTip(text)  # the text on one line, where a narrow column wraps it
    if not editable:
        item.setFlags(item.flags() & ~QtCore.Qt.ItemIsEditable)
    return item


def _check(value: bool) -> QtGui.QTableWidgetItem:
    item = QtGui.QTableWidgetItem()
    item.setFlags((item.flags() | QtCore.Qt.ItemIsUserCheckable) & ~QtCore.Qt.ItemIsEditable)
    item.setCheckState(QtCore.Qt.Checked if value else QtCore.Qt.Unchecked)
    return item


def _checked(item) -> bool:
    return item.checkState() == QtCore.Qt.Checked


class DiagramsPanel:
    """The connection and obstruction diagrams as a table; selecting a row selects the two parts in the 3D
    view. "Remove" deletes the selected relations, "Add" adds a contact or an obstruction (checked at once:
    unknown component, a component related to itself, a duplicate); OK writes all of it as one undoable
    transaction (:func:`freecad_aplan.workflow.edit_analysis_diagrams`), Cancel changes nothing.

    The designer's geometry is stored at once, one undo step each (Cancel does not take it back: Edit > Undo
    does): "Mark not blocking" marks the selected obstructions not blocking (they leave the table and stay
    out after every detection, :func:`freecad_aplan.workflow.mark_not_blocking`), "Unmark" takes marks of the
    list back, and "Add direction" adds a motion direction ``X,Y,Z`` that every detection tests like the axes
    (:func:`freecad_aplan.workflow.add_analysis_direction`)."""

    def __init__(self, analysis):
        self.analysis = analysis
        self.diagrams = read_intent(analysis).diagrams
        self.removed: list[tuple[str, str, str]] = []
        self.added: list[tuple[str, str, str]] = []
        self.plan_view = None  # the selected relation in 3D (made on the first selection)
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanDiagramsPanel")
        self.form.setWindowTitle("APLAN: diagrams")
        layout = panel_layout(self.form)
        summary = self.diagrams.get("analysis", {})
        edited = f", {len(self.diagrams['edits'])} edits" if self.diagrams.get("edits") else ""
        intro = wrapped_label(
            f"{len(self.diagrams.get('parts', []))} parts, {len(self.diagrams.get('contacts', []))} contacts "
            f"({summary.get('engine', '?')} engine{edited}). A row 'blocks +X: a, b' means a, moved along +X, "
            "hits b (and b, moved along -X, hits a).")
        layout.addWidget(intro)
        self.table = _table(["relation", "part", "part"], "AplanDiagramsTable")
        self.table.setSelectionBehavior(QtGui.QAbstractItemView.SelectRows)
        for relation in relation_rows(self.diagrams):
            self._append_row(relation)
        self.table.itemSelectionChanged.connect(self.highlight)
        layout.addWidget(self.table)
        remove = QtGui.QPushButton("Remove selected")
        remove.setObjectName("AplanRemoveRelations")
        remove.setToolTip("Remove the selected relations (stored on OK)")
        remove.clicked.connect(self.remove_selected)
        parts = list(self.diagrams.get("parts", []))
        self.kind = self._combo("AplanRelationKind", RELATION_KINDS, editable=False)
        self.first = self._combo("AplanRelationFirst", parts, editable=True)
        self.second = self._combo("AplanRelationSecond", parts, editable=True)
        add = QtGui.QPushButton("Add")
        add.setObjectName("AplanAddRelation")
        add.clicked.connect(lambda: self.add_relation())
        self._designer_widgets(layout, remove)
        layout.addWidget(wrapped_label("Add a relation: contact a, b, or 'blocks +X' a, b (a blocked by b "
                                       "along +X)"))
        adding = QtGui.QFormLayout()
        adding.setRowWrapPolicy(QtGui.QFormLayout.DontWrapRows)
        adding.setFieldGrowthPolicy(QtGui.QFormLayout.AllNonFixedFieldsGrow)
        for text, widget in (("relation", self.kind), ("a", self.first), ("b", self.second)):
            adding.addRow(text, widget)
        adding.addRow("", add)
        layout.addLayout(adding)
        self._direction_widgets(layout)
        self.message = wrapped_label("", "AplanDiagramsMessage")
        layout.addWidget(self.message)

    def _designer_widgets(self, layout, remove: QtGui.QPushButton) -> None:
        """"Remove selected" and "Mark not blocking" under the table, the list of marks with "Unmark"."""
        mark = QtGui.QPushButton("Mark not blocking")
        mark.setObjectName("AplanMarkNotBlocking")
        mark.setToolTip("The selected obstructions do not block (a detection is wrong about them): stored at once "
                        "and applied after every detection")
        mark.clicked.connect(lambda: self.mark_selected())
        layout.addWidget(button_rows(remove, mark))
        layout.addWidget(wrapped_label("Not blocking (designer marks, applied after every detection):"))
        self.marks = QtGui.QListWidget()
        self.marks.setObjectName("AplanNotBlockingList")
        self.marks.setMaximumHeight(80)
        layout.addWidget(self.marks)
        unmark = QtGui.QPushButton("Unmark selected")
        unmark.setObjectName("AplanUnmark")
        unmark.clicked.connect(lambda: self.unmark_selected())
        layout.addWidget(button_rows(unmark))

    def _direction_widgets(self, layout) -> None:
        """The "Add a direction" field and button, and the designer's directions."""
        self.direction = QtGui.QLineEdit()
        self.direction.setObjectName("AplanDirectionField")
        self.direction.setPlaceholderText("e.g. 0, -0.5, 0.866")
        self.direction.setToolTip("A motion direction X,Y,Z (normalised) that every detection tests like the axes")
        stacked_field(layout, "Add a direction X,Y,Z:", self.direction)
        add = QtGui.QPushButton("Add direction")
        add.setObjectName("AplanAddDirection")
        add.clicked.connect(lambda: self.add_direction())
        layout.addWidget(button_rows(add))
        self.directions = wrapped_label("", "AplanDesignerDirections")
        layout.addWidget(self.directions)
        self._show_designer()

    def _show_designer(self) -> None:
        intent = read_intent(self.analysis)
        self.marks.clear()
        for mark in intent.not_blocking:
            self.marks.addItem(f"{mark['blocked']} not blocked by {mark['blocking']} along "
                               f"{_direction_name(mark['direction'])}")
        shown = "; ".join(", ".join(f"{c:g}" for c in v) for v in intent.directions) or "none"
        self.directions.setText(f"Designer directions (tested like the axes at every detection): {shown}")

    def _reload(self) -> None:
        """The table and the designer lists again, from the analysis and the edits not stored yet."""
        self.diagrams = read_intent(self.analysis).diagrams
        try:
            rows = relation_rows(edited_diagrams(self.diagrams, self.removed, self.added))
        except RelationError:  # an edit not stored yet clashes with a mark taken back: drop the edits
            self.removed, self.added = [], []
            rows = relation_rows(self.diagrams)
        self.table.setRowCount(0)
        for relation in rows:
            self._append_row(relation)
        self._show_designer()

    def _selected_relations(self) -> list[tuple[str, str, str]]:
        rows = sorted(i.row() for i in self.table.selectionModel().selectedRows())
        return [tuple(self.table.item(r, c).text() for c in range(3)) for r in rows]

    def mark_selected(self) -> bool:
        """Mark the selected obstructions not blocking (one undo step); say why not in the panel otherwise."""
        from planner.errors import PlannerError

        from ..workflow import mark_not_blocking

        relations = self._selected_relations()
        if not relations:
            self._say("select the obstructions to mark not blocking first", error=True)
            return False
        pending = [r for r in relations if r in self.added]
        if pending:
            self._say(f"{describe_relation(pending[0])} is added in this panel, not stored yet: press OK first, "
                      "or remove it", error=True)
            return False
        try:
            notes = mark_not_blocking(self.analysis, relations)
        except PlannerError as exc:
            self._say(str(exc), error=True)
            return False
        self._reload()
        what = describe_relation(relations[0]) if len(relations) == 1 else f"{len(relations)} relations"
        self._say("; ".join([f"marked {what} not blocking (stored; Edit > Undo takes it back)"] + notes), error=False)
        return True

    def unmark_selected(self) -> bool:
        """Take the selected marks back (one undo step): their relations return to the table."""
        from planner.errors import PlannerError

        from ..workflow import unmark_not_blocking

        intent = read_intent(self.analysis)
        chosen = [intent.not_blocking[i.row()] for i in self.marks.selectedIndexes()]
        if not chosen:
            self._say("select the marks to take back first", error=True)
            return False
        relations = [(f"blocks {_direction_name(m['direction'])}", m["blocked"], m["blocking"]) for m in chosen]
        try:
            unmark_not_blocking(self.analysis, relations)
        except PlannerError as exc:
            self._say(str(exc), error=True)
            return False
        self._reload()
        self._say(f"took back {len(chosen)} mark(s); their relations block again", error=False)
        return True

    def add_direction(self, text: str | None = None) -> bool:
        """Add the direction of the field (or ``text``) to the analysis (one undo step), or say why not."""
        from planner.errors import PlannerError

        from ..workflow import add_analysis_direction

        text = (text if text is not None else self.direction.text()).strip()
        try:
            notes = add_analysis_direction(self.analysis, text)
        except PlannerError as exc:
            self._say(str(exc), error=True)
            return False
        self._show_designer()
        self._say("; ".join(notes) if notes else f"added direction {text} (stored; detect again to test it)",
                  error=False)
        return not notes

    @staticmethod
    def _combo(name: str, items, editable: bool) -> QtGui.QComboBox:
        combo = QtGui.QComboBox()
        combo.setObjectName(name)
        combo.setEditable(editable)
        combo.addItems(list(items))
        return narrow_combo(combo)

    def _append_row(self, relation) -> None:
        row = self.table.rowCount()
        self.table.insertRow(row)
        for column, text in enumerate(relation):
            self.table.setItem(row, column, _item(text))

    def _say(self, text: str, error: bool) -> None:
        self.message.setText(text)
        (FreeCAD.Console.PrintError if error else FreeCAD.Console.PrintMessage)(f"APLAN: {text}\n")

    def highlight(self) -> None:
        """Select, in the 3D view, the objects of the parts of the selected rows."""
        objects = self.diagrams.get("objects", {})
        document = self.analysis.Document
        FreeCADGui.Selection.clearSelection()
        for index in self.table.selectionModel().selectedRows():
            for column in (1, 2):
                part = self.table.item(index.row(), column).text()
                for name in objects.get(part, []):
                    if document.getObject(name) is not None:
                        FreeCADGui.Selection.addSelection(document.Name, name)
        self._show_in_3d()

    def _show_in_3d(self) -> None:
        """One selected relation shown in 3D (blocked part red, blocking part blue, an arrow along the direction,
        :class:`~freecad_aplan.gui.plan3d.PlanView`; an obstruction's parts are then not left selected, whose
        highlight would hide the colours); any other selection restores the view."""
        from .plan3d import PlanView, restore_when_gone

        if self.plan_view is None:
            self.plan_view = PlanView(self.analysis.Document, self.diagrams)
            restore_when_gone(self.form, self.plan_view)
        relations = self._selected_relations()
        if len(relations) == 1:
            self.plan_view.show_relation(*relations[0])
            if relations[0][0] != "contact":  # the selection's green would hide which part is which
                FreeCADGui.Selection.clearSelection()
        else:
            self.plan_view.restore()

    def remove_selected(self) -> None:
        for index in sorted((i.row() for i in self.table.selectionModel().selectedRows()), reverse=True):
            relation = tuple(self.table.item(index, c).text() for c in range(3))
            if relation in self.added:  # added in this panel: simply not added any more
                self.added.remove(relation)
            else:
                self.removed.append(relation)
            self.table.removeRow(index)

    def add_relation(self, kind: str | None = None, first: str | None = None, second: str | None = None) -> bool:
        """Add the relation of the three fields (or of the arguments) to the table, if valid; else say why in
        the panel and the report view and change nothing. Written to the document on OK."""
        relation = (kind if kind is not None else self.kind.currentText(),
                    (first if first is not None else self.first.currentText()).strip(),
                    (second if second is not None else self.second.currentText()).strip())
        try:
            edited_diagrams(self.diagrams, self.removed, self.added + [relation])
        except RelationError as exc:
            self._say(str(exc), error=True)
            return False
        self.added.append(relation)
        self._append_row(relation)
        self._say(f"added {describe_relation(relation)} (stored on OK)", error=False)
        return True

    def accept(self) -> bool:
        from ..workflow import edit_analysis_diagrams

        try:
            edit_analysis_diagrams(self.analysis, self.removed, self.added)
        except (RelationError, IntentError) as exc:
            self._say(str(exc), error=True)
            return False
        if self.plan_view is not None:
            self.plan_view.restore()
        FreeCADGui.Control.closeDialog()
        return True

    def reject(self) -> bool:
        if self.plan_view is not None:
            self.plan_view.restore()
        FreeCADGui.Control.closeDialog()
        return True


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
