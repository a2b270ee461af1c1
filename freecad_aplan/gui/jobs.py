"""Background jobs of the workbench: ``batch.py`` in a separate process, with a progress dialog and Cancel.

The process runs through ``QProcess``, so FreeCAD's event loop keeps running (the GUI never freezes) and
Cancel simply kills the process: its work happens in a temporary folder, so nothing reaches the document.
The job and its answer follow :mod:`freecad_aplan.protocol`; progress lines update the dialog.
"""
from __future__ import annotations

import time

from PySide import QtCore, QtGui

from ..protocol import JOB_VARIABLE, encode_job, read_answer, read_note, read_progress

__all__ = ["BackgroundJob"]


class BackgroundJob(QtCore.QObject):
    """Run ``command`` (program and script) on ``job`` (the batch action's JSON) in the background.

    ``on_done(result)`` is called with the job's JSON result, ``on_failed(message)`` with a readable message
    (also when cancelled: ``cancelled`` is then True). Both run in the GUI thread. While it runs, the job is
    in the list ``running`` (the workbench's, so that it can wait for its jobs). ``on_progress(text)``, when
    given, gets each note line and the job shows no dialog of its own: a panel shows the progress and offers
    :meth:`cancel` instead.
    """

    def __init__(self, title: str, command: list[str], job: dict, on_done, on_failed, running: list,
                 parent=None, on_progress=None):
        super().__init__(parent)
        self.title, self.on_done, self.on_failed, self.on_progress = title, on_done, on_failed, on_progress
        self.running = running
        self.cancelled = False
        self.output = ""
        self.started = time.monotonic()
        self.progress_text, self._partial = "", ""
        self.process = QtCore.QProcess(self)
        environment = QtCore.QProcessEnvironment.systemEnvironment()
        environment.insert(JOB_VARIABLE, encode_job(job))
        self.process.setProcessEnvironment(environment)
        self.process.setProcessChannelMode(QtCore.QProcess.MergedChannels)
        self.process.readyReadStandardOutput.connect(self._read)
        self.process.finished.connect(self._finished)
        self.process.errorOccurred.connect(self._error)
        self.dialog = QtGui.QProgressDialog(title, "Cancel", 0, 0, parent)
        self.dialog.setObjectName("AplanJobProgress")
        self.dialog.setWindowTitle("APLAN")
        self.dialog.setWindowModality(QtCore.Qt.WindowModal)
        self.dialog.setMinimumDuration(0)
        self.dialog.canceled.connect(self.cancel)
        if on_progress is not None:  # a panel shows the progress: no dialog (Qt shows one after its minimum duration)
            self.dialog.reset()
        self.timer = QtCore.QTimer(self)
        self.timer.timeout.connect(self._tick)
        self.program, self.arguments = command[0], command[1:]

    def start(self) -> "BackgroundJob":
        self.running.append(self)
        self.process.start(self.program, self.arguments)
        self.timer.start(500)
        if self.on_progress is None:
            self.dialog.show()
        return self

    def send(self, line: str) -> None:
        """Write ``line`` to the job's standard input (a keyboard session's picks)."""
        self.process.write((line.rstrip("\n") + "\n").encode("utf-8"))

    def cancel(self) -> None:
        """Stop the job; nothing it computed is kept."""
        if self not in self.running:
            return
        self.cancelled = True
        self.process.kill()

    def _tick(self) -> None:
        seconds = time.monotonic() - self.started
        self.dialog.setLabelText(f"{self.title}\n{seconds:.0f} s{self.progress_text}")

    def _read(self) -> None:
        chunk = bytes(self.process.readAllStandardOutput()).decode("utf-8", "replace")
        self.output += chunk
        # whole lines only: a chunk may end inside a line (its rest comes with the next chunk)
        text = self._partial + chunk
        cut = max(text.rfind("\n"), text.rfind("\r")) + 1  # a line ends at either (a progress line at \r)
        lines, self._partial = text[:cut].splitlines(), text[cut:]
        shown = self.progress_text
        for line in lines:
            progress = read_progress(line)
            if progress is not None:
                self.progress_text = f"  (bounds {progress[1]} .. {progress[2]})"
            note = read_note(line)
            if note is not None:  # any other job's progress: the last note line
                self.progress_text = f"\n{note}"
                if self.on_progress is not None:
                    self.on_progress(note)
        if self.progress_text != shown:  # the label shows a new note at once, not at the next tick
            self._tick()

    def _close(self) -> None:
        self.timer.stop()
        if self in self.running:
            self.running.remove(self)
        self.dialog.canceled.disconnect(self.cancel)
        self.dialog.close()

    def _error(self, error) -> None:
        if error == QtCore.QProcess.FailedToStart:
            self._close()
            self.on_failed(f"{self.title}: cannot start {self.program} ({self.process.errorString()})")

    def _finished(self, *args) -> None:
        self._read()
        self._close()
        if self.cancelled:
            self.on_failed(f"{self.title}: cancelled; nothing was changed")
            return
        answer = read_answer(self.output)
        if answer is not None:
            if answer.error is not None:
                self.on_failed(answer.error)
            else:
                self.on_done(answer.result)
            return
        tail = "\n".join(self.output.strip().splitlines()[-10:])
        self.on_failed(f"{self.title}: the job gave no result (exit code {self.process.exitCode()}); its last output:\n{tail}")
