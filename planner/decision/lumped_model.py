"""The lumped decision model: Alg. 3's POMDP over the factored model's *classes* instead of intentions.

Definition. The classes of :class:`~planner.decision.factored_model.FactoredIntentionModel` are the state edges
``c < E`` (the current assembly state is the edge's source, the operator's next step is the edge) and the
finished product ``E``. The lumped POMDP has one state per class and the flat model's actions, observations,
discount and rewards:

- transitions: with ``M`` the *advance* matrix (class ``c`` goes to the classes ``c'`` that start at
  ``target(c)`` with probability ``class_fraction[c'] = N(target(c')) / N(target(c))``; the finished product
  stays), ``wait`` is ``W = (I + M) / 2`` (stay or advance one step); the action that performs ``c``'s step
  is ``M W`` on class ``c`` (the robot's step, then the operator's stay-or-advance); every other action
  leaves the class as it is;
- observations: those of the class's current state, the same table (one shared object) for every action;
- rewards: ``R(c, a)`` of the class's next step (unfavorable, favorable, wrong operation or wait);
- initial belief: the factored model's (the classes out of the initial state, by their share of the full
  sequences).

Exactness. Call a flat belief over intentions *uniform within classes* when every intention of a class holds
the same probability. The flat initial belief is; the flat prediction keeps the property (every intention of
class ``c`` continues along its own path, and those paths fan out over the classes at ``target(c)`` in
proportion to their path counts: that is ``M``); the Bayes update keeps it (the observation likelihood of an
intention depends only on its current state, the same for the whole class). On such beliefs the flat
prediction, the observation probabilities and the expected rewards equal the lumped ones at the class masses
(the sums over each class), so every belief the flat model reaches from its initial belief corresponds to
one the lumped model reaches with the same probability and the same expected rewards. The optimal value at
corresponding beliefs is the same, and a policy over class masses runs on the flat model unchanged (sum the
flat belief per class, or keep the factored model's belief). The flat model is not lumpable in the strong
sense (an intention's successor is one intention, not a class), so the lumped model says nothing about flat
beliefs that are not uniform within classes; none is ever reached from the initial belief.

The parallel model (:mod:`~planner.decision.parallel`, docs/parallel.md) is defined on these classes: a right
parallel action moves class ``c`` to ``e'`` then by ``W`` (with probability ``q``), a wrong one leaves it.

With operator habits (edge weights, :mod:`~planner.decision.habits`) the same holds with "uniform within
classes" read as "in proportion to the intentions' prior weights within classes": the factored model's weighted
``class_fraction`` is then ``M``, and nothing else changes.

Cost. ``E + 1`` states instead of the intentions (pen: 33 instead of 69; chain of 7: 193 instead of 1,957;
complete 6: 857 instead of 6,872). Building it costs O(nnz(M^2) + (E + 1) A) time and memory: one sparse
product ``M M`` (the two-step advance), one row selection per action and a dense reward table.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..assembly.plan import Plan
from ..defaults import BLANK_WEIGHT, DISCOUNT, STAY
from .deviations import Deviations, lumped_switch, mixed_observations
from .factored_model import FactoredIntentionModel, factored_model
from .intention_model import Rewards
from .parallel_values import parallel_rows
from .pomdp import POMDP
from .step_observations import refuse_step_tables

# The solver's warm start on this model (solver_bounds, solver_start) is the solver's configuration:
# planner.decision.solvers.warm_start. A model imports no solver.
__all__ = ["LumpedModel", "lumped_model", "lumped_pomdp", "lumped_pomdp_bytes", "class_names", "advance_matrix",
           "LUMPED_SUFFIX"]

log = logging.getLogger(__name__)

LUMPED_SUFFIX = ":lumped"  # appended to the model's name: a policy file's ``model`` attribute tells it apart


def class_names(model: FactoredIntentionModel) -> tuple[str, ...]:
    """``c<k>:s<source>>s<target>`` for the state edges, ``c<E>:finished`` for the finished product."""
    E = model.final_class
    source, target = model.class_source[:E], model.class_target[:E]
    return tuple(f"c{c}:s{s}>s{t}" for c, s, t in zip(range(E), source.tolist(), target.tolist())) + \
        (f"c{E}:finished",)


def advance_matrix(model: FactoredIntentionModel) -> sp.csr_matrix:
    """``M`` (E+1, E+1) CSR: one step along the path (module docstring); the finished product stays.
    Cost: O(E + nnz(M))."""
    E = model.final_class
    out, count = model.starting_at(model.class_target[:E].astype(np.int64))
    rows = np.append(np.repeat(np.arange(E), count), E)
    cols = np.append(out, E)
    values = np.append(model.class_fraction[out], 1.0)
    return sp.csr_matrix((values, (rows, cols)), shape=(E + 1, E + 1))


def _transitions(model: FactoredIntentionModel) -> tuple[sp.csr_matrix, ...]:
    n, A = model.n_classes, len(model.action_operations)
    identity = sp.identity(n, format="csr")
    advance = advance_matrix(model)
    wait = ((identity + advance) * STAY).tocsr()
    if model.deviations is not None and model.deviations.switch:  # a change of mind first (deviations.py)
        wait = (lumped_switch(model) @ wait).tocsr()
    performed = (advance @ wait).tocsr()        # the robot's step, then the operator's stay-or-advance
    tables = []
    extra = parallel_rows(model, wait)  # the parallel model's right actions (None: the paper's)
    for a in range(A - 1):
        performs = (model.class_action == a).astype(float)
        if extra is None:
            tables.append((sp.diags(performs) @ performed + sp.diags(1.0 - performs)).tocsr())
        else:
            right, taken = extra[a]
            tables.append((sp.diags(performs) @ performed + sp.diags(1.0 - performs - taken) + right).tocsr())
    tables.append(wait)
    for table in tables:
        table.sum_duplicates()
        table.eliminate_zeros()
    return tuple(tables)


def _observations(model: FactoredIntentionModel) -> sp.csr_matrix:
    """O(z | class): the blank at a quarter of the weight of each observation into the class's state."""
    n, Z = model.n_classes, len(model.plan.observations)
    source = model.class_source.astype(np.int64)
    lo = np.searchsorted(model.emit_keys, source * Z)
    hi = np.searchsorted(model.emit_keys, (source + 1) * Z)
    count = hi - lo
    ends = np.cumsum(count)
    at = np.repeat(lo - ends + count, count) + np.arange(int(ends[-1]) if n else 0)
    rows = np.concatenate([np.arange(n), np.repeat(np.arange(n), count)])
    cols = np.concatenate([np.zeros(n, dtype=np.int64), model.emit_keys[at] % Z])
    weight = model.emit_weight[source]
    values = np.concatenate([BLANK_WEIGHT * weight, np.repeat(weight, count)])
    table = sp.csr_matrix((values, (rows, cols)), shape=(n, Z))
    if model.deviations is not None and model.deviations.mistake:
        table = mixed_observations(table, model.deviations.mistake)
    return table


def _rewards(model: FactoredIntentionModel) -> np.ndarray:
    n, A = model.n_classes, len(model.action_operations)
    reward = np.full((A, n), model.rewards.wrong, dtype=float)
    reward[-1] = model.rewards.wait
    doing = np.flatnonzero(model.class_action >= 0)
    reward[model.class_action[doing], doing] = model.class_match_reward[doing]
    if model.parallel is not None:  # R = wrong + q (r(o) - wrong) on the parallel pairs
        par = model.parallel
        reward[par.action, par.pair_class] = model.rewards.wrong + par.fraction * (par.reward - model.rewards.wrong)
    return reward


def lumped_pomdp_bytes(n_classes: int, n_actions: int) -> int:
    """The most :func:`lumped_pomdp` takes for ``n_classes`` classes and ``n_actions`` actions, on top of the
    factored model, from counts alone: per action and class a transition entry (12 bytes) and a row pointer
    (4), and a float64 reward (the dense (A, classes) table): 24 bytes; the performing rows' second steps,
    the observation table and the class names about 200 bytes a class more, and each action's table object
    about 3 KB. Measured within a factor 3 above (chain 7: tests/decision/test_memory_estimates.py; 26.3
    bytes per class and action on chain 16)."""
    return 26 * n_classes * n_actions + 200 * n_classes + 3000 * n_actions


def lumped_pomdp(model: FactoredIntentionModel) -> POMDP:
    """The POMDP over the classes of ``model`` (module docstring), named ``<product>:lumped``.

    Cost: O(nnz(M^2) + (E + 1) A) for E state edges and A actions. A model with observations of the step
    (:mod:`~planner.decision.step_observations`) has no such tables: :class:`PlannerError` (its POMDP is over
    pairs: :func:`~planner.decision.step_pomdp.step_pomdp`).
    """
    refuse_step_tables(model, "the lumped POMDP over classes", "build the POMDP over (class, seen observation) "
                       "pairs (step_pomdp; aplan pomdp --lumped --observe step), or use the online planner")
    transition = _transitions(model)
    table = _observations(model)
    observation = tuple(table for _ in transition)  # one object: solvers and updaters share its products
    return POMDP(class_names(model), model.actions, model.observations, transition, observation,
                 _rewards(model), model.initial_belief().dense(model.n_classes), model.discount,
                 name=model.name + LUMPED_SUFFIX)


@dataclass(frozen=True)
class LumpedModel:
    """The factored model (what the classes mean, its Bayes filter) and its lumped POMDP (for solvers and
    files): a policy of ``pomdp`` is over class masses, ``factored.initial_belief().dense(n)`` its start."""

    factored: FactoredIntentionModel
    pomdp: POMDP

    @property
    def name(self) -> str:
        return self.pomdp.name

    @property
    def actions(self) -> tuple[str, ...]:
        return self.pomdp.actions

    @property
    def observations(self) -> tuple[str, ...]:
        return self.pomdp.observations


def lumped_model(plan: Plan, rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                 base_part: str | None = None, weights: np.ndarray | None = None,
                 parallel: bool = False, deviations: Deviations | None = None, orders=None) -> LumpedModel:
    """The factored model of ``plan`` (from ``base_part`` if given; ``weights``: operator habits, per state edge;
    ``parallel``: the parallel model, docs/parallel.md; ``deviations``: change of mind and mistakes; ``orders``:
    the orders' model, :mod:`~planner.decision.orders`) and its lumped POMDP. Cost: that of
    :func:`factored_model` plus :func:`lumped_pomdp`."""
    factored = factored_model(plan, rewards, discount, base_part, weights, parallel, deviations, orders)
    return LumpedModel(factored, lumped_pomdp(factored))
