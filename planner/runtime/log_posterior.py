"""The posterior over every sequence that explains a session log (docs/habits.md, Learning from logs): what the
habits learn from a log whose observations several sequences explain.

Definition. A log's steps (:func:`~planner.runtime.logged_sequence.logged_steps`) are robot operations (the
operation is known; for a join, the one of its operations at the state) and operator observations (the part
seen picked: every state edge whose operation shows it explains the step; a blank observation, also nothing).
An *explanation* is a path of state edges from the initial state that takes one matching edge per step (or none
at a blank observation). Of the alignments that give the same sequence (the operations of a run of blank observations can take any of its steps) only the
canonical one is kept, the operations taking the run's first steps, so each sequence is counted once. When some
explanation reaches the finished product, the explanations are those that do (the session finished). An
explanation's weight is the product of the prior's choice ``p(e | s)`` over its *operator* steps: the robot's
action is a function of the observations alone (its belief), the same for every explanation, so its factor
cancels; an unobserved completion and a blank step explained by nothing weigh 1. Under the paper's prior
(``p0(e | s) = N(target) / N(s)``) every finished explanation done by the operator alone weighs ``1 / N``: the
posterior is uniform over them. The posterior is the weights normalised.

Per-state counts are the expected number of times the operator took each state edge under that posterior:
forward-backward over (step, state, whether the current blank run has idled), each step's transition
probabilities normalised to 1 (so one explanation gives counts of exactly 1). Cost: O(T (S + E)) for T steps,
S states, E state edges; no sequence is enumerated. The *orders* are the finished explanations with their
posterior weights, enumerated depth first over the transitions that lead to an explanation (no dead end), at most
:data:`ORDERS_CAP` of them: past the cap none is returned. Cost: O(min(k, cap) T D), D the largest out-degree.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..assembly.explode import SequenceError
from ..assembly.plan import Plan
from ..assembly.tags import BLANK

__all__ = ["Explanations", "explanations", "ORDERS_CAP"]

#: At most this many explaining sequences are recorded as a log's orders (module docstring).
ORDERS_CAP = 64


@dataclass(frozen=True)
class Explanations:
    """The posterior of a log (module docstring): ``counts`` (E,) the operator's expected count of each state
    edge; ``finished`` the explanations reach the finished product; ``orders`` the finished explanations as
    ``(state edges, posterior weight)`` (weights summing to 1), empty when not finished, None past the cap;
    ``number`` how many explanations were enumerated (``ORDERS_CAP + 1`` means more)."""

    counts: np.ndarray
    finished: bool
    orders: tuple[tuple[tuple[int, ...], float], ...] | None
    number: int


def _transitions(plan: Plan, steps, choice: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, bool, bool]]:
    """Per step: the state edges that explain it, their weights (the prior's choice for the operator's step, 1
    for the robot's: module docstring), whether it is a blank observation, whether the operator did it."""
    states, seen = plan.states, plan.operation_observation
    blank = plan.observations.index(BLANK)
    shows = seen[states.edge_operation]
    out = []
    for who, value in steps:
        robot = who == "robot"
        edges = np.flatnonzero(np.isin(states.edge_operation, value) if robot else shows == value)
        out.append((edges, np.ones(edges.size) if robot else choice[edges], not robot and value == blank, not robot))
    return out


def _normalised(x: np.ndarray) -> np.ndarray:
    total = x.sum()
    return x / total if total > 0 else x


def explanations(plan: Plan, steps: list[tuple[str, int]], choice: np.ndarray,
                 cap: int = ORDERS_CAP) -> Explanations:
    """The posterior over the sequences of ``plan`` that explain ``steps`` (module docstring) under the prior's
    per-state-edge ``choice`` probabilities (E,). Raises :class:`SequenceError` when none explains them.
    Cost: module docstring."""
    states = plan.states
    S, src, tgt = states.n_states, states.edge_source, states.edge_target
    moves = _transitions(plan, steps, np.asarray(choice, dtype=float))
    # Forward: alpha[t][s, f], f = 1 once the current run of blank observations has idled (module docstring);
    # each step normalised (only ratios within a step are used).
    alpha = [np.zeros((S, 2))]
    alpha[0][states.initial, 0] = 1.0
    for edges, weight, blank, _ in moves:
        a, new = alpha[-1], np.zeros((S, 2))
        came = a[src[edges], 0] + (0.0 if blank else a[src[edges], 1])
        new[:, 0] = np.bincount(tgt[edges], weights=came * weight, minlength=S)
        if blank:
            new[:, 1] = a[:, 0] + a[:, 1]
        if not new.any():
            raise SequenceError("no assembly sequence of the product explains the logged operations and "
                                f"observations ({', '.join(f'{who} {value}' for who, value in steps)})")
        alpha.append(_normalised(new))
    finished = bool(alpha[-1][states.final].any())
    beta = [np.zeros((S, 2))]
    beta[0][states.final if finished else slice(None)] = 1.0
    for edges, weight, blank, _ in reversed(moves):
        b, new = beta[0], np.zeros((S, 2))
        through = np.bincount(src[edges], weights=weight * b[tgt[edges], 0], minlength=S)
        new[:, 0] = through + (b[:, 1] if blank else 0.0)
        new[:, 1] = b[:, 1] if blank else through
        beta.insert(0, _normalised(new))
    counts = np.zeros(states.n_edges)
    for t, (edges, weight, blank, operator) in enumerate(moves):
        a, b = alpha[t], beta[t + 1]
        xi = (a[src[edges], 0] + (0.0 if blank else a[src[edges], 1])) * weight * b[tgt[edges], 0]
        idle = float(((a[:, 0] + a[:, 1]) * b[:, 1]).sum()) if blank else 0.0
        total = xi.sum() + idle
        if operator and total > 0:
            np.add.at(counts, edges, xi / total)
    orders, number = _orders(plan, moves, beta, cap) if finished else ((), 0)
    return Explanations(counts, finished, orders, number)


def _orders(plan: Plan, moves, beta: list[np.ndarray], cap: int):
    """The finished explanations and their posterior weights, None past ``cap`` (module docstring)."""
    states = plan.states
    found: list[tuple[tuple[int, ...], float]] = []

    def walk(t: int, state: int, idled: int, path: list[int], weight: float) -> None:
        if len(found) > cap:
            return
        if t == len(moves):
            found.append((tuple(path), weight))
            return
        edges, weights, blank, _ = moves[t]
        if not (blank and idled):
            for e, w in zip(edges.tolist(), weights.tolist()):
                target = int(states.edge_target[e])
                if states.edge_source[e] == state and beta[t + 1][target, 0] > 0:
                    walk(t + 1, target, 0, path + [e], weight * w)
        if blank and beta[t + 1][state, 1] > 0:
            walk(t + 1, state, 1, path, weight)

    walk(0, states.initial, 0, [], 1.0)
    if len(found) > cap:
        return None, len(found)
    total = sum(w for _, w in found)
    return tuple((path, w / total) for path, w in found), len(found)
