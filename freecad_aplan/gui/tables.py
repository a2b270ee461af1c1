"""The small tables the workbench's task panels are made of: a read-only or editable cell, a check box cell, and
a table sized to the task view (:mod:`freecad_aplan.gui.layout`). Helpers of the panels of ``gui/`` only, hence
their leading underscores."""
from __future__ import annotations

import json

from PySide import QtCore, QtGui

from .layout import fit_columns

__all__: list[str] = []


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


