"""Cassandra's ``.pomdp`` text format (pomdp-solve, and many other tools): read and write.

Read: ``discount``, ``values`` (``reward`` or ``cost``), ``states``/``actions``/``observations`` (a count or
names), ``start`` (a vector, ``uniform``, a state, or ``include:``/``exclude:`` lists), and ``T``, ``O``, ``R``
entries in all three shapes (single value, row, matrix, with ``*`` wildcards and ``identity``/``uniform``).
Where entries overlap, the later one wins. Rewards that depend on the next state or the observation are
folded into ``R(s, a)`` by expectation over ``T`` and ``O``. Errors name the line.

Both directions stay sparse: the reader streams the file's tokens into
:class:`~planner.decision.io.sparse_tables.SparseTable` and CSR matrices (never a dense A x S x S table, nor the
A x S x S x Z reward) and evaluates the reward only where ``T(s' | s, a) O(z | s', a)`` is non-zero; the
writer streams the CSR entries. Memory O(nnz), time O(nnz log nnz) for nnz non-zero entries.
"""
from __future__ import annotations

import re
from collections import deque
from pathlib import Path

import numpy as np

from ...defaults import SPREAD_CELL_LIMIT
from ...errors import PlannerError
from ...files import open_atomic
from ...validation import CELLS_OPTION, DECLARED_OPTION, INPUT_OPTION, InputLimitError, InputLimits, not_regular
from ..pomdp import POMDP, ModelError
from .sparse_tables import SparseTable, split_rows

__all__ = ["CassandraError", "read_cassandra", "write_cassandra", "cassandra_text", "cassandra_chunks",
           "expected_reward"]


class CassandraError(PlannerError):
    """A ``.pomdp`` file is malformed (the message names the line)."""


_SPLIT = re.compile(r":|[^\s:]+").findall  # ':' is a token of its own


class _Stream:
    """The file's tokens, read a line at a time (the file is never held as a token list); ``#`` starts a
    comment. Errors name the line of the last token taken."""

    def __init__(self, lines, source: str):
        self.lines = enumerate(lines, start=1)
        self.ahead: deque = deque()  # (line number, token) pairs read but not taken
        self.line = 0  # the line of the last token taken
        self.source = source

    def _fill(self, k: int) -> bool:
        while len(self.ahead) <= k:
            item = next(self.lines, None)
            if item is None:
                return False
            self.push(item)
        return True

    def push(self, item: tuple[int, str]) -> None:
        """Queue the tokens of the line ``item`` (its number, its text)."""
        number, text = item
        self.ahead.extend((number, tok) for tok in _SPLIT(text.split("#", 1)[0]))

    def raw_line(self) -> tuple[int, str] | None:
        """The next line as it is, when no token is pending (for one-line entries); else None."""
        return None if self.ahead else next(self.lines, None)

    def fail(self, problem: str, line: int | None = None) -> CassandraError:
        return CassandraError(f"{self.source}: line {self.line if line is None else line}: {problem}")

    def peek(self, k: int = 0):
        return self.ahead[k][1] if self._fill(k) else None

    def take(self):
        if not self._fill(0):
            raise self.fail("unexpected end of file")
        self.line, tok = self.ahead.popleft()
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
    return st.peek() is None or st.peek() in stop or st.peek(1) == ":"


def _declaration(st: _Stream, key: str, names: dict[str, list[str]], header: dict, limit: int) -> None:
    """One preamble declaration ``key: ...`` (``key`` taken already) into ``names`` or ``header``; at most
    ``limit`` names declared."""
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
            count = int(tok)
            if count == 0:
                raise st.fail(f"{key}: 0; a model needs at least one")
            if count > limit:
                raise st.fail(f"{key}: {count:,}, more than the limit of {limit:,} declared values "
                              f"({DECLARED_OPTION} raises it)")
            names[key] = [f"{prefix}{k}" for k in range(count)]
        else:
            items = [tok]
            while not _names_end(st, _KEYS + ("T", "O", "R")):
                items.append(st.take())
                if len(items) > limit:
                    raise st.fail(f"{key}: more than the limit of {limit:,} declared values "
                                  f"({DECLARED_OPTION} raises it)")
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
    if not chosen:
        raise CassandraError(f"{st.source}: start {spec[0]}: leaves no state to start from; list at least one "
                             f"state{' to include' if spec[0] == 'include' else ' that is not excluded'}")
    initial[sorted(chosen)] = 1.0 / len(chosen)
    return initial


def read_cassandra(path: str | Path, limits: InputLimits = InputLimits()) -> POMDP:
    """Read a ``.pomdp`` file into a :class:`POMDP`.

    Memory: O(entries) for the entries the file lists (kept sparse) plus the dense (A, S) reward; never
    A x S x S. Time: O(tokens + nnz log nnz), the reward O(sum over actions a of nnz(T_a) x k log N), k the
    mean non-zeros of an observation row, N the reward entries. ``limits``: the file's bytes, the values
    declared and the cells spread per table (:class:`~planner.validation.InputLimits`)."""
    source = str(path)
    if not_regular(path, "model"):
        raise CassandraError(not_regular(path, "model"))
    try:
        size = Path(path).stat().st_size
        if size > limits.file_bytes:
            raise CassandraError(f"{source}: {size:,} bytes, more than the limit of {limits.file_bytes:,} for a "
                                 f"model file ({INPUT_OPTION} raises it)")
        with open(path, encoding="utf-8", errors="strict") as lines:
            return _read(lines, source, limits)
    except (OSError, UnicodeDecodeError) as exc:
        raise CassandraError(f"{source}: cannot read the file: {exc}") from None


def _read(lines, source: str, limits: InputLimits = InputLimits()) -> POMDP:
    st = _Stream(lines, source)
    names: dict[str, list[str]] = {}
    header: dict = {"discount": None, "sign": 1.0, "start": None}
    tables, positions = None, {}  # both set once states, actions and observations are declared
    while True:
        if tables is not None and not st.ahead:
            item = st.raw_line()
            if item is None:
                break
            try:
                if _one_line_entry(st, item, names, positions, tables):
                    continue
            except InputLimitError as exc:
                raise st.fail(str(exc)) from None
            st.push(item)
        if st.peek() is None:
            break
        key = st.take()
        if key in _KEYS:
            _declaration(st, key, names, header, limits.declared)
            if all(k in names for k in ("states", "actions", "observations")) and tables is None:
                S, A, Z = (len(names[k]) for k in ("states", "actions", "observations"))
                tables = {"T": SparseTable((A, S, S), limits.spread_cells),
                          "O": SparseTable((A, S, Z), limits.spread_cells),
                          "R": SparseTable((A, S, S, Z), cell_limit=None)}  # looked up only, never spread
                positions = {k: {} for k in ("states", "actions", "observations")}
                for k, table in positions.items():
                    for i, n in enumerate(names[k]):
                        table.setdefault(n, i)
        elif key in ("T", "O", "R"):
            if tables is None:
                raise st.fail(f"{key} entry before states, actions and observations are declared")
            try:
                _entry(st, key, names, positions, tables[key])
            except InputLimitError as exc:
                raise st.fail(str(exc)) from None
        else:
            raise st.fail(f"unexpected {key!r}")
    if tables is None:
        raise CassandraError(f"{source}: states, actions and observations must be declared")
    if header["discount"] is None:
        raise CassandraError(f"{source}: no discount")
    initial = _initial_belief(st, names, header["start"])
    try:
        transition, observation = split_rows(tables["T"]), split_rows(tables["O"])
    except InputLimitError as exc:  # entries for some actions, others for '*': the spread counted per action
        raise CassandraError(f"{source}: {exc}") from None
    try:
        reward = header["sign"] * expected_reward(transition, observation, tables["R"], limits.spread_cells)
    except InputLimitError as exc:
        raise CassandraError(f"{source}: {exc}") from None
    try:
        return POMDP(tuple(names["states"]), tuple(names["actions"]), tuple(names["observations"]),
                     transition, observation, reward, initial, header["discount"], name=Path(source).stem)
    except ModelError as exc:
        raise CassandraError(f"{source}: {exc}") from None


def expected_reward(transition, observation, table: SparseTable, cell_limit: int = SPREAD_CELL_LIMIT) -> np.ndarray:
    """``R(s, a) = sum over s', z of T(s' | s, a) O(z | s', a) R(s, a, s', z)`` for the (A, S, S, Z) reward
    ``table``, evaluated only where ``T O`` is non-zero (never the dense A x S x S x Z array).
    Cost per action a: O(nnz(T_a) k log N) time and O(nnz(T_a) k) memory, k the mean non-zeros of an
    observation row, N the reward entries. Past ``cell_limit`` combinations for an action:
    :class:`~planner.validation.InputLimitError`."""
    A, S, _, Z = table.shape
    reward = np.zeros((A, S))
    if not table.order:
        return reward
    if table.leaves_free((2, 3)):  # R: a : s : * : * only (as aplan writes them): R(s, a) is the entry itself,
        for a in range(A):       # the rows of T O summing to 1; looked up at (a, s, 0, 0), O(A S log N)
            reward[a] = table.values_at(((a * S + np.arange(S, dtype=np.int64)) * S) * Z)
        return reward
    for a, (t, o) in enumerate(zip(transition, observation)):
        coo = t.tocoo()
        counts = np.diff(o.indptr)[coo.col]
        total = int(counts.sum())
        if not total:
            continue
        if total > cell_limit:  # the temporaries below hold about 60 bytes per combination
            raise InputLimitError(f"the reward of action {a} would be evaluated over {total:,} (state, next state, "
                                  f"observation) combinations with non-zero probability, more than the limit of "
                                  f"{cell_limit:,} ({CELLS_OPTION} raises it); give rewards as R: a : s : * : * (they "
                                  "do not depend on the next state or the observation), or make the tables sparser")
        # every (s, s', z) with T(s' | s, a) O(z | s', a) > 0: each T entry repeated over its observation row
        position = np.repeat(o.indptr[coo.col] - (np.cumsum(counts) - counts), counts) + np.arange(total)
        s, s2 = np.repeat(coo.row, counts).astype(np.int64), np.repeat(coo.col, counts).astype(np.int64)
        weight = np.repeat(coo.data, counts) * o.data[position]
        lin = ((a * S + s) * S + s2) * Z + o.indices[position]
        reward[a] = np.bincount(s, weights=weight * table.values_at(lin), minlength=S)
    return reward


def _index(st: _Stream, names: list[str], tok: str, positions: dict[str, int] | None = None):
    """The position of ``tok`` in ``names``: a number below their count, else a name (``positions``: the
    names' positions, the first of duplicates, so that a lookup is O(1)); ``None`` for ``*``."""
    if tok == "*":
        return None
    if tok.isdigit() and int(tok) < len(names):
        return int(tok)
    position = positions.get(tok) if positions is not None else (names.index(tok) if tok in names else None)
    if position is None:
        raise st.fail(f"unknown name {tok!r}")
    return position


_SETS = {"T": ("actions", "states", "states"), "O": ("actions", "states", "observations"),
         "R": ("actions", "states", "states", "observations")}


def _one_line_entry(st: _Stream, item: tuple[int, str], names, positions, tables) -> bool:
    """Read ``item`` (a line's number and text) if it is one whole single-value entry, ``T: a : s : s' p``
    (the bulk of a large file), and say whether it was; the same result as :func:`_entry`, several times
    faster."""
    parts = item[1].split("#", 1)[0].split(":")
    key = parts[0].strip()
    if key not in tables or len(parts) != len(_SETS[key]) + 1:
        return False
    last = parts[-1].split()
    if len(last) != 2:
        return False
    tokens = [part.split() for part in parts[1:-1]]
    if any(len(t) != 1 for t in tokens):
        return False
    st.line = item[0]
    index = tuple(_index(st, names[kind], tok, positions[kind])
                  for kind, tok in zip(_SETS[key], [t[0] for t in tokens] + [last[0]]))
    try:
        value = float(last[1])
    except ValueError:
        raise st.fail(f"expected a number, got {last[1]!r}") from None
    tables[key].set(index, value)
    return True


def _entry(st: _Stream, key: str, names, positions, table: SparseTable) -> None:
    """One ``T``, ``O`` or ``R`` entry (``key`` taken already) into ``table``: a single value when every index
    is given, else ``identity``, ``uniform`` or the numbers over the indices left out (a row, a matrix)."""
    line = st.line
    st.expect(":")
    sets = _SETS[key]
    idx = []
    for k, kind in enumerate(sets):
        if k > 0:
            if st.peek() != ":":
                break
            st.take()
        idx.append(_index(st, names[kind], st.take(), positions[kind]))
    if len(idx) == len(sets):
        table.set(tuple(idx), st.number())
        return
    rest = tuple(range(len(idx), len(sets)))
    index = tuple(idx) + (None,) * len(rest)
    if st.peek() in ("identity", "uniform"):
        word = st.take()
        if word == "identity" and key == "T" and len(idx) == 1:
            table.set_identity(index, (1, 2))
        elif word == "uniform":
            table.set(index, 1.0 / table.shape[-1])
        else:
            raise st.fail(f"{word!r} does not fit this {key} entry", line)
        return
    shape = tuple(table.shape[k] for k in rest)
    table.set_listed(index, rest, st.numbers(int(np.prod(shape))).reshape(shape))


def _num(x: float) -> str:
    """The shortest fixed-point text that reads back as the same float: files round-trip exactly."""
    return np.format_float_positional(float(x), unique=True, trim="-")


def cassandra_chunks(model: POMDP):
    """The ``.pomdp`` text of ``model`` in pieces, streamed from the sparse tables: one ``T``/``O`` line per
    non-zero entry (``O: *`` once when the observation table does not depend on the action), one
    ``R: a : s : * : *`` line per non-zero reward; names as identifiers.
    Memory O(S) beyond the model; time O(nnz)."""
    token = lambda n: re.sub(r"[^A-Za-z0-9_]+", "_", n).strip("_") or "x"  # noqa: E731
    S = [f"s{i}_{token(n)}" for i, n in enumerate(model.states)]
    A = [f"a{i}_{token(n)}" for i, n in enumerate(model.actions)]
    Z = [f"o{i}_{token(n)}" for i, n in enumerate(model.observations)]
    name = " ".join(model.name.splitlines())
    yield "\n".join([f"# {name}", f"discount: {_num(model.discount)}", "values: reward", "states: " + " ".join(S),
                     "actions: " + " ".join(A), "observations: " + " ".join(Z),
                     "start: " + " ".join(_num(p) for p in model.initial), "", ""])
    first = model.observation[0]
    same = all(o is first or (o != first).nnz == 0 for o in model.observation[1:])
    observation = [("*", first)] if same else list(zip(A, model.observation))
    for key, tables, cols in (("T", list(zip(A, model.transition)), S), ("O", observation, Z)):
        for action, table in tables:
            coo = _sorted_coo(table)
            texts = _numbers(coo.data)
            yield "".join(f"{key}: {action} : {S[r]} : {cols[c]} {v}\n"
                          for r, c, v in zip(coo.row.tolist(), coo.col.tolist(), texts))
    for a in range(model.n_actions):
        nonzero = np.flatnonzero(model.reward[a])
        yield "".join(f"R: {A[a]} : {S[s]} : * : * {v}\n"
                      for s, v in zip(nonzero.tolist(), _numbers(model.reward[a, nonzero])))


def _numbers(values: np.ndarray) -> list[str]:
    """``_num`` of each value, formatting each distinct value once (a model has few distinct probabilities)."""
    distinct, inverse = np.unique(values, return_inverse=True)
    return np.array([_num(v) for v in distinct], dtype=object)[inverse.ravel()].tolist()


def _sorted_coo(table):
    """The entries of a CSR table in row-major order, columns increasing within a row."""
    table = table.tocsr()
    return (table if table.has_sorted_indices else table.sorted_indices()).tocoo()


def cassandra_text(model: POMDP) -> str:
    """The ``.pomdp`` text of ``model`` as one string (:func:`cassandra_chunks`; for small models)."""
    return "".join(cassandra_chunks(model))


def write_cassandra(model: POMDP, path: str | Path) -> None:
    """Write ``model`` as a ``.pomdp`` file (atomically), streamed: memory O(S + the largest table) beyond
    the model."""
    with open_atomic(path) as handle:
        for chunk in cassandra_chunks(model):
            handle.write(chunk.encode("utf-8"))
