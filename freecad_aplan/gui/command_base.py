"""What every command of the workbench shares (:mod:`freecad_aplan.gui.commands`): the base class (resources,
an ``IsActive`` that never raises, errors the user can fix as one line in the report view), the
:class:`WorkbenchState` the commands keep between them, and the small dialogs they open."""
from __future__ import annotations

import os
import traceback

import FreeCAD
import FreeCADGui
from PySide import QtGui

from planner.errors import PlannerError

from .. import icon_path
from ..document import DocumentError
from ..intent import find_analysis, is_analysis

__all__ = ["WorkbenchState"]

PARAMETERS = "User parameter:BaseApp/Preferences/Mod/APLAN"


class WorkbenchState:
    """What the commands keep between them, for one workbench.

    ``panel``, ``plan_dialog``, ``belief_dialog``: the open task panel and dialogs (Qt destroys a window
    that nothing in Python refers to). ``plan``: what the last plan command showed (statistics and image
    paths). ``policy``: the path of the last policy saved by Solve (Simulate offers it). ``jobs``: the
    background jobs still running.
    """

    def __init__(self) -> None:
        self.panel = None
        self.plan_dialog = None
        self.belief_dialog = None
        self.plan: dict | None = None
        self.policy: str | None = None
        self.jobs: list = []


def _message(text: str, error: bool = True) -> None:
    """One line in the report view (and the status bar)."""
    (FreeCAD.Console.PrintError if error else FreeCAD.Console.PrintMessage)(f"APLAN: {text}\n")
    try:
        FreeCADGui.getMainWindow().statusBar().showMessage(f"APLAN: {text.splitlines()[0]}", 15000)
    except AttributeError:
        pass


def _guarded(action):
    """Run a command body; expected errors become a message, unexpected ones a message plus a log entry."""
    try:
        action()
    except PlannerError as exc:
        _message(str(exc))
    except Exception as exc:  # a bug: say so in one line, keep the details in the log
        _message(f"internal error ({type(exc).__name__}: {exc}); please report it")
        FreeCAD.Console.PrintLog(traceback.format_exc())


def _document():
    document = FreeCAD.ActiveDocument
    if document is None:
        raise DocumentError("no document is open: open an assembly first")
    return document


def _selected_objects() -> list:
    objects = [o for o in FreeCADGui.Selection.getSelection() if not is_analysis(o)]
    if not objects:
        raise DocumentError("nothing is selected: select parts in the 3D view or the tree first")
    return objects


class _Command:
    """Base: resources from the class attributes; active when there is a document (and an analysis).

    ``state`` is shared by the commands of one workbench (a command made alone gets its own).
    """

    name = ""
    menu = ""
    tooltip = ""
    needs_analysis = True

    def __init__(self, state: WorkbenchState | None = None):
        self.state = state if state is not None else WorkbenchState()

    def GetResources(self):
        return {"Pixmap": icon_path(f"{self.name}.svg"), "MenuText": self.menu, "ToolTip": self.tooltip}

    def IsActive(self):
        try:
            document = FreeCAD.ActiveDocument
            if document is None:
                return False
            return (find_analysis(document) is not None) if self.needs_analysis else True
        except Exception:  # IsActive must never raise (FreeCAD calls it all the time)
            return False

    def Activated(self):
        _guarded(self.run)

    def run(self):
        raise NotImplementedError


def _show_panel(state: WorkbenchState, panel) -> None:
    """Show ``panel`` in the task view, replacing any open one (kept in ``state`` so Qt does not drop it)."""
    FreeCADGui.Control.closeDialog()
    state.panel = panel
    FreeCADGui.Control.showDialog(panel)


def _save_path(title: str, filters: str, suffix: str) -> str | None:
    path, _ = QtGui.QFileDialog.getSaveFileName(FreeCADGui.getMainWindow(), title, "", filters)
    if not path:
        return None
    return path if os.path.splitext(path)[1] else path + suffix
