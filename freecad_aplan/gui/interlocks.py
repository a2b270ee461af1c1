"""The interlocks task panel: the interlock rules' proposals of the last detection, and the support contacts it
proposes (a part that would float in the part whose cavity holds it), each shown in the 3D view while it is
selected, for the designer to accept or reject.

Thin Qt over :mod:`freecad_aplan.interlocks` (the logic, also run without the GUI by the tests). The list
shows each proposal's pair, the rule and its decision, each on a line of its own so that it reads at the task
view's default width (as the fasteners panel); below it, the selected proposal's pair, rule, what it would
do and its decision, and Accept / Reject. While one is selected, the 3D view shows the relation
(:class:`~freecad_aplan.gui.plan3d.PlanView`: colours and an arrow in the scene graph only, restored when the
selection changes or the panel closes). OK stores the decisions in one undo step; Cancel changes nothing.
"""
from __future__ import annotations

from types import MappingProxyType

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from .. import interlocks
from ..intent import IntentError, read_intent
from ..plan3d import COLOURS, interlock_looks
from .layout import button_rows, panel_layout, stacked_field, wrapped_label
from .plan3d import PlanView, restore_when_gone
from .plan3d_panel import _text_box

__all__ = ["InterlocksPanel", "RULE_NAMES", "show_interlock"]

#: What each rule is called in the panel (planner.assembly.interlocks.RULES).
RULE_NAMES = MappingProxyType({"overlap": "overlap axis", "direction": "contact direction",
                               "component": "one component", "support": "support contact"})
_SHOWN = MappingProxyType({None: "not decided", "accepted": "accepted", "rejected": "rejected"})


def show_interlock(view: PlanView, proposal: dict) -> None:
    """``proposal`` in the 3D view: with a direction, the part that leaves orange, the other blue, an arrow from
    the first along the direction; one component or a support contact: the two parts highlighted together. The
    others dimmed."""
    a, b = proposal["parts"]
    if proposal.get("direction") is None:
        view.show_parts([frozenset((a, b))])
        return
    leaving = proposal.get("leaving", a)
    other = b if leaving == a else a
    view._begin().apply(view.objects, None, interlock_looks(view.objects, leaving, other))
    view._add_arrow(view._centre([leaving]), tuple(0.5 * view.spacing * c for c in proposal["direction"]),
                    COLOURS["moving"])


def _entry(proposal: dict, decision) -> str:
    a, b = proposal["parts"]
    pair = f"{a} rests in {b}" if proposal["rule"] == "support" else f"{a}\n+ {b}"
    where = f"\nat level {proposal['level']}" if proposal.get("level") else ""  # a line of its own: the list's width
    return f"{pair}{where}\n{RULE_NAMES.get(proposal['rule'], proposal['rule'])}: {_SHOWN[decision]}"


def _button(text: str, name: str, slot) -> QtGui.QPushButton:
    button = QtGui.QPushButton(text)
    button.setObjectName(name)
    button.clicked.connect(slot)
    return button


class InterlocksPanel:
    """The proposals (module docstring); :attr:`decisions` the designer's choices not stored yet (row ->
    ``accepted`` or ``rejected``)."""

    def __init__(self, analysis):
        self.analysis = analysis
        self.proposals, unresolved = interlocks.interlock_report(analysis)
        self.decisions: dict[int, str] = {}
        self.view = PlanView(analysis.Document, read_intent(analysis).diagrams)
        self.form = QtGui.QWidget()
        self.form.setObjectName("AplanInterlocksPanel")
        self.form.setWindowTitle("APLAN: interlocks")
        layout = panel_layout(self.form)
        supports = sum(p["rule"] == "support" for p in self.proposals)
        count = len(self.proposals) - supports
        found = ([f"{count} interlocked pair{'s' if count != 1 else ''} the rules would free"] if count else []) + (
            [f"{supports} support contact{'s' if supports != 1 else ''} for parts that would float"] if supports else [])
        self.summary = wrapped_label(
            (f"{' and '.join(found)}; select one to see it in 3D, then accept or reject it. A rejected interlock is "
             "refused when planning; a rejected support contact is not added." if found else
             "No interlocked pair or support contact to decide on.") +
            "".join(f"\nnot freed: {line}" for line in unresolved), "AplanInterlocksSummary")
        layout.addWidget(self.summary)
        self.list = QtGui.QListWidget()
        self.list.setObjectName("AplanInterlocksList")
        self.list.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        self.list.setMinimumHeight(120)
        for proposal in self.proposals:
            item = QtGui.QListWidgetItem(_entry(proposal, proposal["decision"]))
            item.setToolTip(proposal["text"])
            self.list.addItem(item)
        self.list.currentRowChanged.connect(self.show)
        layout.addWidget(self.list)
        details = QtGui.QGroupBox("selected proposal")
        details.setObjectName("AplanInterlockDetails")
        inner = QtGui.QVBoxLayout(details)
        self.pair, self.rule, self.decision = (wrapped_label("", name) for name in (
            "AplanInterlockPair", "AplanInterlockRule", "AplanInterlockDecision"))
        # The rule's sentence is long (volumes, directions, names): a box of its own that never asks the task
        # view for more room than it has (a wrapped label did, and was cut).
        self.does = _text_box("AplanInterlockDoes", 8)
        for text, widget in (("pair:", self.pair), ("rule:", self.rule), ("would do:", self.does),
                             ("decision:", self.decision)):
            stacked_field(inner, text, widget)
        layout.addWidget(details)
        self.accept_button = _button("Accept", "AplanAcceptInterlock", lambda: self.decide("accepted"))
        self.reject_button = _button("Reject", "AplanRejectInterlock", lambda: self.decide("rejected"))
        layout.addWidget(button_rows(self.accept_button, self.reject_button))
        self.message = wrapped_label("", "AplanInterlocksMessage")
        layout.addWidget(self.message)
        restore_when_gone(self.form, self.view)
        if self.proposals:
            self.list.setCurrentRow(0)
        else:
            self.show(-1)

    def _decision(self, row: int):
        return self.decisions.get(row, self.proposals[row]["decision"])

    def show(self, row: int) -> None:
        """The proposal at ``row`` below the list and in the 3D view (nothing for no row)."""
        if not 0 <= row < len(self.proposals):
            for label in (self.pair, self.rule, self.decision):
                label.setText("")
            self.does.setPlainText("")
            self.accept_button.setEnabled(False)
            self.reject_button.setEnabled(False)
            self.view.restore()
            return
        proposal = self.proposals[row]
        self.pair.setText("\n".join(proposal["parts"]))
        self.rule.setText(RULE_NAMES.get(proposal["rule"], proposal["rule"]))
        self.does.setPlainText(proposal["text"])
        stored = proposal["decision"] == "accepted"  # applied already: undo takes it back
        self.decision.setText(_SHOWN[self._decision(row)] + (" (stored; Edit > Undo takes it back)" if stored else
                                                              "" if row not in self.decisions else " (on OK)"))
        self.accept_button.setEnabled(not stored)
        self.reject_button.setEnabled(not stored)
        show_interlock(self.view, proposal)

    def decide(self, decision: str, row: int | None = None) -> None:
        """Accept or reject the proposal at ``row`` (default: the selected one); stored on OK."""
        row = self.list.currentRow() if row is None else row
        if not 0 <= row < len(self.proposals) or self.proposals[row]["decision"] == "accepted":
            return
        self.decisions[row] = decision
        self.list.item(row).setText(_entry(self.proposals[row], decision))
        self.message.setText(f"{decision}: {' and '.join(self.proposals[row]['parts'])} (stored on OK)")
        self.show(row)

    def _close(self) -> None:
        self.view.restore()
        FreeCADGui.Control.closeDialog()

    def accept(self) -> bool:
        try:
            lines = interlocks.decide_interlocks(self.analysis, self.decisions)
        except IntentError as exc:
            self.message.setText(str(exc))
            return False
        for line in lines:  # one line per decision in the report view, as the command line says them
            FreeCAD.Console.PrintMessage(f"APLAN: {line}\n")
        self._close()
        return True

    def reject(self) -> bool:
        self._close()
        return True
