"""Layout rules that make the task panels fit FreeCAD's default combo view (about 245 px of visible width at the
default window size): text wraps, buttons flow onto as many rows as the width needs, tables stretch their columns
to the width, fields stand in a form (label above field) instead of one long line.

Every panel and dialog of the workbench is built with these helpers; tests/workbench/test_gui.py opens each one at
the default width and checks that nothing is cut off.
"""
from __future__ import annotations

from PySide import QtCore, QtGui

from .fitting import breakable, shared_widths

__all__ = ["BreakAnywhere", "FlowLayout", "button_rows", "fit_columns", "header_width", "narrow_combo", "panel_layout",
           "stacked_field", "wrapped_label"]


def panel_layout(form: QtGui.QWidget) -> QtGui.QVBoxLayout:
    """The column a task panel stacks its widgets in, without margins of its own: the task box around it has
    them already, and a narrow combo view has no pixel to spare."""
    layout = QtGui.QVBoxLayout(form)
    layout.setContentsMargins(0, 0, 0, 0)
    return layout


def wrapped_label(text: str = "", name: str = "") -> QtGui.QLabel:
    """A label whose text wraps at the panel's width (selectable, so a message can be copied)."""
    label = QtGui.QLabel(text)
    label.setWordWrap(True)
    label.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
    if name:
        label.setObjectName(name)
    return label


class FlowLayout(QtGui.QLayout):
    """Widgets side by side while they fit, then on the next row (Qt's flow layout example): the height follows
    the width (``heightForWidth``), so a row of buttons never makes the panel wider than the combo view.
    Cost: O(items) per layout pass."""

    def __init__(self, parent=None, spacing: int = 6):
        super().__init__(parent)
        self._items: list = []
        self.setSpacing(spacing)
        self.setContentsMargins(0, 0, 0, 0)

    def addItem(self, item) -> None:
        self._items.append(item)

    def count(self) -> int:
        return len(self._items)

    def itemAt(self, index: int):
        return self._items[index] if 0 <= index < len(self._items) else None

    def takeAt(self, index: int):
        return self._items.pop(index) if 0 <= index < len(self._items) else None

    def expandingDirections(self):
        return QtCore.Qt.Orientations(0)

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        return self._arrange(QtCore.QRect(0, 0, width, 0), move=False)

    def setGeometry(self, rect) -> None:
        super().setGeometry(rect)
        self._arrange(rect, move=True)

    def sizeHint(self):
        return self.minimumSize()

    def minimumSize(self):
        """The widest single item: the narrowest width at which every item still shows whole."""
        size = QtCore.QSize()
        for item in self._items:
            size = size.expandedTo(item.minimumSize()).expandedTo(QtCore.QSize(item.sizeHint().width(), 0))
        margins = self.contentsMargins()
        return size + QtCore.QSize(margins.left() + margins.right(), margins.top() + margins.bottom())

    def _arrange(self, rect, move: bool) -> int:
        """Place the items left to right, wrapping when the next one would pass the right edge; the height used."""
        margins = self.contentsMargins()
        area = rect.adjusted(margins.left(), margins.top(), -margins.right(), -margins.bottom())
        x, y, row_height = area.x(), area.y(), 0
        for item in self._items:
            hint = item.sizeHint()
            if x + hint.width() > area.right() + 1 and row_height > 0:  # this row is full: start the next one
                x, y, row_height = area.x(), y + row_height + self.spacing(), 0
            if move:
                item.setGeometry(QtCore.QRect(QtCore.QPoint(x, y), QtCore.QSize(min(hint.width(), area.width()),
                                                                                hint.height())))
            x += hint.width() + self.spacing()
            row_height = max(row_height, hint.height())
        return y + row_height - rect.y() + margins.bottom()


def button_rows(*widgets) -> QtGui.QWidget:
    """The buttons (or other small widgets) in a row that wraps onto more rows when the panel is narrow."""
    holder = QtGui.QWidget()
    flow = FlowLayout(holder)
    for widget in widgets:
        flow.addWidget(widget)
    policy = QtGui.QSizePolicy(QtGui.QSizePolicy.Preferred, QtGui.QSizePolicy.Preferred)
    policy.setHeightForWidth(True)
    holder.setSizePolicy(policy)
    return holder


class BreakAnywhere(QtGui.QStyledItemDelegate):
    """Cells that wrap inside names: Qt's item views wrap at spaces only, and part names (``cartridge_001``) have
    none. The text shown (not the item's) gets line-break opportunities (:func:`.fitting.breakable`)."""

    def displayText(self, value, locale) -> str:
        return breakable(super().displayText(value, locale))

    def sizeHint(self, option, index):
        """A tree asks without a width (Qt's item views wrap only in a valid rect): give the column's width less
        the first column's indentation, so that the row is as tall as the wrapped text."""
        view = self.parent()
        if isinstance(view, QtGui.QTreeView):
            width = view.header().sectionSize(index.column())
            if index.column() == 0:
                depth, parent = int(view.rootIsDecorated()), index.parent()
                while parent.isValid():
                    depth, parent = depth + 1, parent.parent()
                width -= depth * view.indentation()
            option = QtGui.QStyleOptionViewItem(option)
            option.rect = QtCore.QRect(0, 0, max(1, width), max(1, option.rect.height()))
        return super().sizeHint(option, index)


def _header(view: QtGui.QAbstractItemView) -> QtGui.QHeaderView:
    return view.horizontalHeader() if isinstance(view, QtGui.QTableView) else view.header()


def header_width(header: QtGui.QHeaderView, column: int) -> int:
    """The width a column needs for its header text to show whole: the text and the header's margins."""
    text = header.model().headerData(column, header.orientation()) or ""
    margin = header.style().pixelMetric(QtGui.QStyle.PM_HeaderMargin, None, header)
    return header.fontMetrics().horizontalAdvance(str(text)) + 2 * margin + 2


class _SharedWidths(QtCore.QObject):
    """Sets the widths of a view's columns whenever the view or a ``fit`` column changes width: the ``fit``
    columns as wide as their contents (Qt's ResizeToContents), the others the rest, as equal as their headers'
    widths allow (:func:`.fitting.shared_widths`). Cost: O(columns^2) per resize."""

    def __init__(self, view: QtGui.QAbstractItemView, fit: tuple[int, ...]):
        super().__init__(view)
        self.view, self.fit, self.busy = view, fit, False
        view.viewport().installEventFilter(self)
        _header(view).sectionResized.connect(lambda column, *_: column in self.fit and self.share())

    def eventFilter(self, watched, event) -> bool:
        if event.type() == QtCore.QEvent.Resize:
            self.share()
        return False

    def share(self) -> None:
        header = _header(self.view)
        shared = [c for c in range(header.count()) if c not in self.fit and not header.isSectionHidden(c)]
        if self.busy or not shared:
            return
        self.busy = True  # resizing a section reports back through sectionResized
        try:
            width = self.view.viewport().width() - sum(header.sectionSize(c) for c in self.fit)
            for column, size in shared_widths([header_width(header, c) for c in shared], width).items():
                header.resizeSection(shared[column], size)
        finally:
            self.busy = False


def fit_columns(view: QtGui.QAbstractItemView, fit: tuple[int, ...] = ()) -> None:
    """Columns that share the table's (or tree's) width, no sideways scrolling: the ``fit`` columns (check boxes,
    short codes) as wide as their contents, the others sharing the rest as equally as their headers allow
    (:func:`.fitting.shared_widths`). Text too long for its column wraps (inside names too, :class:`BreakAnywhere`) and
    the row grows, so no name is elided."""
    header = _header(view)
    for column in range(header.count()):
        mode = QtGui.QHeaderView.ResizeToContents if column in fit else QtGui.QHeaderView.Interactive
        header.setSectionResizeMode(column, mode)
    header.setStretchLastSection(False)  # the shared columns fill the width already
    header.setMinimumSectionSize(16)
    view.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)  # the columns fit: no bar flickering
    view.setWordWrap(True)
    view.setTextElideMode(QtCore.Qt.ElideNone)
    view.setItemDelegate(BreakAnywhere(view))
    view._aplan_widths = _SharedWidths(view, fit)  # kept with the view
    # Qt sizes the rows for the column widths of the moment: size them again when a column changes width.
    if isinstance(view, QtGui.QTableView):
        view.verticalHeader().setSectionResizeMode(QtGui.QHeaderView.ResizeToContents)
        header.sectionResized.connect(lambda *_: view.resizeRowsToContents())
    else:
        view.setUniformRowHeights(False)
        view.setIndentation(min(view.indentation(), 12))  # deep trees leave their names some width
        header.sectionResized.connect(lambda *_: view.doItemsLayout())


def narrow_combo(combo: QtGui.QComboBox, characters: int = 8) -> QtGui.QComboBox:
    """A combo box that does not ask for the width of its longest entry (a long part name would widen the panel);
    the open list still shows the entries whole."""
    combo.setSizeAdjustPolicy(QtGui.QComboBox.AdjustToMinimumContentsLengthWithIcon)
    combo.setMinimumContentsLength(characters)
    combo.view().setTextElideMode(QtCore.Qt.ElideNone)
    return combo


def stacked_field(layout: QtGui.QBoxLayout, text: str, field: QtGui.QWidget) -> None:
    """A field under its (wrapped) label, instead of label and field on one line that may not fit."""
    layout.addWidget(wrapped_label(text))
    layout.addWidget(field)
