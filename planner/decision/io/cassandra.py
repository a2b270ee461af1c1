"""Cassandra's ``.pomdp`` text format (pomdp-solve, and many other tools): read and write.

Read: ``discount``, ``values`` (``reward`` or ``cost``), ``states``/``actions``/``observations`` (a count or
names), ``start`` (a vector, ``uniform``, a state, or ``include:``/``exclude:`` lists), and ``T``, ``O``, ``R``
entries in all three shapes (single value, row, matrix, with ``*`` wildcards and ``identity``/``uniform``).
Rewards that depend on the next state or the observation are folded into ``R(s, a)`` by expectation.
Errors name the line.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...errors import PlannerError
from ...files import write_atomic
from ..pomdp import POMDP, ModelError

__all__ = ["CassandraError", "read_cassandra", "write_cassandra", "cassandra_text"]


class CassandraError(PlannerError):
    """A ``.pomdp`` file is malformed (the message names the line)."""


def _tokens(text: str):
    """(line number, token) pairs; ``#`` starts a comment; ``:`` is a token of its own."""
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0]
        for tok in re.findall(r":|[^\s:]+", line):
            yield number, tok


class _Stream:
    def __init__(self, text: str, source: str):
        self.items = list(_tokens(text))
        self.i = 0
        self.source = source

    def fail(self, problem: str, line: int | None = None) -> CassandraError:
        if line is None:
            line = self.items[min(self.i, len(self.items) - 1)][0] if self.items else 0
        return CassandraError(f"{self.source}: line {line}: {problem}")

    def peek(self):
        return self.items[self.i][1] if self.i < len(self.items) else None

    def take(self):
        if self.i >= len(self.items):
            raise self.fail("unexpected end of file")
        tok = self.items[self.i][1]
        self.i += 1
        return tok

    def expect(self, tok):
        got = self.take()
        if got != tok:
            raise self.fail(f"expected {tok!r}, got {got!r}")

    def number(self) -> float:
        tok = self.take()
        try:
            return float(tok)
        except ValueError:
            raise self.fail(f"expected a number, got {tok!r}") from None

    def numbers(self, count: int) -> np.ndarray:
        return np.array([self.number() for _ in range(count)])


def _is_number(tok) -> bool:
    try:
        float(tok)
        return True
    except (TypeError, ValueError):
        return False


_KEYS = ("discount", "values", "states", "actions", "observations", "start")


def _names_end(st: _Stream, stop: tuple[str, ...]) -> bool:
    """Whether a list of names ends here: the end of the file, a keyword, or the next ``key :``."""
    return (st.peek() is None or st.peek() in stop
            or (st.i + 1 < len(st.items) and st.items[st.i + 1][1] == ":"))


def _declaration(st: _Stream, key: str, names: dict[str, list[str]], header: dict) -> None:
    """One preamble declaration ``key: ...`` (``key`` taken already) into ``names`` or ``header``."""
    if key == "start" and st.peek() in ("include", "exclude"):
        mode = st.take()
        st.expect(":")
        items = []
        while not _names_end(st, ("T", "O", "R")):
            items.append(st.take())
        header["start"] = (mode, items)
        return
    st.expect(":")
    if key == "discount":
        header["discount"] = st.number()
    elif key == "values":
        value = st.take()
        if value not in ("reward", "cost"):
            raise st.fail(f"values must be reward or cost, got {value!r}")
        header["sign"] = 1.0 if value == "reward" else -1.0
    elif key == "start":
        if st.peek() == "uniform":
            st.take()
            header["start"] = ("uniform", None)
        elif "states" in names and _is_number(st.peek()):
            header["start"] = ("vector", st.numbers(len(names["states"])))
        else:
            header["start"] = ("state", st.take())
    else:
        tok = st.take()
        if tok.isdigit():
            prefix = {"states": "s", "actions": "a", "observations": "o"}[key]
            names[key] = [f"{prefix}{k}" for k in range(int(tok))]
        else:
            items = [tok]
            while not _names_end(st, _KEYS + ("T", "O", "R")):
                items.append(st.take())
            names[key] = items


def _initial_belief(st: _Stream, names: dict[str, list[str]], spec) -> np.ndarray:
    """The ``start`` declaration as a belief (uniform when there is none)."""
    S = len(names["states"])
    if spec is None or spec[0] == "uniform":
        return np.full(S, 1.0 / S)
    if spec[0] == "vector":
        return spec[1]
    initial = np.zeros(S)
    if spec[0] == "state":
        initial[_index(st, names["states"], spec[1])] = 1.0
        return initial
    chosen = {_index(st, names["states"], x) for x in spec[1]}
    if spec[0] == "exclude":
        chosen = set(range(S)) - chosen
    initial[sorted(chosen)] = 1.0 / len(chosen)
    return initial


def read_cassandra(path: str | Path) -> POMDP:
    """Read a ``.pomdp`` file into a :class:`POMDP`."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="strict")
    except (OSError, UnicodeDecodeError) as exc:
        raise CassandraError(f"{source}: cannot read the file: {exc}") from None
    st = _Stream(text, source)
    names: dict[str, list[str]] = {}
    header: dict = {"discount": None, "sign": 1.0, "start": None}
    T = O = R = None
    while st.peek() is not None:
        key = st.take()
        if key in _KEYS:
            _declaration(st, key, names, header)
            if all(k in names for k in ("states", "actions", "observations")) and T is None:
                S, A, Z = (len(names[k]) for k in ("states", "actions", "observations"))
                T, O, R = np.zeros((A, S, S)), np.zeros((A, S, Z)), np.zeros((A, S, S, Z))
        elif key in ("T", "O", "R"):
            if T is None:
                raise st.fail(f"{key} entry before states, actions and observations are declared")
            _entry(st, key, names, T, O, R)
        else:
            raise st.fail(f"unexpected {key!r}")
    if T is None:
        raise CassandraError(f"{source}: states, actions and observations must be declared")
    if header["discount"] is None:
        raise CassandraError(f"{source}: no discount")
    initial = _initial_belief(st, names, header["start"])
    reward = header["sign"] * np.einsum("ast,atz,astz->as", T, O, R)
    try:
        return POMDP(tuple(names["states"]), tuple(names["actions"]), tuple(names["observations"]),
                     tuple(sp.csr_matrix(t) for t in T), tuple(sp.csr_matrix(o) for o in O), reward, initial,
                     header["discount"], name=Path(path).stem)
    except ModelError as exc:
        raise CassandraError(f"{source}: {exc}") from None


def _index(st: _Stream, names: list[str], tok: str):
    if tok == "*":
        return slice(None)
    if tok.isdigit() and int(tok) < len(names):
        return int(tok)
    if tok in names:
        return names.index(tok)
    raise st.fail(f"unknown name {tok!r}")


def _entry(st: _Stream, key: str, names, T, O, R) -> None:
    line = st.items[st.i - 1][0]
    st.expect(":")
    sets = {"T": ("actions", "states", "states"), "O": ("actions", "states", "observations"),
            "R": ("actions", "states", "states", "observations")}[key]
    idx = []
    for k, kind in enumerate(sets):
        if k > 0:
            if st.peek() != ":":
                break
            st.take()
        idx.append(_index(st, names[kind], st.take()))
    table = {"T": T, "O": O, "R": R}[key]
    target = table[tuple(idx)]
    if len(idx) == len(sets):
        table[tuple(idx)] = st.number()
        return
    shape = np.shape(target)
    if st.peek() in ("identity", "uniform"):
        word = st.take()
        if word == "identity" and key == "T" and len(idx) == 1:
            table[tuple(idx)] = np.eye(shape[-1])
        elif word == "uniform":
            table[tuple(idx)] = 1.0 / shape[-1]
        else:
            raise st.fail(f"{word!r} does not fit this {key} entry", line)
        return
    count = int(np.prod(shape[len(shape) - (len(sets) - len(idx)):])) if key != "R" else shape[-1]
    values = st.numbers(count)
    if key == "R":
        table[tuple(idx)] = values  # broadcast over any remaining wildcard axes
    else:
        table[tuple(idx)] = values.reshape(shape[len(shape) - (len(sets) - len(idx)):])


def cassandra_text(model: POMDP) -> str:
    """The ``.pomdp`` text of ``model`` (sparse entries; names as identifiers)."""
    token = lambda n: re.sub(r"[^A-Za-z0-9_]+", "_", n).strip("_") or "x"  # noqa: E731
    S = [f"s{i}_{token(n)}" for i, n in enumerate(model.states)]
    A = [f"a{i}_{token(n)}" for i, n in enumerate(model.actions)]
    Z = [f"o{i}_{token(n)}" for i, n in enumerate(model.observations)]
    num = lambda x: f"{float(x):.15f}".rstrip("0").rstrip(".") or "0"  # noqa: E731
    lines = [f"# {model.name}", f"discount: {num(model.discount)}", "values: reward", "states: " + " ".join(S),
             "actions: " + " ".join(A), "observations: " + " ".join(Z),
             "start: " + " ".join(num(p) for p in model.initial), ""]
    for a, t in enumerate(model.transition):
        coo = t.tocoo()
        lines += [f"T: {A[a]} : {S[s]} : {S[s2]} {num(p)}" for s, s2, p in sorted(zip(coo.row, coo.col, coo.data))]
    for a, o in enumerate(model.observation):
        coo = o.tocoo()
        lines += [f"O: {A[a]} : {S[s]} : {Z[z]} {num(p)}" for s, z, p in sorted(zip(coo.row, coo.col, coo.data))]
    for a in range(model.n_actions):
        lines += [f"R: {A[a]} : {S[s]} : * : * {num(model.reward[a, s])}"
                  for s in np.flatnonzero(model.reward[a])]
    return "\n".join(lines) + "\n"


def write_cassandra(model: POMDP, path: str | Path) -> None:
    """Write ``model`` as a ``.pomdp`` file (atomically)."""
    write_atomic(path, cassandra_text(model))
