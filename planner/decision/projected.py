"""The projected model (issue 23, item 2; docs/parallel.md, "The projected model"): the robot may do any
operation now, and the operator's remaining sequence is *projected* onto the state the robot made.

An assembly state is a partition of the parts into subassemblies; an operation joins two of its blocks. The
robot's operation ``o`` at state ``s`` joins blocks ``A`` and ``B`` (state edge ``f``, ``s' = target(f)``). The
operator's intended sequence from ``s`` is a path of states ``s = P_0, P_1, ..., P_k`` (the final state). Its
*projection* onto ``s'`` is the path of the joins ``P_i v s'`` (the finest partition coarser than both: ``P_i``
with the block holding ``A`` and the block holding ``B`` made one), consecutive repeats dropped. Exactly one
step disappears: the step ``j`` at which the sequence first joins the blocks holding ``A`` and ``B`` (the
parts the robot joined are joined there); from ``P_j`` on the projection is the sequence itself. The
projection is *feasible* when every ``P_i v s'`` (``i < j``) is a state of the state graph and each step between
consecutive ones a state edge: the operator's other joins, in its order, are then still operations from the
new state (nothing it meant to do is blocked, no state outside the state graph is made). Truck sa4 adds
parts one by one to a growing subassembly: after the robot adds part ``p``, no AND/OR operation of the
operator's sequence stays the same (each joins a larger block), but its projection is "the sequence minus
add ``p``", feasible when the order of the others still fits together.

The model is the paper's on its classes ``c = (s, e)`` (the state and the operator's next state edge) with one
change. For a robot action performing ``o`` at class ``c`` with ``op(e) != o`` (the robot's edge ``f`` out of
``s``, allowed: with a base part, the allowed first edges at the initial state), call ``(c, o)`` a *pair* when

- ``e'``, the state edge from ``s'`` to ``target(e) v s'``, exists (the operator's next step, projected), and
- ``q = G_o(target e) > 0``: the operator's chance, over its completions after ``e`` with their prior weights
  (``class_fraction``: uniform, or the habits), that the whole projection is feasible.

``G`` is one backward pass over the state graph per pair of parts ``(a, b)`` (the lowest parts of ``A`` and
``B``; ``P v s'`` depends only on which blocks hold them): for a state ``x`` whose blocks of ``a`` and ``b``
differ, ``G(x) = [phi(x) is a state] sum over the edges h out of x of w(h) ([h joins them] + [h not] [phi(x)
-> phi(target h) is a state edge] G(target h))``, ``phi(x) = x v s'``, ``w`` the class fractions.

For a pair, with probability ``q`` the robot's operation is *right*: reward ``r(o)`` (its reward as a next step)
and the class becomes ``e'``, then the operator's stay-or-advance (1/2 each), exactly as after the robot's
next-step action; the operator's choices after ``e'`` follow the model's prior at ``target(e')`` (the model is
Markov on the classes, as the paper's). With probability ``1 - q`` it is *wrong*: reward ``wrong``, the class
unchanged, as in the paper. These are the rows and rewards of :class:`~planner.decision.parallel.ParallelTable`
(``rule = "projected"``), so the factored model's prediction and rewards, the lumped POMDP, the online
planner's bounds and the delayed-reveal bound read them unchanged (``e'`` is one level nearer the finished
product than ``c``, which the bounds' backward passes need). Every other (class, action) is the paper's; with
the model off (``parallel=False``) nothing here is built.

Certain help: an operation whose pairs have ``q = 1`` on every class of the belief is right for every
intention the belief holds (on a chain or a complete product, whose every partition into connected sets is a
state, every pair has ``q = 1``).

Cost of :func:`projected_table`: O(K + P (S n + E log E)) time for K candidates (class, robot edge at its state:
``sum over states of outdeg^2``), P part pairs ``(a, b)`` used by robot operations, S states, E edges and n
parts; at most :data:`CANDIDATE_BYTES` a candidate, plus the lookups and one part pair's pass at a time (about
``16 S n + 24 S + 104 E`` bytes): :func:`projected_bytes`, measured within 30 % above the peak.
"""
from __future__ import annotations

import numpy as np

from ..assembly.intentions import allowed_edges

__all__ = ["PROJECTED", "PROJECTED_CONFIDENCE", "Projector", "projected_table", "projected_candidates",
           "projected_bytes", "projected_rewrite", "project_path"]

PROJECTED = "projected"

# The projected model's own default act confidence (docs/parallel.md, "How sure before a bet"): a robot that
# may do any operation bets wherever its belief is spread over assembly states (the operation exists in some
# of them only), and under the paper's -50 (C = 5/6) a calibrated bet is wrong up to 1/6 of the time. The issue's
# tolerance for wrong actions (2 % of the robot's actions) as the one-step break-even belief: C = 0.98, wrong =
# -490 with the paper's +10. The user's --reward-wrong or --act-confidence wins.
PROJECTED_CONFIDENCE = 0.98

# projected_table's peak per candidate (class, robot edge at its state), all included: measured 126 to 128
# bytes on chain 13 and complete 8 (tracemalloc; 20 MB for 159,744 candidates, 32 MB for 248,039), the table
# held within it (about 70 bytes a pair)
CANDIDATE_BYTES = 140


def _void(rows: np.ndarray) -> np.ndarray:
    """Each row of a 2-d int32 array as one comparable value (its bytes), for sorting and lookups."""
    rows = np.ascontiguousarray(rows, dtype=np.int32)
    return rows.view(np.dtype((np.void, 4 * rows.shape[1]))).ravel()


class Projector:
    """Lookups on a state graph for projections: a state from its blocks, an edge from its two states, and
    ``phi`` (the join with the blocks of two parts made one) for every state at once. Cost: O(S n log S +
    E log E) to build."""

    def __init__(self, states):
        self.states = states
        andor = states.andor
        self.masks = np.array(andor.subassemblies, dtype=object)
        self.index = andor.index
        keys = _void(states.blocks)
        self._state_order = np.argsort(keys, kind="stable")
        self._state_keys = keys[self._state_order]
        S = states.n_states
        edge_keys = states.edge_source.astype(np.int64) * S + states.edge_target
        self._edge_order = np.argsort(edge_keys, kind="stable")
        self._edge_keys = edge_keys[self._edge_order]
        low = [int(m & -m).bit_length() - 1 for m in andor.subassemblies]
        self.first_part = np.array([low[op.children[0]] for op in andor.operations], dtype=np.int64)
        self.second_part = np.array([low[op.children[1]] for op in andor.operations], dtype=np.int64)

    def state_of(self, rows: np.ndarray) -> np.ndarray:
        """The state with each of ``rows`` (blocks per part) as its blocks, -1 where none is. Cost: O(k log S)."""
        if not len(rows):
            return np.zeros(0, dtype=np.int64)
        keys = _void(rows)
        at = np.minimum(np.searchsorted(self._state_keys, keys), self._state_keys.size - 1)
        return np.where(self._state_keys[at] == keys, self._state_order[at], -1).astype(np.int64)

    def edge_between(self, source: np.ndarray, target: np.ndarray) -> np.ndarray:
        """The state edge from ``source`` to ``target`` (arrays), -1 where there is none (or either is -1)."""
        source, target = np.asarray(source, dtype=np.int64), np.asarray(target, dtype=np.int64)
        if not self._edge_keys.size:
            return np.full(source.shape, -1, dtype=np.int64)
        keys = source * self.states.n_states + target
        at = np.minimum(np.searchsorted(self._edge_keys, keys), self._edge_keys.size - 1)
        hit = (self._edge_keys[at] == keys) & (source >= 0) & (target >= 0)
        return np.where(hit, self._edge_order[at], -1).astype(np.int64)

    def phi(self, a: int, b: int, states: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(joined, phi)`` for ``states`` (default all): whether parts ``a`` and ``b`` share a block, and the
        state with their two blocks made one (the state itself where joined; -1 where the union is no
        subassembly or the partition no state). Cost: O(k n + k log S) for k states."""
        blocks = self.states.blocks if states is None else self.states.blocks[states]
        ia, ib = blocks[:, a].astype(np.int64), blocks[:, b].astype(np.int64)
        joined = ia == ib
        out = np.where(joined, np.arange(len(blocks)) if states is None else states, -1).astype(np.int64)
        apart = np.flatnonzero(~joined)
        if not apart.size:
            return joined, out
        pairs, inverse = np.unique(ia[apart] * len(self.masks) + ib[apart], return_inverse=True)
        union = np.array([self.index.get(int(self.masks[p // len(self.masks)] | self.masks[p % len(self.masks)]), -1)
                          for p in pairs.tolist()], dtype=np.int64)[inverse]
        ok = union >= 0
        rows = blocks[apart[ok]]
        merged = (rows == ia[apart[ok], None]) | (rows == ib[apart[ok], None])
        rows = np.where(merged, union[ok, None], rows)
        out[apart[ok]] = self.state_of(rows)
        return joined, out


def projected_candidates(states) -> int:
    """The (class, robot edge at its state) candidates :func:`projected_table` looks at, at most: ``sum over
    states of outdeg^2``. Cost: O(E)."""
    out = np.bincount(states.edge_source, minlength=states.n_states).astype(np.int64)
    return int((out * out).sum())


def projected_bytes(states) -> int:
    """The most :func:`projected_table` takes on ``states``, from counts alone: its candidates, the lookups
    and one part pair's backward pass."""
    S, E, n = states.n_states, states.n_edges, states.blocks.shape[1]
    return CANDIDATE_BYTES * projected_candidates(states) + 24 * S + 40 * E + 16 * S * n + 64 * E


def _completion_share(model, projector: Projector, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
    """``(G, phi)`` per state for the part pair ``(a, b)`` (module docstring), by levels from the final state
    (edges are sorted by target, states numbered by their number of blocks). Cost: O(S n + E log E)."""
    states = projector.states
    S, E = states.n_states, states.n_edges
    joined, phi = projector.phi(a, b)
    src, tgt = states.edge_source.astype(np.int64), states.edge_target.astype(np.int64)
    join_step = ~joined[src] & joined[tgt]
    step_ok = projector.edge_between(phi[src], phi[tgt]) >= 0
    weight = model.class_fraction[:E]
    live = (phi >= 0) & ~joined
    g = np.zeros(S)
    bounds = np.searchsorted(tgt, states.level_start)  # edges into level k-1 leave level k
    for k in range(1, len(states.level_start) - 1):
        h = np.arange(bounds[k - 1], bounds[k])
        if not h.size:
            continue
        term = weight[h] * np.where(join_step[h], 1.0, step_ok[h] * g[tgt[h]])
        g += np.bincount(src[h], weights=term, minlength=S) * live
    return np.minimum(g, 1.0), phi


def projected_table(model, rule: str = PROJECTED):
    """The projected model's pairs of a :class:`~planner.decision.factored_model.FactoredIntentionModel`
    (module docstring) as a :class:`~planner.decision.parallel.ParallelTable` with ``rule`` (``"projected"``, or
    ``"joins"`` when the model's actions are named by joins: the same pairs, read through ``class_action``)
    (``step`` is -1: the step that disappears depends on the whole sequence). Cost: module docstring."""
    from .parallel_table import ParallelTable

    plan = model.plan
    states = plan.states
    E, A = model.final_class, len(model.action_operations)
    projector = Projector(states)
    source = model.class_source[:E].astype(np.int64)
    target = model.class_target[:E].astype(np.int64)
    # candidates: every class c (not the final one) and every robot edge f out of its state, f != c
    f, count = model.starting_at(source)
    c = np.repeat(np.arange(E, dtype=np.int64), count)
    f = f.astype(np.int64)
    keep = (f != c) & (f != model.final_class)
    c, f = c[keep], f[keep]
    action = model.class_action[f].astype(np.int64)
    ok = action >= 0
    if model.base_part is not None:
        ok &= allowed_edges(states, model.base_part)[f]
    c, f, action = c[ok], f[ok], action[ok]
    operation = model.class_operation[f].astype(np.int64)
    a_part, b_part = projector.first_part[operation], projector.second_part[operation]
    n = states.blocks.shape[1]
    pair = a_part * n + b_part
    q = np.zeros(c.size)
    after = np.full(c.size, -1, dtype=np.int64)
    for key in np.unique(pair).tolist():
        at = np.flatnonzero(pair == key)
        g, phi = _completion_share(model, projector, key // n, key % n)
        t = target[c[at]]
        q[at] = g[t]
        after[at] = projector.edge_between(target[f[at]], phi[t])
    ok = (q > 0) & (after >= 0)
    c, f, action, q, after = c[ok], f[ok], action[ok], q[ok], after[ok]
    key = c * A + action
    order = np.argsort(key, kind="stable")
    c, f, action, q, after, key = c[order], f[order], action[order], q[order], after[order], key[order]
    start = np.searchsorted(c, np.arange(model.n_classes + 1))
    arrays = (key, c, action, q, after, model.class_match_reward[f].astype(float), np.full(c.size, -1, np.int64),
              f, start)
    for x in arrays:
        x.flags.writeable = False
    return ParallelTable(A, *arrays, rule=rule, projector=projector)


def project_path(projector: Projector, path: list[int], position: int, robot_edge: int) -> list[int] | None:
    """The projection (module docstring) of the operator's ``path[position:]`` (state edges of
    ``projector.states``) onto the target of the robot's ``robot_edge`` (out of the state ``path[position]``
    starts at), as state edges from there; None when it is not feasible. Cost: O(k (n + log S + log E)) for k
    steps."""
    states = projector.states
    op = int(states.edge_operation[robot_edge])
    a, b = int(projector.first_part[op]), int(projector.second_part[op])
    here = int(states.edge_target[robot_edge])
    out = []
    for i in range(position, len(path)):
        t = int(states.edge_target[path[i]])
        joined, phi = projector.phi(a, b, np.array([t]))
        if joined[0]:
            return out + list(path[i + 1:]) if here == t else None
        edge = int(projector.edge_between(np.array([here]), phi)[0])
        if edge < 0:
            return None
        out.append(edge)
        here = int(phi[0])
    return None  # never joined: not a path to the final state


def projected_rewrite(model, path: list[int], position: int, action: int) -> list[int]:
    """The operator's true sequence after the robot's ``action`` at ``position`` (a simulator's world): when the
    action is a pair of ``path[position]`` and the projection of ``path[position:]`` is feasible (right), the
    path with the robot's edge ``f`` at ``position`` and the projection after it (the episode then counts the
    step as the robot's, with its reward); else (wrong) ``path`` itself."""
    par = model.parallel
    _, p = par.find(np.array([path[position]]), action)
    if not p.size:
        return path
    f = int(par.robot_edge[p[0]])
    rest = project_path(par.projector, path, position, f)
    return path if rest is None else path[:position] + [f] + rest
