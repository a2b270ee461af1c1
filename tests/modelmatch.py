"""Find a renumbering of states, actions and observations that makes two POMDPs' tables equal.

Colour refinement (Weisfeiler-Leman) over the tables: every state, action and observation gets a colour
from its own tables and its neighbours' colours until the colours stop splitting; classes that stay
ambiguous (symmetries) are split by individualising one member at a time. The result is checked entry by
entry, so a wrong renumbering can never pass.
"""
from __future__ import annotations

import numpy as np

from planner.decision.pomdp import POMDP


def _refine(T, O, R, b0, fixed):
    A, S, _ = T.shape
    Z = O.shape[2]
    q = lambda x: round(float(x), 5)  # noqa: E731  (the authors write 6 significant digits)
    cs = [("s", q(b0[s]), fixed.get(("s", s))) for s in range(S)]
    ca = [("a", fixed.get(("a", a))) for a in range(A)]
    cz = [("z", fixed.get(("z", z))) for z in range(Z)]
    for _ in range(S + A + Z):
        ns = [hash((cs[s], tuple(sorted((ca[a], q(R[a, s]), tuple(sorted((q(T[a, s, t]), cs[t])
                                                                          for t in np.flatnonzero(T[a, s]))))
                                         for a in range(A))),
                    tuple(sorted((q(O[0, s, z]), cz[z]) for z in np.flatnonzero(O[0, s])))))
              for s in range(S)]
        na = [hash((ca[a], tuple(sorted((cs[s], q(R[a, s]), tuple(sorted((q(T[a, s, t]), cs[t])
                                                                          for t in np.flatnonzero(T[a, s]))))
                                         for s in range(S)))))
              for a in range(A)]
        nz = [hash((cz[z], tuple(sorted((q(O[0, s, z]), cs[s]) for s in np.flatnonzero(O[0, :, z])))))
              for z in range(Z)]
        done = (len(set(ns)), len(set(na)), len(set(nz))) == (len(set(cs)), len(set(ca)), len(set(cz)))
        cs, ca, cz = ns, na, nz
        if done:
            break
    return {"s": cs, "a": ca, "z": cz}


def renumbering(ours: POMDP, theirs: POMDP) -> dict[str, np.ndarray] | None:
    """Arrays ``perm[kind][i]`` = the index in ``theirs`` of item ``i`` of ``ours``, or None."""
    if (ours.n_states, ours.n_actions, ours.n_observations) != (theirs.n_states, theirs.n_actions,
                                                                 theirs.n_observations):
        return None
    tables = []
    for model in (ours, theirs):
        T, O = model.dense()
        if not np.allclose(O, O[:1]):
            raise ValueError("observation tables that depend on the action are not handled here")
        tables.append((T, O, model.reward, model.initial))
    fixed_ours, fixed_theirs = {}, {}
    for label in range(ours.n_states + ours.n_actions + ours.n_observations):
        mine, other = _refine(*tables[0], fixed_ours), _refine(*tables[1], fixed_theirs)
        perm = {}
        for kind in ("s", "a", "z"):
            if sorted(mine[kind]) != sorted(other[kind]):
                return None
            where = {}
            for j, c in enumerate(other[kind]):
                where.setdefault(c, []).append(j)
            perm[kind] = where
        ambiguous = [(k, c) for k in ("s", "a", "z") for c, js in perm[k].items() if len(js) > 1]
        if not ambiguous:
            result = {k: np.array([perm[k][c][0] for c in mine[k]]) for k in ("s", "a", "z")}
            return result if _equal(ours, theirs, result) else None
        kind, colour = ambiguous[0]
        i = mine[kind].index(colour)
        fixed_ours[(kind, i)] = fixed_theirs[(kind, perm[kind][colour][0])] = ("fixed", label)
    return None


def _equal(ours: POMDP, theirs: POMDP, perm) -> bool:
    s, a, z = perm["s"], perm["a"], perm["z"]
    T1, O1 = ours.dense()
    T2, O2 = theirs.dense()
    return (np.allclose(T1, T2[a][:, s][:, :, s], atol=1e-6) and np.allclose(O1, O2[a][:, s][:, :, z], atol=1e-6)
            and np.allclose(ours.reward, theirs.reward[a][:, s]) and np.allclose(ours.initial, theirs.initial[s],
                                                                                atol=1e-6)
            and abs(ours.discount - theirs.discount) < 1e-9)
