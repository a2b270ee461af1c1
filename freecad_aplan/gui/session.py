"""The session task panel: ``aplan session --demo`` in the simulated camera cell, from the workbench.

The designer picks a level (a workstation; all of them bottom-up), the source (the simulated camera cell, or
the operator's picks typed in the panel: ``--keyboard``), the full sequence the simulated operator follows
and the online planner's expansions per decision, and runs it: the session runs in a background job
(``batch.py session``: :func:`freecad_aplan.sessions.run_simulated_session`, the command line in-process), its
output lines show in the panel as it goes, Cancel ends it, and the belief plot of the last level shows in the
panel when it ends. Nothing in the document changes.

A keyboard session shows what the command line's keyboard prompt shows, in a read-only box: what the robot
does at each step, what the operator could pick now, the prompt, a line refused and why (with the parts and
tools there are), each step's belief and the robot's next action. The picks the operator could make are
offered in a list (and "nothing"): choosing one puts its line in the picks field, a double click or Send sends
it, so nothing needs typing exactly; any other line (a wrong pick, ``apart PART...``, ``q``) can be typed.

The decision model and the operator's habits (``--model NAME --habits FILE``; issue 23) are chosen in the
panel too, checked before a session starts, and learned from the panel's sessions
(:mod:`freecad_aplan.gui.session_habits`).
"""
from __future__ import annotations

import os
import tempfile

import FreeCADGui
from PySide import QtCore, QtGui

from planner.defaults import ONLINE_EXPANSIONS, PRODUCT_FILE

from .. import workflow
from ..sessions import ALL_LEVELS, base_part_in, is_prompt, level_choices, level_of, offered_picks, typed_pick
from .layout import button_rows, narrow_combo, panel_layout, stacked_field, wrapped_label
from .plan3d_panel import _text_box
from .session_habits import HabitsChooser

#: Lines of the keyboard prompt's box (it scrolls; the last line, the prompt, stays in view).
PROMPT_LINES = 11

__all__ = ["SessionPanel", "ask_level"]


class SessionPanel:
    """The task panel of one product (the analysis' ``product``, a resolved :class:`~planner.product.Product`).

    ``run()`` starts the session of the selected level, ``cancel()`` ends it; ``lines`` holds the run's output
    lines so far (the last one shows in the panel), ``result`` the job's answer once it ended (``{"command",
    "assembled", "levels": [...]}``), ``error`` its message when it failed. ``document_file``: the document's
    file, beside which Learn from sessions keeps the habits; ``logs`` the (level, log) of every session run,
    ``learned`` those whose steps are in the habits file already.
    """

    def __init__(self, product, base_part: str | None, jobs: list, document_file: str | None = None):
        from planner.product import save_product

        self.product, self.base_part, self.jobs = product, base_part, jobs
        self.job, self.result, self.error, self.lines, self.running = None, None, None, [], None
        self.logs, self.learned = [], set()
        self.scrolled = False
        self.folder = tempfile.mkdtemp(prefix="aplan-session-")
        self.product_file = os.path.join(self.folder, PRODUCT_FILE)
        save_product(product, self.product_file)
        self.levels = level_choices(product)
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanSessionPanel")
        self.form.setWindowTitle("APLAN: session")
        layout = panel_layout(self.form)
        layout.addWidget(wrapped_label("A simulated camera cell: an operator follows a full sequence on a rendered "
                                       "tray, the robot decides from what the camera sees (aplan session --demo); "
                                       "or you type the operator's picks (--keyboard)."))
        self.level = narrow_combo(QtGui.QComboBox())
        self.level.setObjectName("AplanSessionLevel")
        for choice in self.levels:
            self.level.addItem(choice.label, choice.id)
        if len(self.levels) > 1:
            self.level.addItem(f"{ALL_LEVELS}, bottom-up", ALL_LEVELS)
        stacked_field(layout, "Level (workstation)", self.level)
        self.source = narrow_combo(QtGui.QComboBox())
        self.source.setObjectName("AplanSessionSource")
        self.source.addItem("simulated camera cell", "demo")
        self.source.addItem("keyboard: type the operator's picks", "keyboard")
        stacked_field(layout, "Observations from", self.source)
        self.demo = _column(layout)  # what only the simulated cell needs
        self.sequence = QtGui.QSpinBox()
        self.sequence.setObjectName("AplanSessionSequence")
        self.sequence.setRange(0, 10**6)
        stacked_field(self.demo.layout(), "Full sequence the operator follows (by rank)", self.sequence)
        self.expansions = QtGui.QSpinBox()
        self.expansions.setObjectName("AplanSessionExpansions")
        self.expansions.setRange(1, 10**6)
        self.expansions.setValue(ONLINE_EXPANSIONS)
        stacked_field(layout, "Online planner: expansions per decision", self.expansions)
        self.habits = HabitsChooser(layout, document_file, self.folder, self.learn_habits)
        self.habits.offer_learned(self.selected_level())
        self.level.currentIndexChanged.connect(lambda *_: self.habits.offer_learned(self.selected_level()))
        self.run_button = QtGui.QPushButton("Run session")
        self.run_button.setObjectName("AplanRunSession")
        self.run_button.clicked.connect(self.run)
        self.cancel_button = QtGui.QPushButton("Cancel session")
        self.cancel_button.setObjectName("AplanCancelSession")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel)
        layout.addWidget(button_rows(self.run_button, self.cancel_button))
        self.keyboard = _column(layout)  # the keyboard session: its prompt, the picks offered, the line sent
        self.prompt = _text_box("AplanSessionPrompt", PROMPT_LINES)
        self.prompt.setToolTip("What aplan session --keyboard shows: the robot's step, what the operator could "
                               "pick, the prompt, a refused line and why, the belief after each step")
        self.keyboard.layout().addWidget(self.prompt)
        self.choices = QtGui.QListWidget()
        self.choices.setObjectName("AplanSessionChoices")
        self.choices.setToolTip("What the operator could pick now: choose one (a double click sends it)")
        self.choices.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.choices.setAlternatingRowColors(True)  # an entry is several lines: where one ends shows
        self.choices.currentItemChanged.connect(self._chosen)
        self.choices.itemDoubleClicked.connect(lambda item: (self._chosen(item), self.send_picks()))
        stacked_field(self.keyboard.layout(), "Picks (a double click sends):", self.choices)
        self.picks = QtGui.QLineEdit()
        self.picks.setObjectName("AplanSessionPicks")
        self.picks.setPlaceholderText("or type picks (Enter sends)")
        self.picks.setToolTip("What the operator picked: part and tool ids (empty: nothing; apart PART...: came off; "
                              "q: stop); Enter or Send sends it")
        self.picks.returnPressed.connect(self.send_picks)
        self.send_button = QtGui.QPushButton("Send picks")
        self.send_button.setObjectName("AplanSendPicks")
        self.send_button.clicked.connect(self.send_picks)
        self.keyboard.layout().addWidget(self.picks)
        self.keyboard.layout().addWidget(button_rows(self.send_button))
        self.source.currentIndexChanged.connect(lambda *_: self._show_source())
        self._show_source()
        self._keyboard(False)
        self.progress = QtGui.QProgressBar()
        self.progress.setObjectName("AplanSessionProgress")
        self.progress.setRange(0, 1)
        self.progress.setValue(0)
        layout.addWidget(self.progress)
        self.status = wrapped_label("", "AplanSessionStatus")
        layout.addWidget(self.status)
        self.plot = QtGui.QLabel()
        self.plot.setObjectName("AplanSessionPlot")
        self.plot.setAlignment(QtCore.Qt.AlignHCenter | QtCore.Qt.AlignTop)
        layout.addWidget(self.plot)
        layout.addStretch(1)

    def getStandardButtons(self):
        return int(QtGui.QDialogButtonBox.Close)

    def selected_level(self) -> str | None:
        return self.level.currentData()

    def _show_source(self) -> None:
        """The fields of the source chosen: the sequence for the simulated cell, the prompt for the keyboard."""
        keyboard = self.source.currentData() == "keyboard"
        self.demo.setVisible(not keyboard)
        self.keyboard.setVisible(keyboard)

    def _keyboard(self, running: bool) -> None:
        for widget in (self.picks, self.send_button, self.choices):
            widget.setEnabled(running)

    def _chosen(self, item) -> None:
        if item is not None:
            self.picks.setText(item.data(QtCore.Qt.UserRole))

    def offer(self, picks: list[str]) -> None:
        """List ``picks`` (observations as text, from the keyboard's prompt) and "nothing" as the choices, each
        entry one name per line (a name is never broken at the panel's width), its line to send as data."""
        self.choices.clear()
        for pick in picks:
            names = [f"{n.strip('[]')} (tool)" if n.startswith("[") else n for n in pick.split("+")]
            item = QtGui.QListWidgetItem("\n+ ".join(names))
            item.setData(QtCore.Qt.UserRole, typed_pick(pick))
            self.choices.addItem(item)
        nothing = QtGui.QListWidgetItem("nothing (a blank step)")
        nothing.setData(QtCore.Qt.UserRole, "")
        self.choices.addItem(nothing)
        rows = sum(self.choices.sizeHintForRow(r) for r in range(min(self.choices.count(), 3)))
        self.choices.setFixedHeight(rows + 2 * self.choices.frameWidth() + 4)  # three entries; the list scrolls

    def send_picks(self) -> None:
        """Send the typed picks to the keyboard session running (one step of the operator)."""
        if self.job is not None and self.running == "keyboard":
            self.lines.append(f"picked: {self.picks.text()}")
            self.prompt.appendPlainText(f"> {self.picks.text()}")
            self.job.send(self.picks.text())
            self.picks.clear()
            self.choices.clear()  # the next step's choices come with its prompt

    def run(self) -> None:
        """Start the selected level's session in the background (a second one waits for the first)."""
        from .jobs import BackgroundJob

        if self.job is not None:
            return
        level = self.selected_level()
        if not self.habits.check(self.product_file, level):  # refused: shown under the habits file, nothing runs
            self.status.setText("not started: " + self.habits.note.text())
            _scroll_to(self.habits.box)
            return
        self.result, self.error, self.lines = None, None, []
        count = len(self.levels) if level == ALL_LEVELS else 1
        self.progress.setRange(0, count)
        self.progress.setValue(0)
        self.plot.clear()
        self.prompt.clear()
        self.choices.clear()
        self.scrolled = False
        self.status.setText(f"starting the session of {level or 'the product'}")
        # the designer's base part for the level that holds it (every level at once: each starts anywhere)
        base = self.base_part if len(self.levels) == 1 else None if level == ALL_LEVELS else base_part_in(
            level_of(self.product, level), self.base_part)
        run = tempfile.mkdtemp(prefix="run-", dir=self.folder)
        job = {"action": "session", "product_file": self.product_file, "folder": run, "level": level,
               "sequence": self.sequence.value(), "expansions": self.expansions.value(),
               "base_part": base, "source": self.source.currentData(), "habits": self.habits.habits(),
               "model": self.habits.selected_model()}
        self.job = BackgroundJob(f"Session of {level or 'the product'}", workflow.worker_command("session"), job,
                                 self._done, self._failed, self.jobs, FreeCADGui.getMainWindow(),
                                 on_progress=self._progress)
        self.running = job["source"]  # a keyboard session's picks go to the job's input
        self._started(job["source"] == "keyboard")
        self.job.start()

    def _started(self, keyboard: bool) -> None:
        self.run_button.setEnabled(False)
        self.habits.learn.setEnabled(False)
        self.cancel_button.setEnabled(True)
        self._keyboard(keyboard)

    def learn_habits(self) -> None:
        """Learn from sessions: ``aplan habits`` on the logs of this panel's sessions of the selected level not
        learned yet, added to the habits file beside the document (a background job); that file goes into the
        habits field."""
        from .jobs import BackgroundJob

        level = self.selected_level()
        if self.job is not None:
            return
        if level == ALL_LEVELS:
            self.habits.show(f"habits are of one workstation's plan; choose a level, not {ALL_LEVELS}", error=True)
            return
        logs = [log for ran, log in self.logs if ran == level and log not in self.learned]
        if not logs:
            self.habits.show(f"no session of {level or 'the product'} to learn from yet: run one first", error=True)
            return
        output = self.habits.learned_file(level)
        job = {"action": "habits", "product_file": self.product_file, "level": level, "logs": logs, "output": output}
        self.running = "habits"
        self.habits.show(f"learning habits from {len(logs)} session log{'s' if len(logs) != 1 else ''}")
        self.job = BackgroundJob("Learn habits", workflow.worker_command("habits"), job,
                                 lambda result: self._learned(result, logs), self._failed_learning, self.jobs,
                                 FreeCADGui.getMainWindow(), on_progress=lambda line: None)
        self._started(False)
        self.job.start()

    def _learned(self, result: dict, logs: list[str]) -> None:
        self._ended()
        self.learned.update(logs)
        self.habits.field.setText(result["file"])
        self.habits.offered = result["file"]  # the level's learned file: another level's replaces it
        self.habits.show(f"learned {result['steps']:g} operator step{'s' if result['steps'] != 1 else ''} from "
                         f"{result['logs']} log{'s' if result['logs'] != 1 else ''}"
                         f"{', added to the file' if result['added'] else ''}: {os.path.basename(result['file'])}")

    def _failed_learning(self, message: str) -> None:
        self._ended()
        self.habits.show(message, error=True)

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()

    def _progress(self, line: str) -> None:
        self.lines.append(line)
        if line.startswith("level ") and " of " in line:  # "level sa2 (1 of 5): ..." starts a level
            self.progress.setValue(int(line.split("(", 1)[1].split(" of ")[0]) - 1)
        if self.running == "keyboard":  # the prompt's lines as the command line shows them
            self.prompt.appendPlainText(line.strip())
            self.prompt.verticalScrollBar().setValue(self.prompt.verticalScrollBar().maximum())
            picks = offered_picks(line)
            if picks is not None:
                self.offer(picks)
            if is_prompt(line):
                self.status.setText("waiting for the operator's picks")
                if not self.scrolled:  # the first prompt: the keyboard's part of the panel in view, once
                    self.scrolled = _scroll_to(self.keyboard)
                return
        self.status.setText(line)

    def _ended(self) -> None:
        self.job, self.running = None, None
        self._keyboard(False)
        self.habits.learn.setEnabled(True)
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)

    def _done(self, result: dict) -> None:
        self._ended()
        self.result = result
        self.logs += [(d["level"], d["log"]) for d in result["levels"]]
        self.progress.setValue(self.progress.maximum())
        ended = "; ".join(f"{d['level'] or 'product'}: {d['message']}" for d in result["levels"])
        self.status.setText(f"{'assembled' if result['assembled'] else 'not assembled'}. {ended}. "
                            f"Logs and plots: {os.path.dirname(result['levels'][-1]['log'])}")
        self.show_plot()

    def show_plot(self) -> None:
        """The belief plot of the last level that ran, at the panel's width (again after the panel was widened)."""
        if self.result is not None:
            picture = QtGui.QPixmap(self.result["levels"][-1]["plot"])
            scaled = picture.scaledToWidth(max(self.form.width(), 200), QtCore.Qt.SmoothTransformation)
            self.plot.setPixmap(scaled)
            self.plot.setMinimumHeight(scaled.height())  # whole: the task view scrolls rather than squeeze it

    def _failed(self, message: str) -> None:
        self._ended()
        self.error = message
        self.status.setText(message)

    def close(self) -> bool:
        """Close the panel, ending a session still running; the logs and plots stay in :attr:`folder`."""
        self.cancel()
        FreeCADGui.Control.closeDialog()
        return True

    def accept(self) -> bool:
        return self.close()

    def reject(self) -> bool:
        return self.close()


def _scroll_to(widget: QtGui.QWidget) -> bool:
    """Scroll the task view (the scroll area around ``widget``) so that ``widget``'s top is at the top of its
    visible part, as far as it scrolls; False when ``widget`` is in no scroll area."""
    scroll = widget.parentWidget()
    while scroll is not None and not isinstance(scroll, QtGui.QScrollArea):
        scroll = scroll.parentWidget()
    if scroll is None or scroll.widget() is None:
        return False
    for _ in range(3):  # the layouts asked for (a list just filled, a note shown) first: how far it scrolls
        QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.LayoutRequest)
    bar = scroll.verticalScrollBar()
    bar.setValue(min(bar.maximum(), widget.mapTo(scroll.widget(), QtCore.QPoint(0, 0)).y()))
    return True


def _column(layout: QtGui.QBoxLayout) -> QtGui.QWidget:
    """A widget added to ``layout`` holding a column of its own, without margins (shown or hidden as one)."""
    column = QtGui.QWidget()
    inner = QtGui.QVBoxLayout(column)
    inner.setContentsMargins(0, 0, 0, 0)
    layout.addWidget(column)
    return column


def ask_level(product) -> tuple[bool, str | None]:
    """(chosen, level): for a product of several workstations the level the designer picks
    (:func:`freecad_aplan.sessions.level_choices`; chosen False when cancelled), else (True, None)."""
    choices = level_choices(product)
    if len(choices) == 1:
        return True, None
    labels = [c.label for c in choices]
    label, ok = QtGui.QInputDialog.getItem(FreeCADGui.getMainWindow(), "APLAN level",
                                           "Workstation (level) whose decision model to use", labels, 0, False)
    return bool(ok), choices[labels.index(label)].id if ok else None
