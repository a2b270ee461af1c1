"""The APLAN workbench's commands: small classes over the functions of :mod:`freecad_aplan.workflow`.

Each command has an icon (``resources/icons/<command>.svg``), a tooltip and an ``IsActive`` that never
raises. Errors the user can fix (no document, nothing selected, no solids, an analysis from a newer APLAN,
a cancelled job) are written to the report view and the status bar as one clear line; nothing in the
document changes except what the command is for. What the commands keep between them (open panels and
dialogs, the last plan and policy, running jobs) is a :class:`WorkbenchState` owned by the workbench.
"""
from __future__ import annotations

import os
import shutil
import tempfile

import FreeCAD
import FreeCADGui

from planner.defaults import PRODUCT_FILE

from .. import workflow
from . import session
from ..document import DocumentError
from ..intent import create_analysis, find_analysis, read_intent, update_intent
from .command_base import WorkbenchState, _Command, _document, _guarded, _message, _selected_objects, _show_panel
from .decision_commands import ExportBundle, ExportModel, Simulate, Solve

__all__ = ["COMMANDS", "WorkbenchState", "register"]


class CreateAnalysis(_Command):
    name, menu = "Aplan_CreateAnalysis", "Create analysis"
    tooltip = "Add an APLAN analysis to the document: it holds the designer intent (components, constraints, tags)"
    needs_analysis = False

    def IsActive(self):
        try:
            document = FreeCAD.ActiveDocument
            return document is not None and find_analysis(document) is None
        except Exception:
            return False

    def run(self):
        analysis = create_analysis(_document())
        _message(f"created {analysis.Label!r}; next: Detect contacts and obstructions", error=False)


class GroupComponent(_Command):
    name, menu = "Aplan_GroupComponent", "Group as one component"
    tooltip = ("Make the selected objects one component (a part of the product); "
               "with the objects of one group selected, ungroup them")

    def run(self):
        analysis = workflow.require_analysis(_document())
        names = [o.Name for o in _selected_objects()]
        groups = dict(read_intent(analysis).groups)
        owner = [g for g, members in groups.items() if set(names) <= set(members)]
        if owner:
            del groups[owner[0]]
            update_intent(analysis, f"ungroup {owner[0]}", groups=groups)
            _message(f"component {owner[0]!r} ungrouped", error=False)
            return
        if len(names) < 2:
            raise DocumentError("select two or more objects to group them into one component")
        labels = [FreeCAD.ActiveDocument.getObject(n).Label for n in names]
        name = "+".join(labels)
        groups = {g: [m for m in members if m not in names] for g, members in groups.items()}
        groups = {g: m for g, m in groups.items() if m}
        groups[name] = names
        update_intent(analysis, f"group {name}", groups=groups)
        _message(f"component {name!r} groups {', '.join(labels)}", error=False)


class ExcludeParts(_Command):
    name, menu = "Aplan_ExcludeParts", "Exclude / include parts"
    tooltip = "Leave the selected objects out of the product (e.g. fasteners); again to include them"

    def run(self):
        analysis = workflow.require_analysis(_document())
        names = [o.Name for o in _selected_objects()]
        excluded = list(read_intent(analysis).excluded)
        if all(n in excluded for n in names):
            excluded = [n for n in excluded if n not in names]
            update_intent(analysis, "include parts", excluded=excluded)
            _message(f"included again: {', '.join(names)}", error=False)
        else:
            excluded += [n for n in names if n not in excluded]
            update_intent(analysis, "exclude parts", excluded=excluded)
            _message(f"excluded: {', '.join(names)}", error=False)


class Detect(_Command):
    name, menu = "Aplan_Detect", "Detect contacts and obstructions"
    tooltip = ("Compute the connection and obstruction diagrams of the components in the background: choose the "
               "engine and the exact engine's time limit in the task panel, OK starts it (the other tolerances: "
               "the analysis' properties); the parts are not moved")

    def run(self):
        from .detect_panel import DetectPanel

        document = _document()
        analysis = workflow.require_analysis(document)
        workflow.check_detection(document)  # no solids, a bad intent: told at once, before the panel opens
        _show_panel(self.state, DetectPanel(analysis, lambda: _guarded(lambda: self.start(document, analysis))))

    def start(self, document, analysis):
        """Export the document's components and run the analysis' engine on them, in background jobs, with the
        settings the analysis holds (Detect's panel stored them); the diagrams are stored when both ended."""
        from ..dependencies import detection_engine
        from .jobs import BackgroundJob

        intent = read_intent(analysis)
        engine, note = detection_engine(intent.engine, workflow._mesh_python())  # occt without manifold3d
        if note:
            _message(f"warning: {note}", error=False)
        command = workflow.worker_command("analyze", engine)
        folder = tempfile.mkdtemp(prefix="aplan-detect-")
        try:  # quick checks here (no solids, a bad intent); the export itself runs in the background too
            copy, count = workflow.detection_copy(document, folder)
        except BaseException:
            shutil.rmtree(folder, ignore_errors=True)
            raise
        bundle = os.path.join(folder, "bundle")
        os.mkdir(bundle)
        parent = FreeCADGui.getMainWindow()

        def failed(message):
            shutil.rmtree(folder, ignore_errors=True)
            _message(message)

        def exported(result):
            for warning in result["warnings"]:
                _message(f"warning: {warning}", error=False)

            def done(found):
                try:
                    _guarded(lambda: self._store(analysis, bundle, found))
                finally:
                    shutil.rmtree(folder, ignore_errors=True)

            job = workflow.detection_job(bundle, engine, intent)
            limit = f", at most {intent.occt_time_limit:g} s on the exact shapes" if engine == "occt" else ""
            BackgroundJob(f"Detecting contacts and obstructions of {result['parts']} parts ({engine} engine{limit})",
                          command, job, done, failed, self.state.jobs, parent).start()

        job = {"action": "export", "model": copy, "folder": bundle, "redetect": True, "notes": True}
        BackgroundJob(f"Tessellating {count} components for the detection", workflow.worker_command("export"), job,
                      exported, failed, self.state.jobs, parent).start()

    @staticmethod
    def _store(analysis, folder, result):
        workflow.store_detection(analysis, folder)
        for note in result.get("undecided", []):  # each pair the exact engine left, the answer used (in Diagrams too)
            _message(f"warning: {note}", error=False)
        summary = result.get("summary")
        _message(f"{result['parts']} parts, {result['contacts']} contacts, {result['interferences']} "
                 f"interferences ({result['seconds']:.1f} s{f'; {summary}' if summary else ''}); see Diagrams",
                 error=False)


class Diagrams(_Command):
    name, menu = "Aplan_Diagrams", "Connection and obstruction diagrams"
    tooltip = "Inspect and edit the detected relations; selecting one highlights its two parts"

    def run(self):
        from .panels import DiagramsPanel

        analysis = workflow.require_analysis(_document())
        workflow.analysis_product(analysis)  # a clear message when nothing was detected yet
        _show_panel(self.state, DiagramsPanel(analysis))


class Interlocks(_Command):
    name, menu = "Aplan_Interlocks", "Interlocks"
    tooltip = ("Parts that block each other along every direction, and what the rules would do (an overlap's axis, "
               "a direction from the contacts, one component): see each in 3D, accept or reject it")

    def run(self):
        from ..interlocks import interlock_report
        from .interlocks import InterlocksPanel

        analysis = workflow.require_analysis(_document())
        interlock_report(analysis)  # a clear message when nothing was detected yet
        _show_panel(self.state, InterlocksPanel(analysis))


class Intent(_Command):
    name, menu = "Aplan_Intent", "Technical constraints, operation tags and base part"
    tooltip = ("Edit technical constraints; tag operations as unfavorable to humans, robot-capable, and their tool; "
               "choose the base part assembly starts from")

    def run(self):
        from planner import make_plan

        from .panels import IntentPanel

        analysis = workflow.require_analysis(_document())
        plan = make_plan(workflow.analysis_product(analysis), technical=False)
        _show_panel(self.state, IntentPanel(analysis, plan))


class Plan(_Command):
    name, menu = "Aplan_Plan", "Generate plan and statistics"
    tooltip = ("Build the AND/OR, state and intention graphs; show the statistics (as aplan stats) and pictures; "
               "for a product of several subassemblies, the figures per workstation (in the background)")

    def run(self):
        from .panels import PlanDialog

        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        if workflow.has_levels(product):
            self._levels(product)
            return
        folder = tempfile.mkdtemp(prefix="aplan-plan-")
        plan, statistics, images = workflow.plan_report(product, folder, base_part=workflow.analysis_base_part(analysis))
        figures = statistics.as_dict()
        if statistics.base_part:  # intentions and sequences are those that start from it
            figures["base part"] = statistics.base_part
        self.state.plan = {"statistics": figures, "images": images}
        _message(", ".join(f"{k} {v:,}" if isinstance(v, int) else f"{k} {v}" for k, v in figures.items()),
                 error=False)
        self.state.plan_dialog = PlanDialog(product.name, figures, images, FreeCADGui.getMainWindow())
        from .plan3d import add_parts_tab

        add_parts_tab(self.state.plan_dialog, plan, analysis)  # an operation or a state selected: its parts in 3D
        self.state.plan_dialog.show()

    def _levels(self, product):
        """The figures of every workstation, the total and flat, computed in a background job."""
        from planner.product import save_product

        from .jobs import BackgroundJob
        from .structure import LevelsDialog

        folder = tempfile.mkdtemp(prefix="aplan-levels-")
        path = os.path.join(folder, PRODUCT_FILE)
        save_product(product, path)

        def done(report):
            shutil.rmtree(folder, ignore_errors=True)
            self.state.plan = {"levels": report}
            total = report["total"]
            _message(f"{len(report['levels'])} workstations: " + ", ".join(
                f"{k} {'-' if v is None else format(v, ',')}" for k, v in total.items()), error=False)
            self.state.plan_dialog = LevelsDialog(product.name, report, FreeCADGui.getMainWindow())
            self.state.plan_dialog.show()

        def failed(message):
            shutil.rmtree(folder, ignore_errors=True)
            _message(message)

        BackgroundJob(f"Planning {len(product.subassemblies)} subassemblies and the top level",
                      workflow.worker_command("level-stats"), {"action": "level-stats", "product": path}, done,
                      failed, self.state.jobs, FreeCADGui.getMainWindow()).start()


class Plan3D(_Command):
    name, menu = "Aplan_Plan3D", "Plan in 3D"
    tooltip = ("Step through a full assembly sequence in the 3D view (an exploded view that collapses operation by "
               "operation), or the one a session log recorded; the document is restored when the panel closes")

    def run(self):
        from .plan3d_panel import Plan3DPanel

        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        _show_panel(self.state, Plan3DPanel(analysis, product, workflow.analysis_base_part(analysis)))


class Fasteners(_Command):
    name, menu = "Aplan_Fasteners", "Fasteners"
    tooltip = ("Tag the selected objects as fasteners (with their tool), untag them, or accept the planner's "
               "proposals (small parts joining two others, names such as screw or bolt)")

    def run(self):
        from .structure import FastenersPanel

        analysis = workflow.require_analysis(_document())
        workflow.analysis_product(analysis)  # a clear message when nothing was detected yet
        _show_panel(self.state, FastenersPanel(analysis))


class Subassemblies(_Command):
    name, menu = "Aplan_Subassemblies", "Subassembly tree"
    tooltip = ("Show and edit the product's subassemblies (workstations): the document's structure or the "
               "planner's proposal; checked by the planner, stored in the analysis")

    def run(self):
        from .structure import SubassembliesPanel

        analysis = workflow.require_analysis(_document())
        workflow.analysis_product(analysis)
        _show_panel(self.state, SubassembliesPanel(analysis))


class Session(_Command):
    name, menu = "Aplan_Session", "Run a session (simulated camera cell)"
    tooltip = ("Run aplan session on a level (or all, bottom-up) in the background: a simulated operator on a "
               "rendered tray, or picks typed in; the robot decides; shows the belief plot when it ends")

    def run(self):
        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        _show_panel(self.state, session.SessionPanel(product, workflow.analysis_base_part(analysis), self.state.jobs,
                                                     _document().FileName or None))


COMMANDS = (CreateAnalysis, GroupComponent, ExcludeParts, Detect, Diagrams, Interlocks, Intent, Fasteners, Subassemblies, Plan,
            Plan3D, ExportBundle, ExportModel, Solve, Simulate, Session)


def register(state: WorkbenchState) -> list[str]:
    """Register every command with FreeCAD, sharing ``state``; returns their names (toolbar order)."""
    for command in COMMANDS:
        FreeCADGui.addCommand(command.name, command(state))
    return [c.name for c in COMMANDS]
