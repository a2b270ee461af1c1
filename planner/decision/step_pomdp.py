"""The POMDP tables of a model with observations of the step (``--observe step``, docs/camera.md): for model files
(POMDPX, Cassandra) and any solver that takes ``O(z | state reached)``.

Definition. A POMDP whose observation depends on the transition becomes one whose observation depends on the
state reached by putting the step's observation into the state: the states are the pairs ``(c, z)`` of a class
``c`` of the factored model and the observation ``z`` of the operator's step that led to it (0: no step, or one
that cannot be seen). ``(c, 0)`` exists for every class, ``(c, z)`` for each distinct observation ``z`` of the
operations into ``c``'s state. Then

- transitions from ``(c, z)`` are those of the factored model from ``c`` (they do not depend on ``z``), each
  piece arriving with its own step's observation (:func:`~planner.decision.step_observations.predict_seen`): a
  stay or a robot step at ``(c', 0)``, the operator's step along edge ``e`` at ``(c', obs(e))``;
- ``O(0 | (c, 0)) = 1``; ``O(z | (c, z)) = 4/5`` and ``O(0 | (c, z)) = 1/5`` (the camera's miss); mistakes mix
  ``mu / Z`` in;
- rewards ``R((c, z), a) = R(c, a)``; the initial belief is the factored model's on ``(c, 0)``.

Its beliefs, summed over ``z``, are the factored step filter's (tests/decision/test_step_observations.py), and
its values do not depend on ``z`` (nothing ahead does), so a policy solved on it decides as one over classes.

Cost: ``n = E + 1 + sum over classes of k(source)`` states (``k``: the distinct observations into a state), one
sparse product per table like the lumped POMDP's (:func:`~planner.decision.lumped_model.lumped_pomdp`) on ``n``
rows: O(nnz(M^2) + n A).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..defaults import CAMERA_BLANK, STAY
from .deviations import lumped_switch
from .lumped_model import LUMPED_SUFFIX, _rewards, advance_matrix, class_names
from .parallel_values import parallel_rows
from .pomdp import POMDP
from .step_observations import of_step

__all__ = ["STEP_SUFFIX", "step_states", "step_pomdp", "step_pomdp_states"]

STEP_SUFFIX = LUMPED_SUFFIX + ":step"  # the model's name: <product>:lumped:step


def step_states(model) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(class, seen)`` (module docstring), sorted: two arrays. Cost: O(E log E)."""
    Z = len(model.plan.observations)
    E = model.final_class
    seen = model.plan.operation_observation[model.class_operation[:E]].astype(np.int64)
    into = np.unique(model.class_target[:E].astype(np.int64)[seen != 0] * Z + seen[seen != 0])  # (state, z)
    classes, count = model.starting_at(into // Z)
    keys = np.union1d(np.arange(model.n_classes, dtype=np.int64) * Z, classes.astype(np.int64) * Z
                      + np.repeat(into % Z, count))
    return keys // Z, keys % Z


def step_pomdp_states(model) -> int:
    """How many states :func:`step_pomdp` has, from the model alone. Cost: that of :func:`step_states`."""
    return int(step_states(model)[0].size)


def _columns(model, keys: np.ndarray, classes: np.ndarray, seen: np.ndarray) -> np.ndarray:
    return np.searchsorted(keys, np.asarray(classes, dtype=np.int64) * len(model.plan.observations)
                           + np.asarray(seen, dtype=np.int64))


def step_pomdp(model) -> POMDP:
    """The POMDP over pairs (module docstring) of a factored model with ``observe="step"``. Cost: module
    docstring."""
    if not of_step(model):
        raise ValueError("step_pomdp needs a model with observations of the step (observe='step' or 'join')")
    n, Z, E = model.n_classes, len(model.plan.observations), model.final_class
    pair_class, pair_seen = step_states(model)
    keys = pair_class * Z + pair_seen
    m = keys.size
    at_rest = sp.csr_matrix((np.ones(n), (np.arange(n), _columns(model, keys, np.arange(n), np.zeros(n, int)))),
                            shape=(n, m))
    out, count = model.starting_at(model.class_target[:E].astype(np.int64))
    seen = np.repeat(model.plan.operation_observation[model.class_operation[:E]].astype(np.int64), count)
    moved = sp.csr_matrix((np.append(model.class_fraction[out], 1.0),
                           (np.append(np.repeat(np.arange(E), count), E),
                            np.append(_columns(model, keys, out, seen), _columns(model, keys, [E], [0])))),
                          shape=(n, m))
    wait = (STAY * at_rest + (1 - STAY) * moved).tocsr()  # the operator's stay (unseen) or step (seen)
    if model.deviations is not None and model.deviations.switch:
        wait = (lumped_switch(model) @ wait).tocsr()
    performed = (advance_matrix(model) @ wait).tocsr()  # the robot's step (the camera does not report it)
    extra = parallel_rows(model, wait)
    tables = []
    for a in range(len(model.action_operations) - 1):
        performs = (model.class_action == a).astype(float)
        taken = 0.0 if extra is None else extra[a][1]
        table = sp.diags(performs) @ performed + sp.diags(1.0 - performs - taken) @ at_rest
        tables.append(table if extra is None else table + extra[a][0])
    tables.append(wait)
    transition = []
    for table in tables:
        table = table.tocsr()[pair_class]  # every pair of a class has the class's row
        table.sum_duplicates()
        table.eliminate_zeros()
        transition.append(table.tocsr())
    blank = np.where(pair_seen == 0, 1.0, CAMERA_BLANK)
    rows = np.concatenate([np.arange(m), np.flatnonzero(pair_seen != 0)])
    cols = np.concatenate([np.zeros(m, dtype=np.int64), pair_seen[pair_seen != 0]])
    values = np.concatenate([blank, np.full(int((pair_seen != 0).sum()), 1.0 - CAMERA_BLANK)])
    observation = sp.csr_matrix((values, (rows, cols)), shape=(m, Z))
    if model.deviations is not None and model.deviations.mistake:
        mu = model.deviations.mistake
        observation = sp.csr_matrix(observation.toarray() * (1.0 - mu) + mu / Z)
    names = class_names(model)
    states = tuple(names[c] + (f"|z{z}" if z else "") for c, z in zip(pair_class.tolist(), pair_seen.tolist()))
    initial = np.zeros(m)
    start = model.initial_belief()
    initial[_columns(model, keys, start.classes, np.zeros(start.classes.size, dtype=np.int64))] = start.mass
    return POMDP(states, model.actions, model.observations, tuple(transition),
                 tuple(observation for _ in transition), _rewards(model)[:, pair_class], initial, model.discount,
                 name=model.name + STEP_SUFFIX)
