"""The parallel model (issue 23, item 2; docs/parallel.md): the robot may do the operator's step *after next* now.

The paper's model is a Markov model over the factored model's classes ``c = (s, e)`` (the assembly state ``s``
and the operator's next state edge ``e`` out of it). The parallel model changes one thing. For a robot action
performing operation ``o`` at class ``c`` with ``op(e) != o``, call ``(c, o)`` a *parallel pair* when ``o`` can
be done now without disturbing ``e``:

- a state edge ``f`` out of ``s`` performs ``o`` (allowed: with a base part, the allowed first edges at the
  initial state, :func:`~planner.assembly.intentions.allowed_edges`; technical constraints are in the state
  graph already),
- a state edge ``e2`` out of ``target(e)`` performs ``o`` (the operator could take ``o`` right after ``e``),
- a state edge ``e'`` out of ``target(f)`` performs ``op(e)`` and ``target(e') == target(e2)``.

Then, with probability ``q = class_fraction[e2]`` (the operator's chance of taking ``o`` right after ``e``,
habit-weighted with habits) the action is *right*: reward ``r(o)`` (``class_match_reward[e2]``), and the class
becomes ``e'`` (the robot did ``o``, the operator still does ``e``), followed by the operator's stay-or-advance
(1/2 each), as after the robot's next-step action; with probability ``1 - q`` it is *wrong*: reward ``wrong``,
class unchanged, as in the paper. So ``R(c, a) = wrong + q (r(o) - wrong)``. Everything else is the paper's.

``(c, a)`` determines ``f``, ``e2`` and ``e'`` (an operation applied to a state has one result), so the pairs are
a sparse table keyed by ``c * A + a`` (:class:`ParallelTable`). Cost of :func:`parallel_table`: O(C log E) time
for the C = nnz(M) candidates (class, class out of its target) of the advance matrix, at most 100 bytes a
candidate at its peak, about 66 bytes a pair held (:func:`~planner.decision.budget.check_parallel_memory` refuses past the budget).
"""
from __future__ import annotations

import numpy as np

from ..assembly.intentions import allowed_edges
from .parallel_table import ParallelTable
from .joins import JOINS
from .projected import PROJECTED, projected_rewrite
from .step_observations import stay_part

__all__ = ["ParallelTable", "parallel_table", "parallel_flag", "parallel_rewrite", "parallel_bytes",
           "parallel_candidates", "parallel_predict", "parallel_rewards", "parallel_expected_rewards"]


# parallel_table's peak per candidate (class, class out of its target): measured 85-89 bytes on chain 13 and
# complete 8 (tracemalloc), the table held within it (about 66 bytes a pair: eight 8-byte numbers)
CANDIDATE_BYTES = 100


def parallel_flag(rule: bool | str) -> str:
    """The command-line flag of a parallel model (``True``/``next``: ``--parallel``, ``projected``: ``--projected``,
    ``joins``: ``--joins``)."""
    return {PROJECTED: "--projected", JOINS: "--joins"}.get(rule, "--parallel") if isinstance(rule, str) \
        else "--parallel"


def parallel_candidates(states) -> int:
    """The (class, class out of its target) candidates :func:`parallel_table` looks at: ``nnz(M)``. Cost: O(E)."""
    return int(np.bincount(states.edge_source, minlength=states.n_states)[states.edge_target].sum())


def parallel_bytes(states) -> int:
    """The most :func:`parallel_table` takes on a plan's state graph ``states``, from counts alone."""
    return CANDIDATE_BYTES * parallel_candidates(states)


def parallel_table(model) -> ParallelTable:
    """The parallel pairs of a :class:`~planner.decision.factored_model.FactoredIntentionModel` (module
    docstring), from its tables only. Cost: O(P log E)."""
    plan = model.plan
    states = plan.states
    E, A = model.final_class, len(model.action_operations)
    n_ops = len(plan.andor.operations)
    source = model.class_source[:E].astype(np.int64)
    target = model.class_target[:E].astype(np.int64)
    operation = model.class_operation[:E].astype(np.int64)
    # (state, operation) -> the edge: an operation applied to a state has one result
    edge_key = source * n_ops + operation
    order = np.argsort(edge_key, kind="stable")
    sorted_key = edge_key[order]

    def edge_at(state: np.ndarray, op: np.ndarray) -> np.ndarray:
        keys = state * n_ops + op
        at = np.minimum(np.searchsorted(sorted_key, keys), max(E - 1, 0))
        return np.where(sorted_key[at] == keys, order[at], -1) if E else np.full(keys.shape, -1)

    # candidates: every class c (not the final one) and every class e2 out of target(c)
    e2, count = model.starting_at(target)
    c = np.repeat(np.arange(E, dtype=np.int64), count)
    keep = (e2 != model.final_class)
    c, e2 = c[keep], e2[keep].astype(np.int64)
    o = operation[e2]
    action = model.class_action[e2].astype(np.int64)
    keep = (action >= 0) & (o != operation[c])
    c, e2, o, action = c[keep], e2[keep], o[keep], action[keep]
    f = edge_at(source[c], o)
    ok = f >= 0
    if model.base_part is not None:
        ok &= allowed_edges(states, model.base_part)[np.maximum(f, 0)]
    c, e2, o, action, f = c[ok], e2[ok], o[ok], action[ok], f[ok]
    e_after = edge_at(target[f], operation[c])
    ok = e_after >= 0
    ok[ok] = target[e_after[ok]] == target[e2[ok]]
    c, e2, action, f, e_after = c[ok], e2[ok], action[ok], f[ok], e_after[ok]
    key = c * A + action
    order = np.argsort(key, kind="stable")
    c, e2, action, f, e_after, key = c[order], e2[order], action[order], f[order], e_after[order], key[order]
    start = np.searchsorted(c, np.arange(model.n_classes + 1))
    arrays = (key, c, action, model.class_fraction[e2].astype(float), e_after,
              model.class_match_reward[e2].astype(float), e2, f, start)
    for a in arrays:
        a.flags.writeable = False
    return ParallelTable(A, *arrays)


def parallel_predict(model, classes: np.ndarray, mass: np.ndarray, action: int, performs: np.ndarray,
                     parts: list) -> list:
    """The factored prediction's ``parts`` (``parts[0]``: the classes ``action`` leaves where they are) with the
    parallel pairs: each pair's class keeps ``1 - q`` of its mass (wrong), ``q`` goes to ``e'`` and then stays or
    advances (right). Cost: O(k log P) plus the advance of the right mass."""
    k, p = model.parallel.find(classes, action)
    if not k.size:
        return parts
    right = mass[k] * model.parallel.fraction[p]
    stay = mass.copy()
    stay[k] -= right
    return [stay_part(model, classes[~performs], stay[~performs])] + parts[1:] + \
        model._wait_step(model.parallel.target[p].astype(np.int64), right)


def parallel_rewards(model, classes: np.ndarray, action: int, out: np.ndarray) -> np.ndarray:
    """``out`` (the paper's R(class, action) of ``classes``) with ``R = wrong + q (r(o) - wrong)`` on the pairs."""
    k, p = model.parallel.find(classes, action)
    out[k] = model.rewards.wrong + model.parallel.fraction[p] * (model.parallel.reward[p] - model.rewards.wrong)
    return out


def parallel_expected_rewards(model, belief, out: np.ndarray) -> np.ndarray:
    """``out`` (the paper's R(b, a) per action) with the pairs' rewards in place of ``wrong``. Cost: O(k + pairs)."""
    k, p = model.parallel.of_classes(belief.classes)
    gain = belief.mass[k] * model.parallel.fraction[p] * (model.parallel.reward[p] - model.rewards.wrong)
    out[:-1] += np.bincount(model.parallel.action[p], weights=gain, minlength=out.size - 1)
    return out


def parallel_rewrite(model, path: list[int], position: int, action: int) -> list[int]:
    """The operator's true sequence after the robot's ``action`` at ``position`` (a simulator's world): when the
    action is right (a parallel pair of ``path[position]`` whose ``step`` is ``path[position + 1]``), the path with
    the robot's edge ``f`` and then ``e'`` in place of the operator's next two steps (the robot's step is then the
    path's next one: the episode counts it as the robot's, with its reward), else ``path`` itself."""
    if model.parallel is None or position >= len(path):
        return path
    if model.parallel.rule in (PROJECTED, JOINS):
        return projected_rewrite(model, path, position, action)
    if position + 1 >= len(path):
        return path
    _, p = model.parallel.find(np.array([path[position]]), action)
    if not p.size or int(model.parallel.step[p[0]]) != path[position + 1]:
        return path
    return path[:position] + [int(model.parallel.robot_edge[p[0]]), int(model.parallel.target[p[0]])] + \
        path[position + 2:]
