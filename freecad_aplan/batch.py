"""FreeCADCmd entry point: ``APLAN_BATCH='{"action": ...}' freecadcmd freecad_aplan/batch.py``.

Actions: ``export`` (a model to a bundle folder with its stored designer intent and, unless
``"redetect": true``, its stored diagrams, :func:`freecad_aplan.export.export_model`; the answer names the
intent's engine and tolerances, and ``diagrams``: where the product's diagrams came from, or null when a
geometry engine must still detect them) and
``analyze-occt`` (the exact engine on a bundle's B-reps, :mod:`freecad_aplan.occt`, with note lines of
progress). The job and its answer
follow :mod:`freecad_aplan.protocol`. Used by :mod:`freecad_aplan.runner`.

Three more actions serve the workbench's background jobs (:mod:`freecad_aplan.workflow`), and also run in a
plain Python that has the planner's dependencies (no FreeCAD needed): ``analyze`` (a geometry engine on a
bundle, written into its ``product.json``, with a note line per pair the exact engine left undecided), ``level-stats`` (the per-level figures of ``aplan stats`` for a
product of several workstations, with a note line per level) and ``solve`` (the point-based solver on a product
file, written as a ``.policy``, with progress lines), ``session`` (``aplan session --demo`` in the simulated
camera cell and each level's belief plot, :func:`freecad_aplan.sessions.run_simulated_session`, a note line
per output line), ``habits`` (``aplan habits`` on the session panel's logs,
:func:`freecad_aplan.sessions.learn_session_habits`). ``export`` with ``"notes": true`` prints a note line per
part tessellated (the workbench's background detection).
"""
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from freecad_aplan.protocol import decode_job, error_line, note_line, progress_line, result_line  # noqa: E402


def _run(job: dict) -> dict:
    action = job.pop("action")
    if action == "export":
        from freecad_aplan.export import export_model

        notes = job.pop("notes", False)  # the workbench's background detection shows them as progress
        product, intent = export_model(**job, progress=(lambda text: print(note_line(text), flush=True))
                                       if notes else None)
        stored = None if intent is None else {"engine": intent.engine, "contact": intent.contact,
                                              "interference": intent.interference, "depth": intent.depth,
                                              "face_weight": intent.occt_face_weight,
                                              "prism_triangles": intent.occt_prism_triangles,
                                              "time_limit": intent.occt_time_limit}
        return {"parts": len(product["parts"]), "warnings": product["geometry"]["warnings"], "intent": stored,
                "diagrams": product["geometry"].get("analysis", {}).get("diagrams")}
    if action == "analyze-occt":
        from freecad_aplan.occt import analyze_bundle_breps

        return analyze_bundle_breps(**job, progress=lambda text: print(note_line(text), flush=True))
    if action == "analyze":
        from freecad_aplan.workflow import analyze_bundle

        return analyze_bundle(**job, progress=lambda text: print(note_line(text), flush=True))
    if action == "level-stats":
        from freecad_aplan.workflow import level_statistics_report

        return level_statistics_report(**job, progress=lambda text: print(note_line(text), flush=True))
    if action == "session":
        from freecad_aplan.sessions import run_simulated_session

        return run_simulated_session(**job, progress=lambda text: print(note_line(text), flush=True))
    if action == "habits":
        from freecad_aplan.sessions import learn_session_habits

        return learn_session_habits(**job)
    if action == "solve":
        from freecad_aplan.workflow import solve_product

        def progress(seconds: float, lower: float, upper: float) -> None:
            print(progress_line(seconds, lower, upper), flush=True)

        return solve_product(**job, progress=progress)
    raise ValueError(f"unknown batch action {action!r}")


def main() -> None:
    try:
        result = _run(decode_job(os.environ))
        print(result_line(result), flush=True)
    except Exception as exc:  # every failure becomes one readable line for the caller
        from planner.errors import PlannerError

        # Bad input (the planner's and the workbench's errors, files) is told as is; anything else is a bug,
        # told with its traceback.
        expected = (PlannerError, ValueError, OSError)
        message = str(exc) if isinstance(exc, expected) else \
            f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=5)}"
        print(error_line(message), flush=True)


main()
