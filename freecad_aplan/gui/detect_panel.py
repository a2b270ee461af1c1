"""Detect's task panel: the geometry engine and the exact engine's time limit, then the detection.

The panel shows the analysis' ``Engine`` and ``OcctTimeLimit`` (:mod:`freecad_aplan.intent`; the command line's
``--engine`` and ``--time-limit``, default :data:`~planner.defaults.OCCT_TIME_LIMIT` s). OK checks them
(:func:`freecad_aplan.workflow.detection_settings`: a time limit that is not a finite number of seconds above 0
is refused in red under the fields, the panel stays open and nothing runs), stores them in the analysis when
they changed (one undoable step) and starts the detection in the background (``start()``, the command's); the
exact engine's progress lines show in the job's progress dialog as they come. Cancel changes nothing.
"""
from __future__ import annotations

import FreeCADGui
from PySide import QtGui

from planner.errors import PlannerError

from .. import workflow
from ..intent import ENGINES, read_intent, update_intent
from .layout import narrow_combo, panel_layout, stacked_field, wrapped_label
from .session_habits import ERROR_COLOUR

__all__ = ["DetectPanel"]


class DetectPanel:
    """The task panel of ``analysis``'s detection; ``start()`` runs it (with the settings stored) after OK."""

    def __init__(self, analysis, start):
        self.analysis, self.start = analysis, start
        intent = read_intent(analysis)
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanDetectPanel")
        self.form.setWindowTitle("APLAN: detect")
        layout = panel_layout(self.form)
        layout.addWidget(wrapped_label("Contacts and obstruction diagrams of the components, computed in the "
                                       "background (aplan analyze); the parts are not moved. OK starts it."))
        self.engine = narrow_combo(QtGui.QComboBox())
        self.engine.setObjectName("AplanDetectEngine")
        self.engine.addItems(list(ENGINES))
        self.engine.setCurrentIndex(max(self.engine.findText(intent.engine), 0))
        self.engine.setToolTip("mesh: the meshes decide every pair; occt: the meshes settle the pairs far apart, "
                               "the exact shapes (OCCT) the others (--engine)")
        stacked_field(layout, "Engine", self.engine)
        self.time_limit = QtGui.QLineEdit(f"{intent.occt_time_limit:.15g}")  # read back exactly
        self.time_limit.setObjectName("AplanDetectTimeLimit")
        self.time_limit.setToolTip("CPU seconds OCCT spends on all its pairs (the occt engine's, and those of parts "
                                   "without a good mesh); the pairs left then keep the mesh engine's answer and "
                                   "are reported (--time-limit)")
        stacked_field(layout, "Exact engine: time limit (s)", self.time_limit)
        self.note = wrapped_label("", "AplanDetectMessage")
        self.note.setVisible(False)
        layout.addWidget(self.note)
        layout.addStretch(1)

    def say(self, text: str, error: bool = False) -> None:
        """``text`` under the fields (red for a refusal)."""
        self.note.setText(text)
        self.note.setStyleSheet(f"color: {ERROR_COLOUR}" if error else "")
        self.note.setVisible(bool(text))

    def accept(self) -> bool:
        """Check the fields; refused: the reason in red, the panel open, nothing run. Else store them (when
        they changed), close the panel and start the detection."""
        try:
            settings = workflow.detection_settings(self.engine.currentText(), self.time_limit.text())
        except PlannerError as exc:
            self.say(str(exc), error=True)
            return False
        intent = read_intent(self.analysis)
        if (intent.engine, intent.occt_time_limit) != (settings["engine"], settings["occt_time_limit"]):
            update_intent(self.analysis, "detection settings", **settings)
        FreeCADGui.Control.closeDialog()
        self.start()
        return True

    def reject(self) -> bool:
        FreeCADGui.Control.closeDialog()
        return True
