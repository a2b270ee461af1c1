"""View provider of the APLAN analysis (GUI only): its icon in the tree; double-click opens the diagrams."""
from __future__ import annotations

from . import icon_path

__all__ = ["AnalysisViewProvider"]


class AnalysisViewProvider:
    """Shows the analysis with the APLAN icon; stores nothing."""

    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        self.Object = vobj.Object

    def getIcon(self):
        return icon_path("aplan.svg")

    def doubleClicked(self, vobj):
        import FreeCADGui

        FreeCADGui.runCommand("Aplan_Diagrams")
        return True

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None

    dumps, loads = __getstate__, __setstate__
