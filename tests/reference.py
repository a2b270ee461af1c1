"""A deliberately naive, literal reference implementation used to cross-check the planner on small products.

It tries every subset of parts (no cut enumeration, no bitmask tricks, no numpy), builds the assembly
state graph with Python sets exactly as Alg. 1 reads, and enumerates intentions as Alg. 2 reads. For the
decision models, :func:`horizon_value` is the exact finite-horizon value by expectimax (every action and
observation), which the flat, lumped and weighted models must share.
"""
from __future__ import annotations

from functools import lru_cache
from itertools import combinations

import numpy as np


def connected(parts: frozenset, contacts: set) -> bool:
    if not parts:
        return False
    start = next(iter(parts))
    seen, todo = {start}, [start]
    while todo:
        a = todo.pop()
        for b in parts:
            if b not in seen and frozenset((a, b)) in contacts:
                seen.add(b)
                todo.append(b)
    return seen == set(parts)


def andor(product, technical=None):
    """(subassemblies, operations) with operations as (parent, frozenset({child1, child2}))."""
    product = product.with_technical(technical)
    parts = frozenset(product.part_ids)
    contacts = {frozenset(c) for c in product.contacts}
    relations = [set(o.blocks) for o in product.obstructions]
    constraints = [(c.parts, c.requires) for c in product.technical_constraints if c.active]

    def tech_ok(s):
        return len(s) == 1 or not any(r1 <= s and r2 not in s for r1, r2 in constraints)

    def free(moving, fixed):
        if not relations:
            return True
        for rel in relations:
            if not any((x, y) in rel for x in moving for y in fixed):
                return True
            if not any((y, x) in rel for x in moving for y in fixed):
                return True  # moving along the reverse direction
        return False

    @lru_cache(maxsize=None)
    def splits(s):
        out = []
        items = sorted(s)
        for k in range(1, len(items)):
            for first in combinations(items, k):
                a = frozenset(first)
                b = s - a
                if min(a) != min(s):
                    continue
                if feasible(a) and feasible(b) and free(a, b):
                    out.append((a, b))
        return tuple(out)

    @lru_cache(maxsize=None)
    def feasible(s):
        if not connected(s, contacts) or not tech_ok(s):
            return False
        return len(s) == 1 or bool(splits(s))

    if not feasible(parts):
        return None
    seen, todo, ops = {parts}, [parts], set()
    while todo:
        s = todo.pop()
        if len(s) == 1:
            continue
        for a, b in splits(s):
            ops.add((s, frozenset((a, b))))
            for c in (a, b):
                if c not in seen:
                    seen.add(c)
                    todo.append(c)
    return seen, ops


def state_graph(subassemblies, operations):
    """Alg. 1 literally: states are frozensets of subassemblies; edges (S', S, operation)."""
    by_parent = {}
    for parent, children in operations:
        by_parent.setdefault(parent, []).append(children)
    full = max(subassemblies, key=len)
    states, edges, open_states = {frozenset([full])}, set(), [frozenset([full])]
    while open_states:
        s = open_states.pop()
        for x in s:
            for children in by_parent.get(x, []):
                s2 = (s - {x}) | children
                edges.add((s2, s, (x, children)))
                if s2 not in states:
                    states.add(s2)
                    open_states.append(s2)
    return states, edges


def intentions(states, edges):
    """Alg. 2 literally: intentions are tuples of states ending at the final state."""
    incoming = {}
    for src, dst, _ in edges:
        incoming.setdefault(dst, []).append(src)
    final = next(s for s in states if len(s) == 1)
    found, todo = {(final,)}, [(final,)]
    while todo:
        path = todo.pop()
        for x in incoming.get(path[0], []):
            new = (x,) + path
            found.add(new)
            todo.append(new)
    return found


def horizon_value(model, depth: int) -> float:
    """The optimal value of ``depth`` decisions at the initial belief, by exact expectimax over every action and
    observation (beliefs kept unnormalised: the value is linear in them)."""
    import numpy as np  # the only numpy here: the decision model's tables are arrays

    T = [t.toarray() for t in model.transition]
    O = [o.toarray() for o in model.observation]
    R = model.reward

    def value(B, d):  # B (n, S) unnormalised beliefs -> (n,) values
        if d == 1:
            return (B @ R.T).max(axis=1)
        q = np.empty((len(B), model.n_actions))
        for a in range(model.n_actions):
            nxt = (B @ T[a])[:, None, :] * O[a].T[None]               # (n, Z, S)
            q[:, a] = B @ R[a] + model.discount * value(nxt.reshape(-1, model.n_states), d - 1).reshape(
                len(B), -1).sum(axis=1)
        return q.max(axis=1)
    return float(value(model.initial[None], depth)[0])



def filtered_histories(flat_model, fact, lumped, rng, episodes: int, steps: int = 20, tolerance: float = 1e-9):
    """The flat filter (``flat_model``: an IntentionModel), the factored one (``fact``) and the lumped POMDP's
    (``lumped``) along random histories drawn from the flat model (even episodes wait, odd ones act at random):
    yields ``(flat belief, factored belief, lumped belief)`` at every step, after checking that the observation
    probabilities of the flat and lumped POMDPs agree to ``tolerance``; at the end of each, that no filter
    reset. For the equivalence tests of the weighted models."""
    from planner.decision import DiscreteUpdater, FactoredUpdater

    flat = flat_model.pomdp
    transition = [t.tocsr() for t in flat.transition]
    observation = flat.observation[0].tocsr()
    starts = flat_model.full_sequences()
    for episode in range(episodes):
        up_flat = DiscreteUpdater(flat, reset_weights=flat_model.prior_weights)
        up_fact, up_lump = FactoredUpdater(fact), DiscreteUpdater(lumped)
        b, belief, c = up_flat.initialize(), up_fact.initialize(), up_lump.initialize()
        state = int(rng.choice(starts, p=flat.initial[starts]))
        for _ in range(steps):
            yield b, belief, c
            if state == flat_model.final_state:
                break
            a = int(rng.integers(flat.n_actions)) if episode % 2 else flat.n_actions - 1
            row = transition[a].getrow(state)
            state = int(rng.choice(row.indices, p=row.data / row.data.sum()))
            orow = observation.getrow(state)
            z = int(rng.choice(orow.indices, p=orow.data / orow.data.sum()))
            zb = flat.observation[a].T @ (flat.transition[a].T @ b)
            zc = lumped.observation[a].T @ (lumped.transition[a].T @ c)
            assert np.abs(zb - zc).max() <= tolerance
            b, belief, c = up_flat.update(b, a, z), up_fact.update(belief, a, z), up_lump.update(c, a, z)
        assert not up_flat.events and not up_fact.events
