"""The workbench's commands after the plan: export the bundle and the decision model, solve a policy and simulate a
session with it (over :mod:`freecad_aplan.workflow`, as the command line does through :mod:`planner.api`)."""
from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import replace

import FreeCAD
import FreeCADGui
from PySide import QtGui

from planner.defaults import CONFIDENCE, PRODUCT_FILE, WORKBENCH_SOLVE_TIME_LIMIT

from .. import workflow
from . import session
from .command_base import PARAMETERS, _Command, _document, _message, _save_path

__all__ = ["ExportBundle", "ExportModel", "Solve", "Simulate"]


class ExportBundle(_Command):
    name, menu = "Aplan_ExportBundle", "Export product bundle"
    tooltip = "Write a bundle folder (product.json with diagrams and intent, meshes, B-reps) for aplan"

    def run(self):
        document = _document()
        analysis = workflow.require_analysis(document)
        workflow.analysis_product(analysis)
        path = _save_path("Export APLAN bundle (a new folder)", "Bundle folder (*)", "")
        if path:
            workflow.export_analysis_bundle(document, analysis, path)
            _message(f"wrote the bundle {path}", error=False)


class ExportModel(_Command):
    name, menu = "Aplan_ExportModel", "Export decision model (POMDPX / .pomdp)"
    tooltip = "Write the operator-intent POMDP (Alg. 3) as POMDPX or Cassandra .pomdp"

    def run(self):
        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        chosen, level = session.ask_level(product)
        path = chosen and _save_path("Export decision model", "POMDPX (*.pomdpx);;POMDP (*.pomdp)", ".pomdpx")
        if path:
            sizes = workflow.export_decision_model(product, path, spec=workflow.analysis_spec(analysis), level=level)
            _message(f"wrote {path} ({sizes['model']} model): {sizes['states']} states, {sizes['actions']} actions, "
                     f"{sizes['observations']} observations", error=False)


class Solve(_Command):
    name, menu = "Aplan_Solve", "Solve and save policy"
    tooltip = ("Solve the decision model in the background (point-based solver; time limit: parameter "
               f"Mod/APLAN/SolveTimeLimit, default {WORKBENCH_SOLVE_TIME_LIMIT:g} s) and save the policy")

    def run(self):
        from planner.product import save_product

        from .jobs import BackgroundJob

        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        chosen, level = session.ask_level(product)
        path = chosen and _save_path("Save policy", "SARSOP policy (*.policy)", ".policy")
        if not path:
            return
        seconds = FreeCAD.ParamGet(PARAMETERS).GetFloat("SolveTimeLimit", WORKBENCH_SOLVE_TIME_LIMIT) or WORKBENCH_SOLVE_TIME_LIMIT
        folder = tempfile.mkdtemp(prefix="aplan-solve-")
        save_product(product, os.path.join(folder, PRODUCT_FILE))

        def done(result):
            shutil.rmtree(folder, ignore_errors=True)
            self.state.policy = path
            _message(f"wrote {path} ({result['model']} model): lower bound {result['lower_bound']:.5f}, upper bound "
                     f"{result['upper_bound']:.5f}, {result['alpha_vectors']} alpha vectors", error=False)

        def failed(message):
            shutil.rmtree(folder, ignore_errors=True)
            _message(message)

        job = {"action": "solve", "product": os.path.join(folder, PRODUCT_FILE), "output": path,
               "time_limit": seconds, "level": level,
               **workflow.spec_fields(workflow.analysis_spec(analysis))}
        BackgroundJob(f"Solving the decision model ({seconds:g} s)", workflow.worker_command("solve"), job, done,
                      failed, self.state.jobs, FreeCADGui.getMainWindow()).start()


class Simulate(_Command):
    name, menu = "Aplan_Simulate", "Simulate an operator sequence"
    tooltip = ("Play the operator through a full assembly sequence against the policy (over intentions, or over "
               "the lumped model's classes); show the belief plot")

    def run(self):
        from .panels import ImageDialog

        analysis = workflow.require_analysis(_document())
        product = workflow.analysis_product(analysis)
        chosen, level = session.ask_level(product)
        if not chosen:
            return
        policy = self.state.policy
        if not policy or not os.path.isfile(policy):
            policy, _ = QtGui.QFileDialog.getOpenFileName(FreeCADGui.getMainWindow(), "Policy to simulate", "",
                                                          "SARSOP policy (*.policy)")
            if not policy:
                return
        sequence, ok = QtGui.QInputDialog.getInt(FreeCADGui.getMainWindow(), "Simulate",
                                                 "Full sequence (its intention number with a policy over intentions, "
                                                 "its rank from 0 with one over classes; -1: the first)", -1, -1)
        if not ok:
            return
        choice = replace(workflow.SIMULATE_EPISODE, sequences=() if sequence < 0 else (sequence,))
        stem = os.path.join(tempfile.mkdtemp(prefix="aplan-simulate-"), "belief")
        result = workflow.simulate_sequence(product, policy, stem, choice, spec=workflow.analysis_spec(analysis),
                                            level=level)
        from planner.decision.simulate import confidence_text

        said = confidence_text(result["confident_after"], CONFIDENCE)
        caption = (f"Sequence {result['sequence']} ({result['model']} model): {said}. Steps: "
                   + "; ".join(f"{a} / {o} / {p}" for a, o, p in result["steps"]))
        self.state.belief_dialog = ImageDialog("APLAN belief", caption, result["plots"][0], FreeCADGui.getMainWindow())
        self.state.belief_dialog.show()
