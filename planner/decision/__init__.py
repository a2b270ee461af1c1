"""The decision model (the paper's Sec. III-C, Alg. 3) behind four small interfaces, as in POMDPs.jl:

- the *model*: a discrete :class:`POMDP` in sparse tables (``pomdp``), built from a plan by
  :func:`intention_model` (an :class:`IntentionModel`: the plan, its intention graph and the tables) or read from POMDPX / Cassandra files (``io``);
  the same model without enumerating intentions: :func:`factored_model` (``factored_model``, paper Sec. V);
  its POMDP over classes, exactly equivalent and far smaller: :func:`lumped_model` (``lumped_model``);
- the *solver*: ``solver.solve(model) -> SolveResult`` (``solvers``);
- the *policy*: ``policy.action(belief)`` and ``policy.value(belief)`` (``policy``);
- the *belief updater*: ``initialize`` and ``update(belief, action, observation)`` (``belief``;
  :class:`FactoredUpdater` on the factored model).

``simulate`` plays episodes of any model against any policy with any updater. ``models`` is the interface the
front ends use (:func:`~planner.decision.models.updater_for`, ``tables``, ``belief_over``, ...): no code outside
this package tests a decision type; ``bounds`` holds the class-MDP bounds, ``solvers.warm_start`` the lumped
model's warm start.
"""
from .belief import DiscreteUpdater, UnexplainedObservation
from .factored_model import FactoredBelief, FactoredIntentionModel, factored_model
from .factored_updater import FactoredUpdater, to_flat
from .intention_model import WAIT, IntentionModel, Rewards, intention_model, intention_pomdp
from .lumped_model import LumpedModel, lumped_model, lumped_pomdp
from .policy import AlphaVectorPolicy, PolicyError, read_policy, write_policy
from .pomdp import POMDP, ModelError
from .solvers import PointBasedSolver, SolveResult

__all__ = ["DiscreteUpdater", "UnexplainedObservation", "FactoredBelief", "FactoredIntentionModel", "FactoredUpdater",
           "factored_model", "to_flat", "LumpedModel", "lumped_model", "lumped_pomdp", "WAIT", "IntentionModel", "Rewards", "intention_model", "intention_pomdp",
           "AlphaVectorPolicy", "PolicyError", "read_policy", "write_policy", "POMDP", "ModelError",
           "PointBasedSolver", "SolveResult"]
