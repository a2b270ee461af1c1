"""The diagrams task panel: the connection and obstruction diagrams of the last detection as tables, edited by
the designer (a relation added, removed or marked not blocking) and written back on OK as one undoable step
(:func:`freecad_aplan.intent.update_intent`); Cancel changes nothing.
"""
from __future__ import annotations

import FreeCAD
import FreeCADGui
from PySide import QtGui

from ..diagrams import RELATION_KINDS, RelationError, describe_relation, edited_diagrams, relation_rows
from ..hybrid import undecided_notes
from ..intent import IntentError, read_intent
from .layout import button_rows, narrow_combo, panel_layout, stacked_field, wrapped_label
from .tables import _direction_name, _item, _table

__all__ = ["DiagramsPanel"]


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
        undecided = undecided_notes(summary.get("tolerances", {}))
        if undecided:  # the pairs the exact engine left, and the answer that stands for each
            label = wrapped_label("\n".join(undecided))
            label.setObjectName("AplanUndecidedPairs")
            layout.addWidget(label)
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
