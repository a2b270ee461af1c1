"""POMDPX files (APPL's XML format for SARSOP's ``pomdpsol``): read flat models, write sparse ones.

Only *flat* models are read: one state variable (``vnamePrev``/``vnameCurr``), one observation variable, one
action variable and one reward variable, with ``TBL`` parameters. Instances may use ``*`` (every value,
same probability) and ``-`` (every value, listed in the table) and tables may be ``identity`` or
``uniform``, as APPL defines them; where entries overlap, the later one wins. The writer lists only non-zero
entries, uses ``*`` for the action when the observation table does not depend on it and ``identity`` for an
action that leaves the state as it is, so a model of the pen takes kilobytes.

Both directions stay sparse: the reader streams the XML (one ``<Entry>`` in memory at a time) into
:class:`~planner.decision.io.sparse_tables.SparseTable` and CSR matrices, never a dense actions x states x
states array; the writer streams the entries of the CSR matrices to the file. Memory: O(nnz) for nnz non-zero
entries (plus the dense (A, S) reward table), time O(nnz log nnz).

The XML parser never expands entities, loads DTDs or touches the network.
"""
from __future__ import annotations

import gzip
import re
from pathlib import Path
from html import escape as _escape  # & < > only (quote=False): as xml.sax.saxutils.escape, without urllib

import numpy as np
from lxml import etree

from ...errors import PlannerError
from ...files import open_atomic
from ...validation import DECLARED_OPTION, INPUT_OPTION, CappedReader, InputLimitError, InputLimits, not_regular
from ..pomdp import POMDP, ModelError
from .sparse_tables import SparseTable, split_rows

__all__ = ["PomdpxError", "read_pomdpx", "write_pomdpx", "pomdpx_text", "pomdpx_chunks", "safe_parser"]

_SAFE = dict(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False, remove_comments=True)


class PomdpxError(PlannerError):
    """A POMDPX file is malformed or not a flat POMDP (the message names the line)."""


def safe_parser() -> etree.XMLParser:
    """An XML parser with entity expansion, DTD loading and network access disabled."""
    return etree.XMLParser(**_SAFE)


def _fail(source: str, element, problem: str) -> PomdpxError:
    line = f" line {element.sourceline}" if element is not None and element.sourceline else ""
    return PomdpxError(f"{source}:{line}: {problem}")


def _values(source, var, prefix, limit: int):
    enum = var.find("ValueEnum")
    if enum is not None and enum.text and enum.text.split():
        return enum.text.split()
    count = var.find("NumValues")
    if count is None or not (count.text or "").strip().isdigit():
        raise _fail(source, var, f"<{var.tag}> needs <NumValues> or <ValueEnum>")
    number = int(count.text)
    if number == 0:
        raise _fail(source, count, f"<{var.tag}> declares 0 values; a model needs at least one")
    if number > limit:
        raise _fail(source, count, f"<{var.tag}> declares {number:,} values, more than the limit of {limit:,} "
                                   f"({DECLARED_OPTION} raises it)")
    return [f"{prefix}{i}" for i in range(number)]


class _Section:
    """One table being read: its variables in the file's order and their axes in the table."""

    def __init__(self, source, cond, order, axes, shape, index, cell_limit: int):
        self.source, self.cond, self.order, self.index = source, cond, order, index
        self.axes = [axes[v] for v in order]  # file position -> table axis
        self.sizes = [shape[a] for a in self.axes]
        self.table = SparseTable(shape, cell_limit)

    def entry(self, entry) -> None:
        """Add one ``<Entry>`` to the table (APPL's semantics: ``*`` spreads one number, ``-`` lists them)."""
        source, order = self.source, self.order
        inst = table = None
        for child in entry:  # cheaper than find(): an entry has two children
            tag = child.tag
            if tag == "Instance":
                inst = child
            elif tag == "ProbTable" or (tag == "ValueTable" and table is None):
                table = child
        if inst is None or table is None or inst.text is None or table.text is None:
            raise _fail(source, entry, "an <Entry> needs an <Instance> and a <ProbTable> or <ValueTable>")
        tokens = inst.text.split()
        if len(tokens) != len(order):
            raise _fail(source, inst, f"instance {inst.text.strip()!r} has {len(tokens)} values, expected "
                                      f"{len(order)} ({' '.join(order)})")
        index = [None] * len(tokens)
        dash = []  # file positions of '-'
        for k, (tok, var) in enumerate(zip(tokens, order)):
            if tok == "-":
                dash.append(k)
            elif tok != "*":
                i = self.index[var].get(tok)
                if i is None:
                    raise _fail(source, inst, f"unknown value {tok!r} of variable {var!r}")
                index[self.axes[k]] = i
        text = table.text.split()
        if text == ["identity"]:
            if len(dash) < 2:
                raise _fail(source, table, "'identity' needs two '-' in the instance")
            self.table.set_identity(index, tuple(sorted((self.axes[dash[-2]], self.axes[dash[-1]]))))
            return
        if text == ["uniform"]:
            if not dash:
                raise _fail(source, table, "'uniform' needs a '-' in the instance")
            self.table.set(index, 1.0 / self.sizes[dash[-1]])
            return
        expected = 1
        for k in dash:
            expected *= self.sizes[k]
        if len(text) != expected:
            if not all(_is_number(x) for x in text):
                raise _fail(source, table, f"not a list of numbers: {table.text.strip()[:60]!r}")
            raise _fail(source, table, f"{len(text)} values for instance {inst.text.strip()!r}, expected {expected}")
        try:
            if not dash:
                self.table.set(index, float(text[0]))
                return
            values = np.array(text, dtype=float)
        except ValueError:
            raise _fail(source, table, f"not a list of numbers: {table.text.strip()[:60]!r}") from None
        # the file lists the '-' axes in its own order; the table wants them in increasing axis order
        listed = [self.axes[k] for k in dash]
        values = values.reshape([self.sizes[k] for k in dash]).transpose(np.argsort(listed))
        self.table.set_listed(index, tuple(sorted(listed)), values)


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _open(path, source, limit: int):
    if not_regular(path, "model"):
        raise PomdpxError(not_regular(path, "model"))
    try:
        return CappedReader(gzip.open(path) if source.endswith(".gz") else open(path, "rb"), limit, source,
                            INPUT_OPTION)
    except OSError as exc:
        raise PomdpxError(f"{source}: cannot read the file: {exc}") from None


def read_pomdpx(path: str | Path, limits: InputLimits = InputLimits()) -> POMDP:
    """Read a flat POMDPX file (optionally gzip-compressed, ``.gz``) into a :class:`POMDP`.

    The XML is streamed: each ``<Entry>`` goes into its table and is dropped. Memory: O(nnz) for the
    transition and observation tables' non-zero entries (and the cells the file lists, zeros included), plus
    the dense (A, S) reward; never A x S x S. Time: O(entries + nnz log nnz). ``limits``: the bytes read
    (decompressed), the values declared and the cells spread per table (:class:`~planner.validation.InputLimits`).
    """
    source = str(path)
    stream = _open(path, source, limits.file_bytes)
    try:
        with stream:
            return _read(stream, source, limits)
    except (OSError, EOFError) as exc:
        raise PomdpxError(f"{source}: cannot read the file: {exc}") from None
    except InputLimitError as exc:
        raise PomdpxError(str(exc)) from None
    except etree.XMLSyntaxError as exc:
        raise PomdpxError(f"{source}: line {exc.lineno}: malformed XML: {exc.msg}") from None


_SECTIONS = {"InitialStateBelief": "CondProb", "StateTransitionFunction": "CondProb", "ObsFunction": "CondProb",
             "RewardFunction": "Func"}


_ENTRY_PARTS = ("Entry", "Instance", "ProbTable", "ValueTable")
_ELEMENT_LIMIT = 100_000  # elements other than entries: each is kept until the end of the file


def _read(stream, source: str, limits: InputLimits) -> POMDP:
    root = variable = None
    names = {}  # variable name -> its values
    roles = {}  # 'prev', 'curr', 'obs', 'act' -> variable name
    found: dict[str, _Section] = {}
    section = section_of = None  # the table being read, and its <Parameter>
    text = {}  # texts of the top-level elements
    structural = 0  # elements kept in memory: all but the entries (and their children), which are dropped
    for _, element in etree.iterparse(stream, events=("end",), **_SAFE):
        tag = element.tag
        if tag not in _ENTRY_PARTS:
            structural += 1
            if structural > _ELEMENT_LIMIT:
                raise _fail(source, element, f"more than {_ELEMENT_LIMIT:,} elements besides the tables' <Entry>s; "
                                             "not a POMDPX file the planner reads (a flat model has a few dozen)")
        if tag == "Entry":
            parameter = element.getparent()
            if parameter is not section_of:  # the first entry of a table: its <Var> and <Parent> are read
                section_of = parameter
                section = None
                if parameter is not None and parameter.tag == "Parameter":
                    section = _start_section(source, parameter, names, roles, found, limits.spread_cells)
            if section is not None:
                try:
                    section.entry(element)
                except InputLimitError as exc:
                    raise _fail(source, element, str(exc)) from None
                element.clear()
                while element.getprevious() is not None:  # drop the entries read so far
                    del parameter[0]
            continue
        if root is None:
            root = element.getroottree().getroot()
            if root.tag != "pomdpx":
                raise _fail(source, root, f"the root element is <{root.tag}>, not <pomdpx>")
        parent = element.getparent()
        if tag == "Parameter" and parent is not None and element is not section_of:
            _start_section(source, element, names, roles, found, limits.spread_cells)  # a table with no entries
        elif tag == "Variable" and parent is root:
            variable = element
            _variables(source, variable, names, roles, limits.declared)
        elif tag in ("Discount", "Description") and parent is root:
            text[tag] = element.text
    if root is None:
        raise PomdpxError(f"{source}: no XML element")
    if variable is None:
        raise _fail(source, root, "no <Variable> element")
    for tag, child in _SECTIONS.items():
        if tag not in found:
            raise _fail(source, root, f"no <{tag}><{child}>")
    S = len(names[roles["prev"]])
    initial = found["InitialStateBelief"].table.dense().reshape(S)
    try:
        transition = split_rows(found["StateTransitionFunction"].table)
        observation = split_rows(found["ObsFunction"].table)
    except InputLimitError as exc:  # entries for some actions, others for '*': the spread counted per action
        raise PomdpxError(f"{source}: {exc}") from None
    reward = found["RewardFunction"].table.dense()
    try:
        discount = float(text.get("Discount"))
    except (TypeError, ValueError):
        raise _fail(source, root, "missing or invalid <Discount>") from None
    try:
        return POMDP(tuple(names[roles["prev"]]), tuple(names[roles["act"]]), tuple(names[roles["obs"]]),
                     transition, observation, reward, initial, discount,
                     name=(text.get("Description") or root.get("id") or "pomdpx").strip())
    except ModelError as exc:
        raise PomdpxError(f"{source}: {exc}") from None


def _variables(source, variable, names, roles, limit: int) -> None:
    """The flat model's variables from ``<Variable>``: their names into ``roles``, values into ``names``."""
    state_vars, obs_vars, action_vars = (variable.findall(t) for t in ("StateVar", "ObsVar", "ActionVar"))
    if len(state_vars) != 1 or len(obs_vars) != 1 or len(action_vars) != 1:
        raise _fail(source, variable, f"a factored model ({len(state_vars)} state, {len(obs_vars)} observation, "
                                      f"{len(action_vars)} action variables) is not supported; flat models only")
    sv, ov, av = state_vars[0], obs_vars[0], action_vars[0]
    roles.update(prev=sv.get("vnamePrev"), curr=sv.get("vnameCurr"), obs=ov.get("vname"), act=av.get("vname"))
    states = _values(source, sv, "s", limit)
    names.update({roles["prev"]: states, roles["curr"]: states, roles["obs"]: _values(source, ov, "o", limit),
                  roles["act"]: _values(source, av, "a", limit)})


def _start_section(source, parameter, names, roles, found, cell_limit: int) -> _Section | None:
    """The table a ``<Parameter>`` fills, from its section's ``<Var>`` and ``<Parent>`` (read already)."""
    cond = parameter.getparent()
    tag = cond.getparent().tag if cond.getparent() is not None else None
    if tag not in _SECTIONS or cond.tag != _SECTIONS[tag]:
        return None
    if not roles:
        raise _fail(source, cond, f"<{tag}> before <Variable>")
    if parameter.get("type", "TBL") != "TBL":
        raise _fail(source, cond, "only TBL parameters are supported")
    var = (cond.findtext("Var") or "").strip()
    parents = [p for p in (cond.findtext("Parent") or "").split() if p != "null"]
    prev, curr, obs, act = (roles[k] for k in ("prev", "curr", "obs", "act"))
    S, Z, A = len(names[prev]), len(names[obs]), len(names[act])
    if tag == "InitialStateBelief":
        if var not in (prev, curr) or parents:
            raise _fail(source, cond, f"the initial belief must be P({prev})")
        axes, shape = {var: 0}, (S,)
    elif tag == "StateTransitionFunction":
        if var != curr or sorted(parents) != sorted([prev, act]):
            raise _fail(source, cond, f"transition must be P({curr} | {prev}, {act})")
        axes, shape = {act: 0, prev: 1, curr: 2}, (A, S, S)
    elif tag == "ObsFunction":
        if var != obs or sorted(parents) != sorted([curr, act]):
            raise _fail(source, cond, f"observation must be P({obs} | {curr}, {act})")
        axes, shape = {act: 0, curr: 1, obs: 2}, (A, S, Z)
    else:
        if sorted(parents) != sorted([prev, act]):
            raise _fail(source, cond, f"reward must be R({prev}, {act})")
        axes, shape = {act: 0, prev: 1}, (A, S)
        # The model holds the reward dense, A x S numbers, whatever the file says: its rows (as aplan writes
        # them, a 9-part chain's 5,041,646 non-zero rewards) are bounded by that, not by the spread limit.
        cell_limit = max(cell_limit, A * S)
    order = parents + [var] if tag != "RewardFunction" else parents
    index = {v: {n: i for i, n in enumerate(names[v])} for v in order}
    found[tag] = _Section(source, cond, order, axes, shape, index, cell_limit)
    return found[tag]


def _token(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "x"


def _tokens(names) -> list[str]:
    out, used = [], set()
    for name in names:
        base = token = _token(name)
        k = 1
        while token in used:
            k += 1
            token = f"{base}_{k}"
        used.add(token)
        out.append(token)
    return out


def _num(x: float) -> str:
    """Fixed-point text (APPL's parser does not read scientific notation), the shortest that reads back as
    the same float: files round-trip exactly."""
    return np.format_float_positional(float(x), unique=True, trim="-")


def _numbers(values: np.ndarray) -> np.ndarray:
    """``_num`` of each value, formatting each distinct value once (a model has few distinct probabilities)."""
    distinct, inverse = np.unique(values, return_inverse=True)
    return np.array([_num(v) for v in distinct], dtype=object)[inverse.ravel()]


def _entries(rows, cols, values, prefix, row_names, col_names, tag="ProbTable"):
    """The ``<Entry>`` lines of the non-zero entries ``(rows, cols, values)``, in row-major order."""
    texts = _numbers(values)
    for r, c, v in zip(rows.tolist(), cols.tolist(), texts):
        yield f"<Entry><Instance>{prefix}{row_names[r]} {col_names[c]}</Instance><{tag}>{v}</{tag}></Entry>\n"


def _is_identity(table) -> bool:
    S = table.shape[0]
    table = table.tocsr()
    return (table.shape == (S, S) and table.nnz == S and np.array_equal(table.indices, np.arange(S))
            and np.array_equal(table.indptr, np.arange(S + 1)) and bool(np.all(table.data == 1)))


def pomdpx_chunks(model: POMDP):
    """The POMDPX document of ``model`` in pieces of text, streamed from the sparse tables: one ``<Entry>``
    per non-zero entry, ``identity`` for an action that leaves the state as it is, ``*`` for the action when
    the observation table does not depend on it. Names become ``ValueEnum`` tokens.
    Memory: O(S) beyond the model (one table's entries at a time); time O(nnz)."""
    S, A, Z = _tokens(model.states), _tokens(model.actions), _tokens(model.observations)
    yield ('<?xml version="1.0" encoding="ISO-8859-1"?>\n'
           f'<pomdpx version="0.1" id="{_token(model.name)}">\n'
           f"<Description>{_escape(model.name, quote=False)}</Description>\n"
           f"<Discount>{_num(model.discount)}</Discount>\n"
           "<Variable>\n"
           f'<StateVar vnamePrev="state_0" vnameCurr="state_1" fullyObs="false"><ValueEnum>{" ".join(S)}'
           "</ValueEnum></StateVar>\n"
           f'<ObsVar vname="obs"><ValueEnum>{" ".join(Z)}</ValueEnum></ObsVar>\n'
           f'<ActionVar vname="action"><ValueEnum>{" ".join(A)}</ValueEnum></ActionVar>\n'
           '<RewardVar vname="reward"/>\n</Variable>\n')

    def section(tag, var, parents, child="CondProb"):
        return (f"<{tag}><{child}><Var>{var}</Var><Parent>{parents}</Parent><Parameter type=\"TBL\">\n",
                f"</Parameter></{child}></{tag}>\n")

    start, end = section("InitialStateBelief", "state_0", "null")
    yield start
    nonzero = np.flatnonzero(model.initial)
    yield from (f"<Entry><Instance>{S[s]}</Instance><ProbTable>{v}</ProbTable></Entry>\n"
                for s, v in zip(nonzero.tolist(), _numbers(model.initial[nonzero])))
    yield end
    start, end = section("StateTransitionFunction", "state_1", "action state_0")
    yield start
    for a, table in enumerate(model.transition):
        if _is_identity(table):
            yield f"<Entry><Instance>{A[a]} - -</Instance><ProbTable>identity</ProbTable></Entry>\n"
            continue
        coo = _sorted_coo(table)
        yield from _entries(coo.row, coo.col, coo.data, f"{A[a]} ", S, S)
    yield end
    start, end = section("ObsFunction", "obs", "action state_1")
    yield start
    first = model.observation[0]
    same = all(o is first or (o != first).nnz == 0 for o in model.observation[1:])
    for a, table in enumerate(model.observation[:1] if same else model.observation):
        coo = _sorted_coo(table)
        yield from _entries(coo.row, coo.col, coo.data, f"{'*' if same else A[a]} ", S, Z)
    yield end
    start, end = section("RewardFunction", "reward", "action state_0", child="Func")
    yield start
    for a in range(model.n_actions):
        row = model.reward[a]
        if np.any(row):  # a whole row at once: no reliance on how a reader resolves overlapping entries
            yield (f"<Entry><Instance>{A[a]} -</Instance><ValueTable>{' '.join(_numbers(row))}</ValueTable>"
                   "</Entry>\n")
    yield end
    yield "</pomdpx>\n"


def _sorted_coo(table):
    """The entries of a CSR table in row-major order, columns increasing within a row."""
    table = table.tocsr()
    if not table.has_sorted_indices:
        table = table.sorted_indices()
    return table.tocoo()


def pomdpx_text(model: POMDP) -> str:
    """The POMDPX document of ``model`` as one string (:func:`pomdpx_chunks`; for small models)."""
    return "".join(pomdpx_chunks(model))


def write_pomdpx(model: POMDP, path: str | Path) -> None:
    """Write ``model`` as POMDPX (atomically), streamed from its sparse tables: memory O(S) beyond the model.

    ISO-8859-1, as the header says; characters outside it (in the description) become character references.
    """
    with open_atomic(path) as handle:
        batch = []
        for chunk in pomdpx_chunks(model):
            batch.append(chunk)
            if len(batch) >= 4096:
                handle.write("".join(batch).encode("latin-1", "xmlcharrefreplace"))
                batch.clear()
        handle.write("".join(batch).encode("latin-1", "xmlcharrefreplace"))
