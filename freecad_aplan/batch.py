"""FreeCADCmd entry point: ``APLAN_BATCH='{"action": ...}' freecadcmd freecad_aplan/batch.py``.

Actions: ``export`` (a model to a bundle folder with its stored designer intent and, unless
``"redetect": true``, its stored diagrams, :func:`freecad_aplan.export.export_model`; the answer names the
intent's engine and tolerances, and ``diagrams``: where the product's diagrams came from, or null when a
geometry engine must still detect them) and
``analyze-occt`` (the exact engine on a bundle's B-reps, :mod:`freecad_aplan.occt`). The answer is one line
``APLAN-RESULT <json>`` or ``APLAN-ERROR <message>`` on standard output (FreeCADCmd's exit code is not
reliable). Used by :mod:`freecad_aplan.runner`.

Two more actions serve the workbench's background jobs (:mod:`freecad_aplan.workflow`), and also run in a
plain Python that has the planner's dependencies (no FreeCAD needed): ``analyze`` (a geometry engine on a
bundle, written into its ``product.json``) and ``solve`` (the point-based solver on a product file, written
as a ``.policy``; progress as ``APLAN-PROGRESS seconds lower upper`` lines).
"""
import json
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _run(job: dict) -> dict:
    action = job.pop("action")
    if action == "export":
        from freecad_aplan.export import export_model

        product, intent = export_model(**job)
        stored = None if intent is None else {"engine": intent.engine, "contact": intent.contact,
                                              "interference": intent.interference, "depth": intent.depth}
        return {"parts": len(product["parts"]), "warnings": product["geometry"]["warnings"], "intent": stored,
                "diagrams": product["geometry"].get("analysis", {}).get("diagrams")}
    if action == "analyze-occt":
        from freecad_aplan.occt import analyze_bundle_breps

        return analyze_bundle_breps(**job)
    if action == "analyze":
        from freecad_aplan.workflow import analyze_bundle

        return analyze_bundle(**job)
    if action == "solve":
        from freecad_aplan.workflow import solve_product

        def progress(seconds: float, lower: float, upper: float) -> None:
            print(f"APLAN-PROGRESS {seconds:.1f} {lower:.6f} {upper:.6f}", flush=True)

        return solve_product(**job, progress=progress)
    raise ValueError(f"unknown batch action {action!r}")


def main() -> None:
    try:
        result = _run(json.loads(os.environ["APLAN_BATCH"]))
        print("APLAN-RESULT " + json.dumps(result), flush=True)
    except Exception as exc:  # every failure becomes one readable line for the caller
        from planner.errors import PlannerError

        expected = (PlannerError, ValueError, OSError)
        if "FreeCAD" in sys.modules:  # not when the job runs in a plain Python
            from freecad_aplan.document import DocumentError

            expected += (DocumentError,)
        message = str(exc) if isinstance(exc, expected) else \
            f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=5)}"
        print("APLAN-ERROR " + message.replace("\n", " | "), flush=True)


main()
