"""Task panels for the product's structure: fastener tags, the subassembly tree; the per-level statistics.

Thin Qt over :mod:`freecad_aplan.structure` (the logic, also run under FreeCADCmd by the tests): every store
is one undoable transaction, a refused change is told in the panel and changes nothing.
"""
from __future__ import annotations

from types import MappingProxyType

import FreeCADGui
from PySide import QtCore, QtGui

from .. import structure
from ..intent import IntentError, read_intent
from .layout import button_rows, fit_columns, narrow_combo, panel_layout, stacked_field, wrapped_label
from .tables import _item, _table

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


def _names(names) -> str:
    """Names one per line: a label wraps at spaces only, so a name is never broken inside (``cabin_door_001``)."""
    return "\n".join(names) or "none"


def _entry(group) -> str:
    """A group's entry in the list: the parts it joins, one per line (what the designer recognises; a proposed
    group's id, ``fasteners_HOST+HOST``, is wider than the default task view: it is the entry's tooltip), or
    its id when it joins none yet."""
    return "\n+ ".join(sorted(group.hosts)) if group.hosts else group.id


_HEADINGS = MappingProxyType({"designer": "Tagged by the designer", "proposed": "Proposed by the planner"})


class FastenersPanel:
    """The designer's fastener groups and the planner's proposals (the call behind ``aplan fasteners``): a list
    of the groups, ticked to keep (tagged) or accept (proposed) on OK, and below it the selected group's parts,
    the parts it joins, its tool (typed in) and why it is there, each name on a line of its own so that the
    panel reads at the task view's default width (a six-column table broke names inside words there). OK
    stores the ticked groups with their tools in one undo step. "Tag selected" makes the selected objects one
    group (with the tool typed beside it) and "Untag selected" takes them out, each at once and undoable."""

    def __init__(self, analysis):
        self.analysis = analysis
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanFastenersPanel")
        self.form.setWindowTitle("APLAN: fasteners")
        layout = panel_layout(self.form)
        self.summary = wrapped_label()
        layout.addWidget(self.summary)
        self.groups = QtGui.QListWidget()
        self.groups.setObjectName("AplanFastenersList")
        self.groups.setToolTip("ticked: kept (tagged) or accepted (proposed) on OK; select one to see it below")
        self.groups.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.groups.setMinimumHeight(150)  # a few groups at a time; the list scrolls
        self.groups.currentRowChanged.connect(self.show_group)
        layout.addWidget(self.groups)
        details = QtGui.QGroupBox("selected group")
        details.setObjectName("AplanFastenerDetails")
        inner = QtGui.QVBoxLayout(details)
        self.parts, self.hosts, self.why = (wrapped_label("", name) for name in
                                            ("AplanFastenerParts", "AplanFastenerHosts", "AplanFastenerWhy"))
        self.group_tool = QtGui.QLineEdit()
        self.group_tool.setObjectName("AplanFastenerGroupTool")
        self.group_tool.setPlaceholderText("none (e.g. screwdriver)")
        self.group_tool.textEdited.connect(self._tool_typed)
        for text, widget in (("fasteners:", self.parts), ("joins:", self.hosts), ("tool:", self.group_tool),
                             ("why:", self.why)):
            stacked_field(inner, text, widget)
        layout.addWidget(details)
        layout.addWidget(wrapped_label("New group from the objects selected in the 3D view, with this tool:"))
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
        """Fill the list from the analysis' tags and the planner's proposals for the other components: a heading
        for each source, then its groups."""
        designed, proposals = structure.fastener_report(self.analysis)
        tagged = {g["id"]: g for g in read_intent(self.analysis).fasteners}
        # (designer or proposed, the group, its list entry), in the list's order; tools typed, by group
        self.rows: list[tuple[str, object, QtGui.QListWidgetItem]] = []
        self.tools: dict[int, str] = {}
        self.groups.blockSignals(True)
        self.groups.clear()
        for source, groups in (("designer", designed), ("proposed", proposals.groups)):
            if not groups:
                continue
            heading = QtGui.QListWidgetItem(_HEADINGS[source])
            heading.setFlags(QtCore.Qt.ItemIsEnabled)  # not selectable, no check box
            font = heading.font()
            font.setBold(True)
            heading.setFont(font)
            self.groups.addItem(heading)
            for group in groups:
                item = QtGui.QListWidgetItem(_entry(group))
                item.setToolTip(group.id)
                item.setFlags(item.flags() | QtCore.Qt.ItemIsUserCheckable)
                item.setCheckState(QtCore.Qt.Checked)
                item.setData(QtCore.Qt.UserRole, len(self.rows))
                self.groups.addItem(item)
                self.tools[len(self.rows)] = group.tool or ""
                self.rows.append((source, group, item))
        self.groups.blockSignals(False)
        self.summary.setText(f"{len(tagged)} tagged groups; {len(proposals.groups)} proposed by the planner "
                             f"({sum(len(g.parts) for g in proposals.groups)} parts); untick a proposal to reject it"
                             + "".join(f"\nnot proposed: {p}: {r}" for p, r in proposals.left_out))
        if self.rows:
            self.groups.setCurrentItem(self.rows[0][2])
        self.show_group(self.groups.currentRow())

    def _group_at(self, row: int) -> int | None:
        """The index in :attr:`rows` of the group at list row ``row`` (None: a heading, or no row)."""
        item = self.groups.item(row) if row >= 0 else None
        value = item.data(QtCore.Qt.UserRole) if item is not None else None
        return None if value is None else int(value)

    def show_group(self, row: int) -> None:
        """Show the group at list row ``row`` below the list (nothing for a heading or no row)."""
        k = self._group_at(row)
        if k is None:
            for label in (self.parts, self.hosts, self.why):
                label.setText("")
            self.group_tool.setText("")
            self.group_tool.setEnabled(False)
            return
        source, group, _ = self.rows[k]
        self.parts.setText(_names(group.parts))
        self.hosts.setText(_names(sorted(group.hosts)))
        self.why.setText("tagged by the designer" if source == "designer" else group.reason)
        self.group_tool.setEnabled(True)
        self.group_tool.setText(self.tools[k])

    def _tool_typed(self, text: str) -> None:
        k = self._group_at(self.groups.currentRow())
        if k is not None:
            self.tools[k] = text

    def set_tool(self, k: int, tool: str) -> None:
        """Type ``tool`` for group ``k`` (of :attr:`rows`) as a designer does: select it, type in its tool field."""
        self.groups.setCurrentItem(self.rows[k][2])
        self.group_tool.setText(tool)
        self.group_tool.textEdited.emit(tool)

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
        rows = [(source, group.id, item.checkState() == QtCore.Qt.Checked, self.tools[k].strip())
                for k, (source, group, item) in enumerate(self.rows)]
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
