"""The planner's application interface: what every front end (the ``aplan`` command line, the FreeCAD
workbench, batch jobs, user scripts) does with a product, in one place, one module per stage of the pipeline.

Front ends only parse their input and show results; the steps of the method live here, each a plain function:

1. :mod:`~planner.api.products`: :func:`resolve_product`: a PRODUCT argument (a product file, a bundle folder,
   a CAD file read through a plugin, or an embedded example) -> :class:`~planner.product.Product`, with the
   fastener groups to fold (``tagged``, ``auto``, ``none``); :func:`fastener_report`, :func:`accept_fasteners`:
   the designer's and the proposed fastener groups;
2. :mod:`~planner.api.plans`: :func:`plan_statistics_of`: the plan of a product and its figures (``aplan
   stats``); :func:`base_part_of`: the base part every sequence starts from (paper Sec. V), ``"auto"`` for the
   most connected part; the sequences and their exploded views. :mod:`~planner.api.levels`: a product planned
   as workstations, level by level;
3. :mod:`~planner.api.models`: :func:`decision_model` / :func:`lumped_model` / :func:`load_model` /
   :func:`model_of` / :func:`save_model`: the decision model of Alg. 3 (over intentions, or lumped over the
   factored model's classes), or a POMDP read from a file, and writing it as POMDPX or ``.pomdp``;
   :data:`MODEL_PRESETS`, :func:`habits_for`, :func:`session_habits`, :func:`learn_habits`: the named models
   (``--model``) and the operator's habits they read, checked against a product, learned from session logs;
4. :mod:`~planner.api.policies`: :func:`solve`, :func:`policy_for`: a policy from a solver (the built-in
   point-based one, or SARSOP);
5. :mod:`~planner.api.decisions`: :func:`decision_maker`: the model and policy a session, a simulation or an
   evaluation runs: the offline policy on the flat model (the paper's), or the online planner on the factored
   model (paper Sec. V), chosen by :func:`choose_planner`; :func:`simulate`, :func:`evaluate`: episodes of an
   operator against a policy.

:mod:`~planner.api.specs` holds the values a front end builds once and passes down: :class:`ModelSpec` (which
decision model), :class:`PlannerChoice` (who decides) and :class:`EpisodeChoice` (which episodes are played).
Every name is importable from ``planner.api`` itself.

>>> from planner import api
>>> model = api.decision_model("pen")
>>> model.pomdp.n_states, model.pomdp.n_actions, model.pomdp.n_observations
(69, 22, 12)
"""
from __future__ import annotations

from ..assembly.plan import Plan
from ..errors import PlannerError
from ..product import Product
from ..validation import InputLimits
from .decisions import (PLANNERS, check_cell_observe, choose_planner, decision_maker, evaluate, evaluate_operator,
                        online_planner, simulate)
from .levels import (
    LEVEL_KEYS,
    arranged,
    hierarchy_statistics_of,
    level_product,
    level_support_proposals,
    level_report,
    level_table,
    levels_of,
    proposed_subassemblies,
    structure_problems,
)
from .models import (
    FILE_OPTION,
    MODEL_PRESETS,
    MODEL_SUFFIXES,
    Model,
    _model_file_kind,
    check_model_file,
    check_parallel_flat,
    decision_model,
    factored_decision_model,
    habits_for,
    learn_habits,
    load_model,
    lumped_model,
    model_of,
    read_habits,
    save_model,
    session_habits,
    tables,
    write_habits,
)
from .plans import (
    AUTO_BASE_PART,
    _decidable,
    base_part_of,
    explain_disconnected,
    plan_in_3d,
    plan_of,
    plan_statistics_of,
    sequence_choices,
    sequence_from_log,
)
from .policies import SOLVER_ENGINES, check_solved, policy_for, solve
from .products import (
    DEFAULT_MODE,
    FASTENER_MODES,
    accept_fasteners,
    fastener_report,
    record_detection_proposals,
    resolve_product,
)
from .specs import EpisodeChoice, ModelSpec, PlannerChoice

# Private names other modules of the planner read from here (the command line's habits, its model files).
_PRIVATE = (_decidable, _model_file_kind)

__all__ = ["resolve_product", "record_detection_proposals", "DEFAULT_MODE", "fastener_report", "accept_fasteners", "FASTENER_MODES", "plan_of",
           "proposed_subassemblies", "level_support_proposals", "structure_problems", "level_report", "level_table",
           "LEVEL_KEYS",
           "explain_disconnected", "plan_statistics_of", "base_part_of", "decision_model", "lumped_model",
           "load_model", "save_model", "check_model_file", "tables", "MODEL_SUFFIXES", "SOLVER_ENGINES", "solve",
           "check_solved", "evaluate_operator",
           "policy_for", "simulate", "evaluate", "check_cell_observe", "PLANNERS", "factored_decision_model",
           "online_planner",
           "choose_planner", "decision_maker", "arranged", "levels_of", "level_product", "hierarchy_statistics_of",
           "sequence_choices", "plan_in_3d", "sequence_from_log", "InputLimits",
           # the stages' values (issue 24), and names front ends read from here
           "ModelSpec", "PlannerChoice", "EpisodeChoice", "model_of", "check_parallel_flat", "Model", "Product",
           "Plan", "AUTO_BASE_PART",
           "FILE_OPTION",
           # operator habits (issue 23): the named models, reading, checking and learning habits
           "MODEL_PRESETS", "habits_for", "session_habits", "learn_habits", "read_habits", "write_habits",
           "PlannerError"]
