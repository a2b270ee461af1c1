"""Options several commands share, one bundle per kind of argument, and their conversion into the planner's
arguments: each bundle has an ``add_...`` that adds its options to a parser and a ``..._from(args)`` that reads
them into one value, built once per command and passed down.

- :mod:`.products`: PRODUCT -> the product planned (:func:`product_from`; :func:`add_product_options`);
- :mod:`.models`: the decision model -> :class:`~planner.api.specs.ModelSpec` (:func:`model_spec_from`);
- :mod:`.planners`: who decides -> :class:`~planner.api.specs.PlannerChoice` (:func:`planner_choice_from`), and
  the episodes of simulate and evaluate -> :class:`~planner.api.specs.EpisodeChoice` (:func:`episode_choice_from`);
- :mod:`.limits`: size limits (:func:`limits_from`) and input limits (:func:`inputs_from`);
- :mod:`.geometry`: the engines' tolerances (:func:`tolerances_from`, :func:`contact_tolerances_from`);
- :mod:`.outputs`: ``--force`` and the outputs checked before any work; :mod:`.values`: argparse types;
- :mod:`.advice`: how a refusal names the options that help.
"""
from __future__ import annotations

from .values import (
    contact_tolerance,
    decision_seconds,
    designer_direction,
    finite,
    gibibytes,
    index,
    number,
    positive,
    positive_length,
    positive_seconds,
    whole,
)
from .outputs import add_force, check_outputs
from .limits import add_input_options, add_size_options, inputs_from, limits_from
from .products import (
    PRODUCT_HELP,
    add_base_part,
    add_fasteners,
    add_hierarchy,
    add_interlocks,
    add_model_options,
    add_product_options,
    add_technical,
    model_options_from,
    parse_group,
    product_from,
)
from .geometry import add_contact_options, add_tolerance_options, contact_tolerances_from, tolerances_from
from .models import (
    add_decision_options,
    add_deviation_options,
    add_habits_options,
    add_parallel_options,
    deviations_from,
    habits_from,
    model_spec_from,
    parallel_from,
    rewards_from,
)
from .planners import (
    add_episode_options,
    add_policy_options,
    episode_choice_from,
    online_budget,
    operator_model,
    planner_choice_from,
)
from .advice import LONG_MESSAGE, add_verbose, advice, explain, offer_options

__all__ = ["contact_tolerance", "decision_seconds", "designer_direction", "finite", "gibibytes", "index", "number",
           "positive", "positive_length", "positive_seconds", "whole", "add_force", "check_outputs",
           "add_input_options", "add_size_options", "inputs_from", "limits_from", "PRODUCT_HELP", "add_base_part",
           "add_fasteners", "add_hierarchy", "add_interlocks", "add_model_options", "add_product_options",
           "add_technical", "model_options_from", "parse_group", "product_from", "add_contact_options",
           "add_tolerance_options", "contact_tolerances_from", "tolerances_from", "add_decision_options",
           "add_deviation_options", "add_habits_options", "add_parallel_options", "deviations_from", "habits_from",
           "model_spec_from", "parallel_from", "rewards_from", "add_episode_options", "add_policy_options",
           "episode_choice_from",
           "online_budget", "operator_model", "planner_choice_from", "LONG_MESSAGE", "add_verbose", "advice",
           "explain", "offer_options"]
