"""Task panels for the product's structure: fastener tags, the subassembly tree; the per-level statistics.

Thin Qt over :mod:`freecad_aplan.structure` (the logic, also run under FreeCADCmd by the tests): every store
is one undoable transaction, a refused change is told in the panel and changes nothing.
"""
from __future__ import annotations

import FreeCADGui
from PySide import QtCore, QtGui

from .. import structure
from ..intent import IntentError, read_intent
from .layout import button_rows, fit_columns, narrow_combo, panel_layout, wrapped_label
from .panels import _check, _checked, _item, _table

__all__ = ["FastenersPanel", "SubassembliesPanel", "LevelsDialog", "level_rows"]


def _button(text: str, name: str, slot) -> QtGui.QPushButton:
    button = QtGui.QPushButton(text)
    button.setObjectName(name)
    button.clicked.connect(slot)
    return button


def _message_label(name: str) -> QtGui.QLabel:
    return wrapped_label("", name)


def _selected_names(analysis) -> list[str]:
    return [o.Name for o in FreeCADGui.Selection.getSelection() if o is not analysis]


class FastenersPanel:
    """The designer's fastener groups and the planner's proposals (the call behind ``aplan fasteners``) in one
    table: a ticked row is kept (tagged) or accepted (proposed) on OK, with the tool typed in its row, in one
    undo step. "Tag selected"
    makes the selected objects one group (with the tool typed beside it) and "Untag selected" takes them out,
    each at once and undoable."""

    def __init__(self, analysis):
        self.analysis = analysis
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanFastenersPanel")
        self.form.setWindowTitle("APLAN: fasteners")
        layout = panel_layout(self.form)
        self.summary = wrapped_label()
        layout.addWidget(self.summary)
        self.table = _table(["use", "group", "parts", "joins", "tool", "why"], "AplanFastenersTable", fit=(0,),
                            tips={0: "ticked: kept (tagged) or accepted (proposed) on OK", 2: "the fasteners of the group",
                                  3: "the parts the group joins", 5: "designer (tagged) or why the planner proposes it"})
        self.table.setMinimumHeight(280)  # six columns in a narrow panel make tall rows: show a few of them
        layout.addWidget(self.table)
        self.tool = QtGui.QLineEdit()
        self.tool.setObjectName("AplanFastenerTool")
        self.tool.setPlaceholderText("tool (e.g. screwdriver)")
        layout.addWidget(self.tool)
        layout.addWidget(button_rows(_button("Tag selected", "AplanTagFasteners", self.tag_selected),
                                     _button("Untag selected", "AplanUntagFasteners", self.untag_selected)))
        self.message = _message_label("AplanFastenersMessage")
        layout.addWidget(self.message)
        self.refresh()

    def refresh(self) -> None:
        """Fill the table from the analysis' tags and the planner's proposals for the other components."""
        designed, proposals = structure.fastener_report(self.analysis)
        tagged = {g["id"]: g for g in read_intent(self.analysis).fasteners}
        self.rows: list[tuple[str, str]] = []
        self.table.setRowCount(0)
        for source, groups in (("designer", designed), ("proposed", proposals.groups)):
            for group in groups:
                k = self.table.rowCount()
                self.table.insertRow(k)
                self.table.setItem(k, 0, _check(True))
                for column, text in enumerate((group.id, ", ".join(group.parts), ", ".join(sorted(group.hosts)),
                                               group.tool or "", source if source == "designer" else group.reason),
                                              start=1):
                    self.table.setItem(k, column, _item(text, editable=column == 4))  # the tool can be typed in
                self.rows.append((source, group.id))
        self.summary.setText(f"{len(tagged)} tagged groups; {len(proposals.groups)} proposed by the planner "
                             f"({sum(len(g.parts) for g in proposals.groups)} parts); untick a proposal to reject it"
                             + "".join(f"\nnot proposed: {p}: {r}" for p, r in proposals.left_out))

    def tag_selected(self) -> None:
        try:
            intent = structure.tag_fasteners(self.analysis, _selected_names(self.analysis), self.tool.text() or None)
        except IntentError as exc:
            self.message.setText(str(exc))
            return
        self.message.setText(f"tagged {intent.fasteners[-1]['id']}")
        self.refresh()

    def untag_selected(self) -> None:
        try:
            structure.untag_fasteners(self.analysis, _selected_names(self.analysis))
        except IntentError as exc:
            self.message.setText(str(exc))
            return
        self.message.setText("untagged")
        self.refresh()

    def accept(self) -> bool:
        rows = [(source, g, _checked(self.table.item(k, 0)), self.table.item(k, 4).text().strip())
                for k, (source, g) in enumerate(self.rows)]
        keep = [g for source, g, use, _ in rows if source == "designer" and use]
        accepted = [g for source, g, use, _ in rows if source == "proposed" and use]
        tools = {g: tool for source, g, use, tool in rows if source == "proposed" and use and tool}
        kept_tools = {g: tool for source, g, use, tool in rows if source == "designer" and use}
        try:
            structure.accept_fastener_proposals(self.analysis, accepted, keep, tools, kept_tools)
        except IntentError as exc:
            self.message.setText(str(exc))
            return False
        FreeCADGui.Control.closeDialog()
        return True

    def reject(self) -> bool:
        FreeCADGui.Control.closeDialog()
        return True


class SubassembliesPanel:
    """The subassembly tree (the analysis' own, else the document's containers) as a tree to edit: the planner's
    proposal or the document's structure as a start, a new subassembly of the selected rows, delete one, move
    the selected rows into another (or the top level). OK checks it with the planner (a cycle, a member in two,
    a subassembly that cannot be built: named) and stores it as one undo step; Cancel changes nothing."""

    def __init__(self, analysis):
        self.analysis = analysis
        self.entries, source = structure.current_structure(analysis)
        self.components = [p for p in read_intent(analysis).diagrams.get("parts", [])]
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanSubassembliesPanel")
        self.form.setWindowTitle("APLAN: subassemblies")
        layout = panel_layout(self.form)
        self.source = wrapped_label(f"from the {source}")
        layout.addWidget(self.source)
        self.tree = QtGui.QTreeWidget()
        self.tree.setObjectName("AplanSubassemblyTree")
        self.tree.setHeaderLabels(["member", "kind"])
        self.tree.setSelectionMode(QtGui.QAbstractItemView.ExtendedSelection)
        fit_columns(self.tree)
        self.tree.setMinimumHeight(280)  # names wrap in a narrow panel: show a good part of the tree
        layout.addWidget(self.tree)
        layout.addWidget(wrapped_label("Start from:"))
        layout.addWidget(button_rows(_button("Planner's proposal", "AplanProposeSubassemblies", self.propose),
                                     _button("Document's structure", "AplanDocumentSubassemblies",
                                             self.from_document)))
        self.name = QtGui.QLineEdit()
        self.name.setObjectName("AplanSubassemblyName")
        self.name.setPlaceholderText("new subassembly name")
        layout.addWidget(self.name)
        layout.addWidget(button_rows(_button("New of selected", "AplanNewSubassembly", self.new),
                                     _button("Delete", "AplanDeleteSubassembly", self.delete)))
        self.target = narrow_combo(QtGui.QComboBox())
        self.target.setObjectName("AplanMoveTarget")
        layout.addWidget(self.target)
        layout.addWidget(button_rows(_button("Move selected here", "AplanMoveMember", self.move)))
        self.message = _message_label("AplanSubassembliesMessage")
        layout.addWidget(self.message)
        self.show()

    def show(self) -> None:
        """Draw the tree of ``self.entries``: the top level holds the members of no subassembly."""
        by_id = {s["id"]: s for s in self.entries}
        held = {m for s in self.entries for m in s["parts"]}
        fasteners = {p for g in structure.fastener_entries(read_intent(self.analysis),
                                                          structure.component_objects(read_intent(self.analysis)))
                     for p in g["parts"]}
        self.tree.clear()

        def add(parent, member: str, seen: frozenset) -> None:
            kind = "subassembly" if member in by_id else "fastener" if member in fasteners else "part"
            label = by_id[member].get("label", "") if member in by_id else ""
            item = QtGui.QTreeWidgetItem(parent, [member, f"{kind}: {label}" if label and label != member else kind])
            for column in (0, 1):  # the whole name of an entry elided in a narrow panel
                item.setToolTip(column, item.text(column))
            item.setData(0, QtCore.Qt.UserRole, member)
            if member in by_id and member not in seen:
                for inner in by_id[member]["parts"]:
                    add(item, inner, seen | {member})
            item.setExpanded(True)

        top = QtGui.QTreeWidgetItem(self.tree, ["top", "top level"])
        top.setData(0, QtCore.Qt.UserRole, None)
        # Fasteners are no members: each group is installed where its hosts come together (planner.assembly.hierarchy).
        for member in [s["id"] for s in self.entries if s["id"] not in held] + [
                p for p in self.components if p not in held and p not in fasteners]:
            add(top, member, frozenset())
        if fasteners:
            self.source.setText(self.source.text().split(";")[0] + f"; {len(fasteners)} fastener parts not shown: "
                                "each group is installed where its hosts come together")
        top.setExpanded(True)
        self.tree.resizeColumnToContents(0)
        self.target.clear()
        self.target.addItems(["top"] + [s["id"] for s in self.entries])

    def _selected(self) -> list[str]:
        return [i.data(0, QtCore.Qt.UserRole) for i in self.tree.selectedItems() if i.data(0, QtCore.Qt.UserRole)]

    def _edit(self, change, done: str) -> None:
        try:
            self.entries = change()
        except IntentError as exc:
            self.message.setText(str(exc))
            return
        self.message.setText(done)
        self.show()

    def propose(self) -> None:
        self._edit(lambda: structure.proposed_structure(self.analysis), "the planner's proposal (stored on OK)")
        self.source.setText("the planner's proposal")

    def from_document(self) -> None:
        self._edit(lambda: structure.document_structure(self.analysis), "the document's structure (stored on OK)")
        self.source.setText("from the document")

    def new(self) -> None:
        members = self._selected()
        self._edit(lambda: structure.add_subassembly(self.entries, self.name.text(), members),
                   f"new subassembly {self.name.text()} of {', '.join(members)}")

    def delete(self) -> None:
        gone = [m for m in self._selected() if m in {s["id"] for s in self.entries}]

        def change():
            entries = self.entries
            for name in gone:
                entries = structure.delete_subassembly(entries, name)
            return entries

        self._edit(change, f"deleted {', '.join(gone) or 'nothing (select a subassembly)'}")

    def move(self) -> None:
        members, target = self._selected(), self.target.currentText()

        def change():
            entries = self.entries
            for member in members:
                entries = structure.move_member(entries, member, None if target == "top" else target)
            return [s for s in entries if s["parts"]]

        self._edit(change, f"moved {', '.join(members)} to {target}")

    def accept(self) -> bool:
        try:
            structure.set_subassemblies(self.analysis, self.entries)
        except IntentError as exc:
            self.message.setText(str(exc))
            return False
        FreeCADGui.Control.closeDialog()
        return True

    def reject(self) -> bool:
        FreeCADGui.Control.closeDialog()
        return True


_COLUMNS = (("members", "members"), ("and_or_nodes", "subassemblies"), ("and_arcs", "operations"),
            ("states", "states"), ("state_edges", "state_edges"), ("intentions", "intentions"),
            ("sequences", "sequences"))


def level_rows(report: dict) -> list[list[str]]:
    """The rows ``aplan stats`` prints for a product of several levels (:func:`planner.api.level_report`):
    each level, the total and the product planned flat, as text ("-": not computed)."""
    def shown(value) -> str:
        return "-" if value is None else f"{value:,}"

    rows = []
    for row in report["levels"]:
        rows.append([row["level"], shown(len(row["members"]))] + [shown(row[k]) for _, k in _COLUMNS[1:]])
    total = report["total"]
    rows.append(["total", shown(total["parts"])] + [shown(total[k]) for _, k in _COLUMNS[1:]])
    if report.get("flat"):
        rows.append(["flat", shown(report["flat"]["parts"])] + [shown(report["flat"][k]) for _, k in _COLUMNS[1:]])
    return rows


class LevelsDialog(QtGui.QDialog):
    """The per-level statistics (each workstation, the total, the product planned flat), as ``aplan stats``."""

    def __init__(self, title: str, report: dict, parent=None):
        super().__init__(parent)
        self.setObjectName("AplanLevelsDialog")
        self.setWindowTitle(f"APLAN plan by workstation: {title}")
        self.resize(900, 420)
        layout = QtGui.QVBoxLayout(self)
        table = _table(["level"] + [name for name, _ in _COLUMNS], "AplanLevelsTable")
        for k, row in enumerate(level_rows(report)):
            table.insertRow(k)
            for column, text in enumerate(row):
                table.setItem(k, column, _item(text))
        table.resizeColumnsToContents()
        layout.addWidget(table, 3)
        folded = report.get("fasteners") or []
        notes = ([f"fasteners folded: {sum(len(g['parts']) for g in folded)} parts in {len(folded)} groups"]
                 if folded else [])
        notes += [f"{row['level']}: {', '.join(row['members'])}" for row in report["levels"]]
        notes += [f"{row['level']}: {row.get('error') or row.get('not_computed')}" for row in report["levels"]
                  if row.get("error") or row.get("not_computed")]
        if report.get("flat_not_computed"):
            notes.append(f"flat: not counted: {report['flat_not_computed']}")
        text = QtGui.QPlainTextEdit("\n".join(notes))
        text.setObjectName("AplanLevelsNotes")
        text.setReadOnly(True)
        layout.addWidget(text, 1)
        close = QtGui.QPushButton("Close")
        close.clicked.connect(self.close)
        layout.addWidget(close)
