"""The parallel model's pairs (:mod:`.parallel`) in the lumped POMDP's transitions and in the online planner's
bounds (:mod:`.online`): the hooks those modules call, each a no-op (or None) for the paper's model.

Bounds. For a pair ``p = (c, a)`` (``q``, ``e'``, ``r``) the class MDP's Q-value is ``Q(c, a) = q X + (1 - q)
(R_wrong + g V(c))`` with ``X = r + g (V(e') + W(target e')) / 2`` (the robot's step, then the operator's
stay-or-advance; ``W`` the value on arriving at a state: QMDP's ``W``, or the revealed bound's ``VT``). ``e'`` is
one level nearer the finished product than ``c``, so the backward passes know ``V(e')`` when they reach ``c``,
and the self-loop of trying again has the closed form ``(q X + (1 - q) R_wrong) / (1 - (1 - q) g)``, taken into
``V(c)``'s maximum. The revealed bound's robot, which knows the state ``t`` but not the next step, tries an
action ``a`` for ``sum over the classes c out of t of f(c) Q_a(c)``: ``Q_a(c)`` is the matching value, the pair's
or ``R_wrong + g K(c)`` (``K`` the class MDP's value) — it is then told the class, which only helps, so every
value stays an upper bound. Cost: O(P) per pass for P pairs.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["parallel_rows", "parallel_level", "parallel_tries", "parallel_q_values", "parallel_q_matrix"]


def parallel_rows(model, wait: sp.csr_matrix) -> list[tuple[sp.csr_matrix, np.ndarray]] | None:
    """Per robot action ``a``: the lumped transition rows of its right parallel actions (``q`` from ``c`` to
    ``e'``, then ``wait``: the operator's stay-or-advance) and ``q`` per class (what leaves the diagonal); None
    for the paper's model. Cost: O(P + nnz) per action."""
    par = model.parallel
    if par is None:
        return None
    n, A = model.n_classes, len(model.action_operations)
    out = []
    for a in range(A - 1):
        p = np.flatnonzero(par.action == a)
        right = sp.csr_matrix((par.fraction[p], (par.pair_class[p], par.target[p])), shape=(n, n)) @ wait
        taken = np.zeros(n)
        taken[par.pair_class[p]] = par.fraction[p]
        out.append((right.tocsr(), taken))
    return out


def parallel_level(model, classes: np.ndarray, v: np.ndarray, value: np.ndarray, arrive: np.ndarray,
                   out: np.ndarray, redraw: np.ndarray | None = None, other: np.ndarray | None = None) -> None:
    """One level block of a backward pass (module docstring): raise ``v`` (the values of ``classes``, in
    place) to each pair's self-loop fixed point, then write each pair's Q-value into ``out`` (per pair).
    ``value``: per class, ``arrive``: per state, both known on the levels nearer the finished product.

    With a change of mind (``sigma``, :mod:`~planner.decision.deviations`) the operator's step after the robot's
    is a redraw first: ``X = r + g ((1 - sigma) (V(e') + arrive(target e')) + sigma redraw(s')) / 2``, ``redraw``
    per state the redraw's value ``sum over the classes c' of s' of share(c') (V(c') + arrive(target c'))``
    (:func:`~planner.decision.deviations.switch_wait_values`' ``X``, known at ``s' = source(e')``, one level
    nearer). ``other`` (per class of ``classes``, in place): also raised to the pairs' fixed points, for the
    caller's fixed point of waiting."""
    par = model.parallel
    if par is None:
        return
    k, p = par.of_classes(classes)
    if not p.size:
        return
    g, wrong = model.discount, model.rewards.wrong
    after = par.target[p].astype(np.int64)
    stay_or_advance = value[after] + arrive[model.class_target[after]]
    if redraw is not None:
        sigma = model.deviations.switch
        stay_or_advance = (1 - sigma) * stay_or_advance + sigma * redraw[model.class_source[after]]
    x = par.reward[p] + g * stay_or_advance / 2
    q = par.fraction[p]
    fixed = (q * x + (1 - q) * wrong) / (1 - (1 - q) * g)
    np.maximum.at(v, k, fixed)
    if other is not None:
        np.maximum.at(other, k, fixed)
    out[p] = q * x + (1 - q) * (wrong + g * v[k])


def parallel_tries(model, classes: np.ndarray, source: np.ndarray, size: int, m: np.ndarray, can: np.ndarray,
                   pair_q: np.ndarray, known: np.ndarray) -> np.ndarray:
    """The revealed bound's best try per state of a level block (module docstring): ``source`` the block-local
    state of each of ``classes``, ``m`` their matching values (``can``: a robot action matches), ``pair_q`` the
    pairs' Q-values, ``known`` the class MDP's values. -inf at a state with nothing to try."""
    g, wrong = model.discount, model.rewards.wrong
    A = len(model.action_operations)
    source = np.asarray(source, dtype=np.int64)
    f = model.class_fraction[classes]
    miss = wrong + g * known[classes]
    base = np.bincount(source, weights=f * miss, minlength=size)
    hit = np.flatnonzero(can)
    k, p = model.parallel.of_classes(classes)
    keys = np.concatenate([source[hit] * A + model.class_action[classes[hit]],
                           source[k] * A + model.parallel.action[p]])
    gains = np.concatenate([f[hit] * (m[hit] - miss[hit]), f[k] * (pair_q[p] - miss[k])])
    best = np.full(size, -np.inf)
    if keys.size:
        distinct, inverse = np.unique(keys.astype(np.int64), return_inverse=True)
        state = distinct // A
        np.maximum.at(best, state, base[state] + np.bincount(inverse, weights=gains, minlength=distinct.size))
    return best


def parallel_q_values(model, values, classes: np.ndarray, mass: np.ndarray, out: np.ndarray) -> None:
    """Add the pairs' Q-values (above the ``wrong`` one each replaces) to ``out`` (per action, in place)."""
    if model.parallel is None or values.parallel is None:
        return
    k, p = model.parallel.of_classes(classes)
    gain = mass[k] * (values.parallel[p] - values.wrong[classes[k]])
    out[:-1] += np.bincount(model.parallel.action[p], weights=gain, minlength=out.size - 1)


def parallel_q_matrix(model, values, out: np.ndarray) -> None:
    """Write the pairs' Q-values into ``out`` (A, classes), in place."""
    if model.parallel is not None and values.parallel is not None:
        out[model.parallel.action, model.parallel.pair_class] = values.parallel
