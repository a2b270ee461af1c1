"""FreeCADCmd entry point: ``APLAN_BATCH='{"action": ...}' freecadcmd freecad_aplan/batch.py``.

Actions: ``export`` (a model to a bundle folder, :func:`freecad_aplan.export.export_model`) and
``analyze-occt`` (the exact engine on a bundle's B-reps, :mod:`freecad_aplan.occt`). The answer is one line
``APLAN-RESULT <json>`` or ``APLAN-ERROR <message>`` on standard output (FreeCADCmd's exit code is not
reliable). Used by :mod:`freecad_aplan.runner`.
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

        product = export_model(**job)
        return {"parts": len(product["parts"]), "warnings": product["geometry"]["warnings"]}
    if action == "analyze-occt":
        from freecad_aplan.occt import analyze_bundle_breps

        return analyze_bundle_breps(**job)
    raise ValueError(f"unknown batch action {action!r}")


def main() -> None:
    try:
        result = _run(json.loads(os.environ["APLAN_BATCH"]))
        print("APLAN-RESULT " + json.dumps(result), flush=True)
    except Exception as exc:  # every failure becomes one readable line for the caller
        from freecad_aplan.document import DocumentError

        message = str(exc) if isinstance(exc, (DocumentError, ValueError, OSError)) else \
            f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=5)}"
        print("APLAN-ERROR " + message.replace("\n", " | "), flush=True)


main()
