"""The operator habits of the session panel (issue 23, docs/habits.md): the model choice, the habits file and
learning habits from the panel's session logs.

- The model choice lists the command line's default (no ``--model``: the habits' model with a habits file, the
  paper's without) and each named model of the planner (:func:`freecad_aplan.sessions.model_names`, described by
  :func:`~freecad_aplan.sessions.model_label`): a preset added to the planner is offered here unchanged.
- The habits file (optional) is typed or chosen (Browse); it starts as the file the panel learns into, beside the
  document (:func:`~freecad_aplan.sessions.habits_path`), when that exists.
- Before a session starts, :meth:`HabitsChooser.check` reads the file through the planner's reader and checks it
  against the level's plan (:func:`~freecad_aplan.sessions.check_habits`); a refusal (another product or version,
  a damaged file, a model that needs habits without a file) shows in red under the file, and nothing starts.
- Learn from sessions runs ``aplan habits`` on the logs of the panel's sessions of the selected level not
  learned yet (a background job: ``batch.py habits``), adding their counts to the file beside the document, and
  puts that file in the field.
"""
from __future__ import annotations

import os

from PySide import QtGui

from planner.errors import PlannerError

from ..sessions import ALL_LEVELS, DEFAULT_MODEL, check_habits, habits_path, model_label, model_names
from .layout import button_rows, narrow_combo, stacked_field, wrapped_label

__all__ = ["HabitsChooser", "ERROR_COLOUR"]

#: The colour of a refusal under the habits file (a dark red that reads on the light panel).
ERROR_COLOUR = "#b00020"


class HabitsChooser:
    """The model choice, habits file, Browse and Learn buttons and the note under them, in a column of their
    own (:attr:`box`) of the session panel. ``learn`` is called when Learn from sessions is clicked."""

    def __init__(self, layout: QtGui.QBoxLayout, document_file: str | None, folder: str, learn) -> None:
        self.document_file, self.folder, self.offered = document_file, folder, None
        self.box = QtGui.QWidget()
        inner = QtGui.QVBoxLayout(self.box)
        inner.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.box)
        self.model = narrow_combo(QtGui.QComboBox())
        self.model.setObjectName("AplanSessionModel")
        self.model.addItem(DEFAULT_MODEL, None)
        for name in model_names():
            self.model.addItem(model_label(name), name)
        self.model.setToolTip("aplan session --model: the paper's model, or one that uses the operator's habits "
                              "(docs/habits.md)")
        stacked_field(inner, "Decision model", self.model)
        self.field = QtGui.QLineEdit()
        self.field.setObjectName("AplanSessionHabits")
        self.field.setPlaceholderText("no habits file")
        self.field.setToolTip("aplan session --habits FILE: the operator's habits (learned from session logs)")
        stacked_field(inner, "Operator habits (optional)", self.field)
        self.browse = QtGui.QPushButton("Browse...")
        self.browse.setObjectName("AplanBrowseHabits")
        self.browse.clicked.connect(self.ask_file)
        self.learn = QtGui.QPushButton("Learn from sessions")
        self.learn.setObjectName("AplanLearnHabits")
        self.learn.setToolTip("aplan habits on the logs of this panel's sessions of the selected level, added to "
                              "the habits beside the document")
        self.learn.clicked.connect(learn)
        inner.addWidget(button_rows(self.browse, self.learn))
        self.note = wrapped_label("", "AplanSessionHabitsNote")
        inner.addWidget(self.note)
        self.note.hide()

    def selected_model(self) -> str | None:
        return self.model.currentData()

    def habits(self) -> str | None:
        return self.field.text().strip() or None

    def learned_file(self, level: str | None) -> str:
        """The file Learn from sessions writes for ``level``: beside the document."""
        return habits_path(self.document_file, level, self.folder)

    def offer_learned(self, level: str | None) -> None:
        """Put the learned file of ``level`` in the field, when it exists (learned in an earlier session) and the
        field is empty or holds the learned file of another level (offered here before: not the designer's)."""
        if self.habits() is not None and self.habits() != self.offered:
            return
        path = self.learned_file(level)
        self.offered = path if level != ALL_LEVELS and os.path.isfile(path) else None
        self.field.setText(self.offered or "")

    def ask_file(self) -> None:
        import FreeCADGui

        path, _ = QtGui.QFileDialog.getOpenFileName(FreeCADGui.getMainWindow(), "Operator habits", "",
                                                    "Habits (*.json);;All files (*)")
        if path:
            self.field.setText(path)

    def check(self, product_file: str, level: str | None) -> bool:
        """Whether a session of ``level`` may start with the chosen habits and model
        (:func:`~freecad_aplan.sessions.check_habits`); a refusal shows under the file, in red."""
        try:
            found = check_habits(product_file, level, self.habits(), self.selected_model())
        except PlannerError as exc:
            self.show(str(exc), error=True)
            return False
        self.show("" if found is None else f"habits of {found.product}: {len(found.counts)} state edges counted, "
                                           f"prior {found.prior:g} per {found.prior_per}")
        return True

    def show(self, text: str, error: bool = False) -> None:
        """``text`` under the habits file (red for a refusal); nothing shown for no text. The file's folder is
        left out (the field above shows it): a long path would break inside, unreadable at the panel's width."""
        path = self.habits()
        if path:
            text = text.replace(path, os.path.basename(path))
        self.note.setText(text)
        self.note.setStyleSheet(f"color: {ERROR_COLOUR}" if error else "")
        self.note.setVisible(bool(text))
