"""An upper bound on the lumped model's value from an information relaxation: the assembly state is told
one step late.

Definition. The *delayed-reveal* problem is the lumped POMDP (:mod:`~planner.decision.lumped_model`) in which
the robot, right after its action at time ``t``, is also told the assembly state of the class ``x_t`` it
acted in (after a robot operation, ``x_t`` itself: the class, i.e. the state and the operator's next step).
The extra signal is a function of the hidden trajectory and changes nothing else, so every policy of the
lumped POMDP runs in the relaxed problem (ignoring the signal) with the same returns, and its optimal value
bounds the lumped one from above at every belief: ``V_d(b) >= V*(b)``. With ``every = k`` the state is told
after every ``k``-th action only (robot operations still tell the class): less is told, so the bound is
lower (``V_k <= V_1``) and the graph larger (a node is a belief and its phase, ``0 .. k-1``).

Closure. In the relaxed problem the belief at a decision is ``post(pi, a, z)``: a *prior* ``pi`` (the belief
at the previous decision restricted to what was told: one state's classes, or one class), predicted through
action ``a`` and updated with observation ``z`` (with ``k > 1``, up to ``k`` such steps). Starting from a
state's classes spread by their path fractions (``class_fraction``: the initial belief, and what waiting
leaves at every state, since the observations depend on the state only) or from one class, every prior is
again a spread or a single class: waiting moves a spread into spreads at the targets, a known class stays or
spreads at its target; the robot performing a class's step spreads it over the target and beyond; any other
robot action moves nothing, and its class is told (in the parallel model, :mod:`~planner.decision.parallel`, an
action with a pair at the class moves it too, through the lumped table, as a performing one). So the relaxed
beliefs form a finite graph: ``O(states + classes)`` priors times the actions that can move them times the
observations (chain of 7: 617 nodes with ``k = 1``, 2,576 with ``k = 2``; complete 6: 2,625 and 10,135).

Values. On that graph ``V_d`` is the fixed point of the Bellman operator ``V(b) = max_a R(b, a) + gamma
sum P(b' | b, a) V(b')``, with one successor list per action that matters at ``b``: waiting, each robot
action that performs a class of ``b`` and one *probe* (any other robot action: they all earn ``R_wrong``,
move nothing and tell every class). Value iteration from ``R_max / (1 - gamma)`` (above ``V_d`` since the
operator is monotone and maps that constant below itself) decreases to ``V_d``, so every iterate is an
upper bound, at every graph belief, on ``V_d`` and hence on ``V*``. Iterated ``H`` times from zero it gives
the relaxed problem's ``H``-step value instead (tests compare it with an independent expectimax).

Any belief. At the phase after which the state is told, the relaxed Q-value of *any* belief ``b`` follows
from the graph (:meth:`DelayedReveal.relaxed_q`): after a robot action every class is told, so it is linear
in ``b`` (per class, the row of the class's node); after waiting each state's part of ``b`` is told, and the
continuation ``g(pi) = sum_z P(z | pi) V_d(post(pi, wait, z))`` is convex and positively homogeneous in the
unnormalised ``pi`` (the perspective of the convex ``V_d``), hence subadditive: writing the part of ``b`` at
a state as ``alpha`` times its spread plus a non-negative rest gives ``g <= alpha g(spread) + sum_c rest_c
g(class c)``. So ``max(robot terms, waiting term)`` bounds ``V*(b)`` at every belief, with one action for the
whole belief (what the spreads' own values, mixed, cannot see): the solver's
:class:`~planner.decision.solvers.upper.RelaxedQ`.

Cost. Building the graph: one prediction and observation split per (prior, action that moves it), and per
belief a sum over its classes: O(N k) for N beliefs of at most k classes (in Python, about 0.4 ms per
belief); each sweep is one sparse product over the successor lists. Chain of 7: 0.24 s (``k = 1``), 1.0 s
(``k = 2``); complete 6: 1.1 s and 4.9 s (one core).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .factored_model import FactoredIntentionModel
from .pomdp import POMDP
from .solvers.upper import RelaxedQ

__all__ = ["DelayedReveal", "RevealGraph", "delayed_reveal_bound", "reveal_graph", "reveal_values"]

_DIGITS = 12  # beliefs equal to this many digits are one graph node


@dataclass(frozen=True)
class RevealGraph:
    """The relaxed problem's beliefs and their successor lists (module docstring). ``beliefs`` (N, n) CSR over
    the lumped model's classes; row ``k`` of ``successors`` (K, N) is one action at belief ``owner[k]``
    (sorted, every belief owns at least one row, waiting first), action ``action[k]`` (``probe[k]``: the
    probe, standing for every robot action that performs none of the belief's classes), with expected reward
    ``reward[k]``; a node is a belief and a
    phase (the state is told after the action of phase ``every - 1``); ``initial`` (every,): the node of the
    initial belief at each phase, ``corner`` (every, n): of each class known outright, ``spread`` (every,
    states): of each state's spread (-1 for a state with no class)."""

    beliefs: sp.csr_matrix
    owner: np.ndarray
    action: np.ndarray
    probe: np.ndarray
    reward: np.ndarray
    successors: sp.csr_matrix
    discount: float
    initial: np.ndarray
    corner: np.ndarray
    spread: np.ndarray
    every: int = 1

    @property
    def n(self) -> int:
        return self.beliefs.shape[0]


@dataclass(frozen=True)
class DelayedReveal:
    """The relaxed values ``values`` (N,) at the graph's beliefs (upper bounds on the lumped model's
    ``V*`` there) and the graph; a belief's bound is the least over its phases."""

    graph: RevealGraph
    values: np.ndarray

    @property
    def initial_value(self) -> float:
        return float(self.values[self.graph.initial].min())

    @property
    def corner_values(self) -> np.ndarray:
        """(n,): the bound at each class known outright (an upper bound on ``Q*(a, c)`` for every action)."""
        return self.values[self.graph.corner].min(axis=0)

    def spread_values(self, states: np.ndarray) -> np.ndarray:
        """The bound at the spreads of ``states`` (``inf`` where a state has no spread node)."""
        node = self.graph.spread[:, states]
        return np.where(node >= 0, self.values[np.maximum(node, 0)], np.inf).min(axis=0)

    def relaxed_q(self, states: np.ndarray) -> RelaxedQ:
        """The relaxed Q-values at the phase after which the state is told (``every - 1``), as the linear
        pieces of :class:`~planner.decision.solvers.upper.RelaxedQ`: per robot action and class (every class
        is told after a robot action, so a belief's Q-value is linear in it: the row of the class's corner
        node, the probe's for every action that does not perform it), and for waiting per class and at the
        spread of each of ``states`` (the solver's corner groups, in their order). Cost: O(A n + rows)."""
        g = self.graph
        q = g.reward + g.discount * (g.successors @ self.values)
        phase, wait = g.every - 1, int(g.action[0])          # every node's first row is its wait row
        n = g.corner.shape[1]
        robot = np.full((wait + 1, n), -np.inf)
        waiting = q[np.searchsorted(g.owner, g.corner[phase])]
        for c, node in enumerate(g.corner[phase]):
            rows = np.arange(np.searchsorted(g.owner, node), np.searchsorted(g.owner, node, side="right"))[1:]
            probe = rows[g.probe[rows]]
            if probe.size:
                robot[:wait, c] = q[probe[0]]
            for row in rows[~g.probe[rows]]:
                robot[g.action[row], c] = q[row]
        spread_wait = q[np.searchsorted(g.owner, g.spread[phase, states])]
        robot = robot[:wait]    # every (robot action, class) has its row: the action's own or the probe
        if not np.all(np.isfinite(robot)):
            raise ValueError("a robot action has no relaxed Q-value at some class")
        return RelaxedQ(robot, waiting, spread_wait)

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """(N, n) dense beliefs and their values: sawtooth points for the solver's upper bound."""
        return self.graph.beliefs.toarray(), self.values.copy()


class _Builder:
    def __init__(self, model: FactoredIntentionModel, pomdp: POMDP, every: int):
        self.every = every
        self.n, self.A = pomdp.n_states, pomdp.n_actions
        self.wait = self.A - 1
        self.T = [t.tocsr() for t in pomdp.transition]
        dense: dict[int, np.ndarray] = {}
        self.O = [dense.setdefault(id(o), o.toarray()) for o in pomdp.observation]   # (n, Z) per action
        self.R = np.asarray(pomdp.reward, dtype=float)
        self.state_of = np.asarray(model.class_source, dtype=np.int64)
        self.act_of = np.asarray(model.class_action, dtype=np.int64)
        self.parallel = model.parallel
        self.nodes: list[tuple[np.ndarray, np.ndarray, int]] = []
        self.keys: dict[tuple[bytes, int], int] = {}
        self.posts: dict[tuple[bytes, int, int], tuple[np.ndarray, np.ndarray]] = {}
        self.known: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]] = {}

    def node(self, idx: np.ndarray, val: np.ndarray, phase: int = 0) -> int:
        key = (idx.tobytes() + np.round(val, _DIGITS).tobytes(), phase)
        k = self.keys.get(key)
        if k is None:
            k = self.keys[key] = len(self.nodes)
            self.nodes.append((idx, val, phase))
        return k

    def successors(self, idx: np.ndarray, val: np.ndarray, a: int, phase: int) -> tuple[np.ndarray, np.ndarray]:
        """The nodes ``post(pi, a, z)`` (at ``phase``) for the prior ``pi`` = (idx, val), and their probabilities."""
        key = (idx.tobytes() + np.round(val, _DIGITS).tobytes(), a, phase)
        hit = self.posts.get(key)
        if hit is not None:
            return hit
        predicted = np.asarray(self.T[a][idx].T @ val).ravel()
        support = np.flatnonzero(predicted > 0)
        joint = self.O[a][support] * predicted[support, None]        # (k, Z)
        pz = joint.sum(axis=0)
        children, probs = [], []
        for z in np.flatnonzero(pz > 1e-15):
            keep = joint[:, z] > 0
            children.append(self.node(support[keep], joint[keep, z] / pz[z], phase))
            probs.append(pz[z])
        out = (np.asarray(children, dtype=np.int64), np.asarray(probs))
        self.posts[key] = out
        return out

    def rows(self, idx: np.ndarray, val: np.ndarray, phase: int, corner: np.ndarray):
        """(action, probe?, reward, children, probabilities) for each action that matters at the belief (idx, val) of
        ``phase`` (the state is told after its action when ``phase == every - 1``); ``corner`` (phases, n)."""
        after = (phase + 1) % self.every
        states = self.state_of[idx]
        children, probs = [], []
        if phase == self.every - 1:      # waiting, then the state is told: the prior is that state's classes
            for s in np.unique(states):
                mine = states == s
                c, p = self.successors(idx[mine], val[mine] / val[mine].sum(), self.wait, after)
                children.append(c)
                probs.append(p * val[mine].sum())
        else:                            # waiting, nothing told
            c, p = self.successors(idx, val, self.wait, after)
            children.append(c)
            probs.append(p)
        yield self.wait, False, float(val @ self.R[self.wait, idx]), np.concatenate(children), np.concatenate(probs)
        acts = np.unique(self.act_of[idx])
        if self.parallel is not None:    # the parallel model: an action with a pair moves its class too
            acts = np.union1d(acts, self.parallel.action[self.parallel.of_classes(idx)[1]])
        acts = acts[(acts >= 0) & (acts != self.wait)]
        told = corner[after, idx]        # a robot action: every class is told (it stays where it is)
        acting = self.act_of[idx]
        for a in acts:
            right = acting == a
            if self.parallel is not None:
                right[self.parallel.find(idx, int(a))[0]] = True
            children, probs = [told[~right]], [val[~right]]
            for k in np.flatnonzero(right):   # the classes it performs: their step, then stay or advance
                c, p = self.performed(int(idx[k]), int(a), after)
                children.append(c)
                probs.append(p * val[k])
            yield int(a), False, float(val @ self.R[a, idx]), np.concatenate(children), np.concatenate(probs)
        if len(acts) < self.A - 1:       # the probe: a robot action that performs none of the classes
            free = np.ones(self.A - 1, dtype=bool)
            free[acts] = False
            probe = int(np.argmax(free))
            yield probe, True, float(val @ self.R[probe, idx]), told, val

    def performed(self, c: int, a: int, phase: int) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`successors` of the class ``c`` known outright (cached by integers, not by belief)."""
        key = (c, a, phase)
        hit = self.known.get(key)
        if hit is None:
            hit = self.known[key] = self.successors(np.array([c]), np.ones(1), a, phase)
        return hit


def reveal_graph(model: FactoredIntentionModel, pomdp: POMDP, every: int = 1, deadline: float | None = None,
                 clock: Callable[[], float] | None = None) -> RevealGraph | None:
    """The relaxed problem's belief graph for the lumped POMDP ``pomdp`` of ``model`` (module docstring), the
    state told after every ``every``-th action (a node is a belief and its phase); None once ``clock()``
    passes ``deadline`` (checked per belief). Cost: module docstring."""
    b = _Builder(model, pomdp, every)
    initial = np.asarray(pomdp.initial, dtype=float)
    support = np.flatnonzero(initial > 0)
    phases = range(every)
    first = np.array([b.node(support, initial[support], p) for p in phases], dtype=np.int64)
    corner = np.array([[b.node(np.array([c]), np.ones(1), p) for c in range(b.n)] for p in phases], dtype=np.int64)
    n_states = int(b.state_of.max()) + 1
    spread = np.full((every, n_states), -1, dtype=np.int64)
    fraction = np.asarray(model.class_fraction, dtype=float)
    for s in np.unique(b.state_of):
        members = np.flatnonzero(b.state_of == s)
        spread[:, s] = [b.node(members, fraction[members] / fraction[members].sum(), p) for p in phases]
    owner, action, probe, reward, rows, cols, probs = [], [], [], [], [], [], []
    done = 0
    while done < len(b.nodes):
        if deadline is not None and clock is not None and clock() >= deadline:
            return None
        idx, val, phase = b.nodes[done]
        for a, is_probe, r, c, p in b.rows(idx, val, phase, corner):
            action.append(a)
            probe.append(is_probe)
            rows.append(np.full(len(c), len(owner)))
            cols.append(c)
            probs.append(p)
            owner.append(done)
            reward.append(r)
        done += 1
    N, K = len(b.nodes), len(owner)
    successors = sp.csr_matrix((np.concatenate(probs), (np.concatenate(rows), np.concatenate(cols))), shape=(K, N))
    lengths = [len(i) for i, _, _ in b.nodes]
    beliefs = sp.csr_matrix((np.concatenate([v for _, v, _ in b.nodes]), np.concatenate([i for i, _, _ in b.nodes]),
                             np.concatenate([[0], np.cumsum(lengths)])), shape=(N, b.n))
    return RevealGraph(beliefs, np.asarray(owner, dtype=np.int64), np.asarray(action, dtype=np.int64),
                       np.asarray(probe, dtype=bool), np.asarray(reward), successors,
                       float(pomdp.discount), first, corner, spread, every)


def reveal_values(graph: RevealGraph, start: np.ndarray | float, sweeps: int, tolerance: float = 0.0,
                  deadline: float | None = None, clock: Callable[[], float] | None = None) -> np.ndarray:
    """``sweeps`` Bellman sweeps over ``graph`` from ``start`` (a value per belief, or one for all), stopping
    early when no value moves by more than ``tolerance`` or once ``clock()`` passes ``deadline``. From zero,
    ``H`` sweeps give the ``H``-step values; from an upper bound on the fixed point, every sweep is one.
    Cost: O(nnz(successors)) per sweep."""
    values = np.broadcast_to(np.asarray(start, dtype=float), (graph.n,)).copy()
    starts = np.flatnonzero(np.r_[True, graph.owner[1:] != graph.owner[:-1]])
    for _ in range(sweeps):
        new = np.maximum.reduceat(graph.reward + graph.discount * (graph.successors @ values), starts)
        moved = float(np.abs(new - values).max())
        values = new
        if moved <= tolerance or (deadline is not None and clock is not None and clock() >= deadline):
            break
    return values


def delayed_reveal_bound(model: FactoredIntentionModel, pomdp: POMDP, every: int = 1, tolerance: float = 1e-9,
                         max_sweeps: int = 2000, deadline: float | None = None,
                         clock: Callable[[], float] | None = None) -> DelayedReveal | None:
    """The relaxed values at every graph belief (module docstring): value iteration from ``R_max / (1 -
    gamma)`` until a sweep moves no value by more than ``tolerance`` (every iterate is an upper bound); None
    when the graph is not built by ``deadline`` (a ``clock()`` value). Cost: module docstring."""
    graph = reveal_graph(model, pomdp, every, deadline, clock)
    if graph is None:
        return None
    top = max(float(np.max(pomdp.reward)), 0.0) / (1 - graph.discount)
    return DelayedReveal(graph, reveal_values(graph, top, max_sweeps, tolerance, deadline, clock))
