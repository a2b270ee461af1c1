"""Helpers of the tests that run FreeCAD or the command line: the pen's liaisons, ``aplan`` (run in this process),
and the answer of a FreeCADCmd script."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from aplan_runner import run_aplan
from background import Job, folder, run

__all__ = ["LIAISONS", "aplan", "aplan_process", "freecad_result", "freecadcmd_job", "succeeded"]

#: The pen's connection diagram (the ground truth of the models in ../shared).
LIAISONS = {frozenset(p) for p in [("ink_001", "cartridge_001"), ("cartridge_001", "head_001"),
                                   ("head_001", "body_001"), ("body_001", "cap_001"), ("body_001", "button_001")]}


def freecad_result(done: subprocess.CompletedProcess) -> dict:
    """The JSON a FreeCADCmd script printed after ``APLAN-RESULT`` (FreeCAD's progress output surrounds it)."""
    found = re.search(r"APLAN-RESULT (.*)", done.stdout)
    assert found, f"no result from FreeCAD:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return json.loads(found.group(1))


def freecadcmd_job(name: str, script: Callable[[Path], str], files: dict[str, Path] | None = None) -> Job:
    """A background job (tests/background.py): FreeCADCmd runs the script ``script(tmp)`` in a new folder
    ``tmp``, after ``files`` (name there -> file) are copied into it; its result is ``(tmp, the run)``.
    ``name`` names the folder and the script (``NAME_probe.py``: FreeCADCmd imports a script by its name)."""

    def work() -> tuple[Path, subprocess.CompletedProcess]:
        tmp = folder(name)
        for target, source in (files or {}).items():
            shutil.copy(source, tmp / target)
        path = tmp / f"{name}_probe.py"
        path.write_text(script(tmp))
        return tmp, run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(path)])

    return Job(name, work)


def aplan(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    """Run the command line ``aplan ARGS`` (its ``main``, in this process: FreeCAD still runs in its own, as it
    does from ``python -m planner``); fails the test when it fails, if ``check``."""
    done = run_aplan(*args)
    return succeeded(done) if check else done


def aplan_process(*args: str) -> subprocess.CompletedProcess:
    """``aplan ARGS`` in a process of its own, unchecked: what a background job (tests/background.py) runs,
    since ``aplan`` in this process redirects the standard output, which only the tests' thread may do."""
    done = run([sys.executable, "-m", "planner", *args])
    return subprocess.CompletedProcess(["aplan", *args], done.returncode, done.stdout, done.stderr)


def succeeded(done: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    """``done``, when ``aplan`` succeeded; fails the test with its output otherwise."""
    if done.returncode != 0:
        raise AssertionError(f"aplan {' '.join(done.args[1:])} failed ({done.returncode}):\n{done.stdout}\n"
                             f"{done.stderr}")
    return done


# Shared by the GUI test scripts (run inside the FreeCAD window; each defines OUT, result and imports json, os,
# traceback): write the result and leave at once; run a Qt-timer step, ending the run with its traceback.
GUI_HELPERS = '''
def finish(code):
    with open(OUT, "w") as handle:
        json.dump(result, handle)
    os._exit(code)


def guarded(step):
    def run():
        try:
            step()
        except Exception:
            result["error"] = traceback.format_exc()
            finish(1)
    return run
'''


# Shared by the GUI test scripts that drive the workbench (after GUI_HELPERS; needs QtCore and FreeCADGui): what
# the commands keep between them, and a step run once the workbench's background jobs have ended.
WORKBENCH_HELPERS = '''
def state():
    return FreeCADGui.getWorkbench("AplanWorkbench").state


def after_jobs(step):
    def wait():
        if state().jobs:
            QtCore.QTimer.singleShot(100, guarded(wait))
            return
        step()
    QtCore.QTimer.singleShot(100, guarded(wait))


def detect():
    # Detect opens its task panel (engine, the exact engine's time limit); OK starts it with the values shown.
    FreeCADGui.runCommand("Aplan_Detect")
    state().panel.accept()
'''


# Shared by the GUI test scripts that show task panels and dialogs (needs QtCore, QtGui and FreeCADGui): what
# is cut off in a panel at the width it has, and the task view's visible part, the root those checks start from.
LAYOUT_CHECK = '''
def _widget_name(widget):
    text = widget.text() if hasattr(widget, "text") and callable(widget.text) else ""
    return f"{type(widget).__name__} {widget.objectName() or repr(str(text)[:40])}"


def _inside_nested_scroll(widget, root):
    # Pictures in a scroll area of their own may scroll: only the root's own layout must fit.
    parent = widget.parentWidget()
    while parent is not None and parent is not root:
        if isinstance(parent, QtGui.QAbstractScrollArea) and widget is not parent:
            return True
        parent = parent.parentWidget()
    return False


def _indexes(model, parent=None, limit=200):
    parent = parent or QtCore.QModelIndex()
    for row in range(min(model.rowCount(parent), limit)):
        for column in range(model.columnCount(parent)):
            index = model.index(row, column, parent)
            yield index
            if column == 0:
                yield from _indexes(model, index, limit)


def _cut_cells(view, name):
    # A cell whose text as the view shows it (its delegate's displayText), wrapped as Qt wraps it (at break
    # opportunities, when the view wraps) at its column's width less the item's margins, is wider or taller
    # than the cell: it is elided or clipped.
    problems = []
    metrics, margin = view.fontMetrics(), 2 * (view.style().pixelMetric(QtGui.QStyle.PM_FocusFrameHMargin) + 1)
    wrap = int(QtCore.Qt.TextWordWrap) if view.wordWrap() else 0
    for index in _indexes(view.model()):
        data, rect = index.data(), view.visualRect(index)
        if not data or rect.width() <= 0 or (index.flags() & QtCore.Qt.ItemIsUserCheckable and
                                             index.data(QtCore.Qt.CheckStateRole) is not None):
            continue
        text = view.itemDelegate(index).displayText(data, QtCore.QLocale())
        needed = metrics.boundingRect(QtCore.QRect(0, 0, rect.width() - margin, 10 ** 5), wrap, text)
        if needed.height() > rect.height() or needed.width() > rect.width() - margin:
            problems.append(f"{name}: cell {data!r} needs {needed.width()}x{needed.height()} px, "
                            f"has {rect.width() - margin}x{rect.height()}")
    return problems


def cut_off(root):
    """What does not fit in ``root`` (a task view's viewport or a dialog) at its current width: a widget whose
    right edge is beyond the root's, a label without word wrap wider than its box, a word-wrapped label
    taller than its box, a button or tab whose text is wider than the button, a table or tree whose columns
    are wider than its viewport (a horizontal scroll bar), whose header text or cell text does not fit its
    column or cell (elided or clipped), a sideways scroll bar on the task view."""
    problems = []
    width = root.width()
    if isinstance(root.parentWidget(), QtGui.QAbstractScrollArea):
        bar = root.parentWidget().horizontalScrollBar()
        if bar.isVisible() and bar.maximum() > 0:
            problems.append(f"the task view scrolls sideways by {bar.maximum()} px")
    for widget in root.findChildren(QtGui.QWidget):
        if not widget.isVisibleTo(root) or widget.width() <= 0 or _inside_nested_scroll(widget, root):
            continue
        name = _widget_name(widget)
        right = widget.mapTo(root, QtCore.QPoint(widget.width(), 0)).x()
        if right > width:
            problems.append(f"{name}: right edge at {right} px, beyond the visible {width} px")
        if isinstance(widget, QtGui.QLabel) and widget.text() and widget.pixmap() is None:
            if widget.wordWrap():
                if widget.heightForWidth(widget.width()) > widget.height():
                    problems.append(f"{name}: wrapped text needs {widget.heightForWidth(widget.width())} px "
                                    f"of height, has {widget.height()}")
            elif widget.sizeHint().width() > widget.width():
                problems.append(f"{name}: text needs {widget.sizeHint().width()} px, has {widget.width()}")
        if isinstance(widget, QtGui.QAbstractButton) and widget.text():
            if widget.sizeHint().width() > widget.width():
                problems.append(f"{name}: text needs {widget.sizeHint().width()} px, has {widget.width()}")
        if isinstance(widget, (QtGui.QTableView, QtGui.QTreeView)):
            header = widget.horizontalHeader() if isinstance(widget, QtGui.QTableView) else widget.header()
            if header.length() > widget.viewport().width():
                problems.append(f"{name}: columns need {header.length()} px, "
                                f"the table shows {widget.viewport().width()}")
            problems += _cut_cells(widget, name)
            margin = 2 * header.style().pixelMetric(QtGui.QStyle.PM_HeaderMargin, None, header)
            for column in range(header.count()):
                text = str(header.model().headerData(column, QtCore.Qt.Horizontal) or "")
                needed = header.fontMetrics().horizontalAdvance(text) + margin
                if not header.isSectionHidden(column) and needed > header.sectionSize(column):
                    problems.append(f"{name}: header {text!r} needs {needed} px, has {header.sectionSize(column)}")
        if isinstance(widget, QtGui.QTabBar):
            for k in range(widget.count()):
                if widget.tabRect(k).right() > widget.width():
                    problems.append(f"{name}: tab {widget.tabText(k)!r} beyond the tab bar")
    return problems


def broken_words(root):
    """What a person would read broken or cut in ``root``'s labels and lists (a task view's viewport or a
    dialog): a word (text between spaces) wider than its label's text width (Qt breaks it inside, the
    "cabi / n_d / oor_ / 001" of a narrow column), a zero-width break opportunity inside a name, a list entry
    (check box and text) wider than its list."""
    problems = []
    for widget in root.findChildren(QtGui.QWidget):
        if not widget.isVisibleTo(root) or widget.width() <= 0 or _inside_nested_scroll(widget, root):
            continue
        name = _widget_name(widget)
        if isinstance(widget, QtGui.QLabel) and widget.text() and widget.pixmap() is None:
            text, width = widget.text(), widget.contentsRect().width()
            if "\u200b" in text:
                problems.append(f"{name}: break opportunities inside names")
            for word in text.split():
                if widget.fontMetrics().horizontalAdvance(word) > width:
                    problems.append(f"{name}: {word!r} needs {widget.fontMetrics().horizontalAdvance(word)} px, "
                                    f"the label is {width} px wide: it breaks inside the word")
        if isinstance(widget, QtGui.QListView):
            option = QtGui.QStyleOptionViewItem()
            option.initFrom(widget.viewport())
            for row in range(widget.model().rowCount()):
                index = widget.model().index(row, 0)
                needed = widget.itemDelegate(index).sizeHint(option, index).width()
                if needed > widget.viewport().width():
                    problems.append(f"{name}: entry {index.data()!r} needs {needed} px, the list shows "
                                    f"{widget.viewport().width()}")
    return problems


def task_view_viewport():
    """The visible part of the combo view's task panel (FreeCAD's TaskView is a QScrollArea)."""
    views = [w for w in FreeCADGui.getMainWindow().findChildren(QtGui.QScrollArea)
             if type(w).__name__ == "TaskView" or w.metaObject().className() == "Gui::TaskView::TaskView"]
    return views[0].viewport() if views else None
'''
