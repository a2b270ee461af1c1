"""POMDPX files (APPL's XML format for SARSOP's ``pomdpsol``): read flat models, write sparse ones.

Only *flat* models are read: one state variable (``vnamePrev``/``vnameCurr``), one observation variable, one
action variable and one reward variable, with ``TBL`` parameters. Instances may use ``*`` (every value,
same probability) and ``-`` (every value, listed in the table) and tables may be ``identity`` or
``uniform``, as APPL defines them. The writer lists only non-zero entries and uses ``*`` for the action
when the observation table does not depend on it, so a model of the pen takes kilobytes.

The XML parser never expands entities, loads DTDs or touches the network.
"""
from __future__ import annotations

import gzip
import itertools
import re
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from lxml import etree

from ...errors import PlannerError
from ...files import write_atomic
from ..pomdp import POMDP, ModelError

__all__ = ["PomdpxError", "read_pomdpx", "write_pomdpx", "pomdpx_text", "safe_parser"]


class PomdpxError(PlannerError):
    """A POMDPX file is malformed or not a flat POMDP (the message names the line)."""


def safe_parser() -> etree.XMLParser:
    """An XML parser with entity expansion, DTD loading and network access disabled."""
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False,
                           remove_comments=True)


def _fail(source: str, element, problem: str) -> PomdpxError:
    line = f" line {element.sourceline}" if element is not None and element.sourceline else ""
    return PomdpxError(f"{source}:{line}: {problem}")


def _values(source, var, prefix):
    enum = var.find("ValueEnum")
    if enum is not None and enum.text and enum.text.split():
        return enum.text.split()
    count = var.find("NumValues")
    if count is None or not (count.text or "").strip().isdigit():
        raise _fail(source, var, f"<{var.tag}> needs <NumValues> or <ValueEnum>")
    return [f"{prefix}{i}" for i in range(int(count.text))]


def _read_tables(source, cond, order, sizes, index):
    """Fill a dense array with axes ``order`` (variable names) from a ``<CondProb>``/``<Func>`` element."""
    out = np.zeros([sizes[v] for v in order])
    param = cond.find("Parameter")
    if param is None or param.get("type", "TBL") != "TBL":
        raise _fail(source, cond, "only TBL parameters are supported")
    for entry in param.findall("Entry"):
        inst = entry.find("Instance")
        table = entry.find("ProbTable")
        if table is None:
            table = entry.find("ValueTable")
        if inst is None or table is None or inst.text is None or table.text is None:
            raise _fail(source, entry, "an <Entry> needs an <Instance> and a <ProbTable> or <ValueTable>")
        tokens = inst.text.split()
        if len(tokens) != len(order):
            raise _fail(source, inst, f"instance {inst.text.strip()!r} has {len(tokens)} values, expected "
                                      f"{len(order)} ({' '.join(order)})")
        axes = []
        for tok, var in zip(tokens, order):
            if tok in ("*", "-"):
                axes.append(tok)
            elif tok in index[var]:
                axes.append(index[var][tok])
            else:
                raise _fail(source, inst, f"unknown value {tok!r} of variable {var!r}")
        dash = [sizes[v] for tok, v in zip(tokens, order) if tok == "-"]
        text = table.text.split()
        if text == ["identity"]:
            values = np.eye(*dash[-2:]) if len(dash) >= 2 else None
            if values is None:
                raise _fail(source, table, "'identity' needs two '-' in the instance")
            values = np.broadcast_to(values, dash).copy()
        elif text == ["uniform"]:
            values = np.full(dash, 1.0 / dash[-1]) if dash else None
            if values is None:
                raise _fail(source, table, "'uniform' needs a '-' in the instance")
        else:
            try:
                flat = np.array([float(x) for x in text])
            except ValueError:
                raise _fail(source, table, f"not a list of numbers: {table.text.strip()[:60]!r}") from None
            expected = int(np.prod(dash)) if dash else 1
            if flat.size != expected:
                raise _fail(source, table, f"{flat.size} values for instance {inst.text.strip()!r}, expected {expected}")
            values = flat.reshape(dash) if dash else flat[0]
        ranges = [range(sizes[v]) if tok in ("*", "-") else [ax] for ax, tok, v in zip(axes, tokens, order)]
        dash_positions = [k for k, tok in enumerate(tokens) if tok == "-"]
        for point in itertools.product(*ranges):
            out[point] = values[tuple(point[k] for k in dash_positions)] if dash_positions else values
    return out


def read_pomdpx(path: str | Path) -> POMDP:
    """Read a flat POMDPX file (optionally gzip-compressed, ``.gz``) into a :class:`POMDP`."""
    source = str(path)
    try:
        raw = gzip.open(path).read() if source.endswith(".gz") else Path(path).read_bytes()
    except (OSError, EOFError) as exc:
        raise PomdpxError(f"{source}: cannot read the file: {exc}") from None
    try:
        root = etree.fromstring(raw, safe_parser())
    except etree.XMLSyntaxError as exc:
        raise PomdpxError(f"{source}: line {exc.lineno}: malformed XML: {exc.msg}") from None
    if root.tag != "pomdpx":
        raise _fail(source, root, f"the root element is <{root.tag}>, not <pomdpx>")
    variable = root.find("Variable")
    if variable is None:
        raise _fail(source, root, "no <Variable> element")
    state_vars, obs_vars, action_vars = (variable.findall(t) for t in ("StateVar", "ObsVar", "ActionVar"))
    if len(state_vars) != 1 or len(obs_vars) != 1 or len(action_vars) != 1:
        raise _fail(source, variable, f"a factored model ({len(state_vars)} state, {len(obs_vars)} observation, "
                                      f"{len(action_vars)} action variables) is not supported; flat models only")
    sv, ov, av = state_vars[0], obs_vars[0], action_vars[0]
    prev, curr, obs, act = sv.get("vnamePrev"), sv.get("vnameCurr"), ov.get("vname"), av.get("vname")
    states, observations, actions = _values(source, sv, "s"), _values(source, ov, "o"), _values(source, av, "a")
    sizes = {prev: len(states), curr: len(states), obs: len(observations), act: len(actions)}
    index = {prev: {n: i for i, n in enumerate(states)}, curr: {n: i for i, n in enumerate(states)},
             obs: {n: i for i, n in enumerate(observations)}, act: {n: i for i, n in enumerate(actions)}}

    def section(tag, child="CondProb"):
        node = root.find(tag)
        cond = node.find(child) if node is not None else None
        if cond is None:
            raise _fail(source, node if node is not None else root, f"no <{tag}><{child}>")
        var = (cond.findtext("Var") or "").strip()
        parents = (cond.findtext("Parent") or "").split()
        return cond, var, [p for p in parents if p != "null"]

    cond, var, parents = section("InitialStateBelief")
    initial = _read_tables(source, cond, parents + [var], sizes, index).reshape(-1)
    cond, var, parents = section("StateTransitionFunction")
    if var != curr or sorted(parents) != sorted([prev, act]):
        raise _fail(source, cond, f"transition must be P({curr} | {prev}, {act})")
    T = np.moveaxis(_read_tables(source, cond, parents + [var], sizes, index), parents.index(act), 0)
    cond, var, parents = section("ObsFunction")
    if var != obs or sorted(parents) != sorted([curr, act]):
        raise _fail(source, cond, f"observation must be P({obs} | {curr}, {act})")
    O = np.moveaxis(_read_tables(source, cond, parents + [var], sizes, index), parents.index(act), 0)
    cond, var, parents = section("RewardFunction", "Func")
    if sorted(parents) != sorted([prev, act]):
        raise _fail(source, cond, f"reward must be R({prev}, {act})")
    R = _read_tables(source, cond, parents, sizes, index)
    R = R if parents[0] == act else R.T
    try:
        discount = float(root.findtext("Discount"))
    except (TypeError, ValueError):
        raise _fail(source, root, "missing or invalid <Discount>") from None
    try:
        return POMDP(tuple(states), tuple(actions), tuple(observations),
                     tuple(sp.csr_matrix(t) for t in T), tuple(sp.csr_matrix(o) for o in O), R, initial, discount,
                     name=(root.findtext("Description") or root.get("id") or "pomdpx").strip())
    except ModelError as exc:
        raise PomdpxError(f"{source}: {exc}") from None


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
    """Fixed-point text: APPL's parser does not read scientific notation."""
    return f"{float(x):.15f}".rstrip("0").rstrip(".") or "0"


def pomdpx_text(model: POMDP) -> str:
    """The POMDPX document of ``model``: sparse entries, names as ``ValueEnum`` tokens."""
    S, A, Z = _tokens(model.states), _tokens(model.actions), _tokens(model.observations)
    root = etree.Element("pomdpx", version="0.1", id=_token(model.name))
    etree.SubElement(root, "Description").text = model.name
    etree.SubElement(root, "Discount").text = _num(model.discount)
    variable = etree.SubElement(root, "Variable")
    sv = etree.SubElement(variable, "StateVar", vnamePrev="state_0", vnameCurr="state_1", fullyObs="false")
    etree.SubElement(sv, "ValueEnum").text = " ".join(S)
    ov = etree.SubElement(variable, "ObsVar", vname="obs")
    etree.SubElement(ov, "ValueEnum").text = " ".join(Z)
    av = etree.SubElement(variable, "ActionVar", vname="action")
    etree.SubElement(av, "ValueEnum").text = " ".join(A)
    etree.SubElement(variable, "RewardVar", vname="reward")

    def cond(parent_tag, var, parents, child="CondProb"):
        node = etree.SubElement(root, parent_tag)
        c = etree.SubElement(node, child)
        etree.SubElement(c, "Var").text = var
        etree.SubElement(c, "Parent").text = parents
        return etree.SubElement(c, "Parameter", type="TBL")

    def entry(param, instance, values, tag="ProbTable"):
        e = etree.SubElement(param, "Entry")
        etree.SubElement(e, "Instance").text = instance
        etree.SubElement(e, tag).text = values

    param = cond("InitialStateBelief", "state_0", "null")
    for s in np.flatnonzero(model.initial):
        entry(param, S[s], _num(model.initial[s]))
    param = cond("StateTransitionFunction", "state_1", "action state_0")
    for a, table in enumerate(model.transition):
        coo = table.tocoo()
        for s, t, p in sorted(zip(coo.row, coo.col, coo.data)):
            entry(param, f"{A[a]} {S[s]} {S[t]}", _num(p))
    param = cond("ObsFunction", "obs", "action state_1")
    same = all((o != model.observation[0]).nnz == 0 for o in model.observation[1:])
    for a, table in enumerate(model.observation[:1] if same else model.observation):
        coo = table.tocoo()
        for s, z, p in sorted(zip(coo.row, coo.col, coo.data)):
            entry(param, f"{'*' if same else A[a]} {S[s]} {Z[z]}", _num(p))
    param = cond("RewardFunction", "reward", "action state_0", child="Func")
    for a in range(model.n_actions):
        row = model.reward[a]
        if np.any(row):  # a whole row at once: no reliance on how a reader resolves overlapping entries
            entry(param, f"{A[a]} -", " ".join(_num(v) for v in row), "ValueTable")
    return etree.tostring(root, pretty_print=True, xml_declaration=True, encoding="ISO-8859-1").decode("latin-1")


def write_pomdpx(model: POMDP, path: str | Path) -> None:
    """Write ``model`` as POMDPX (atomically)."""
    write_atomic(path, pomdpx_text(model))
