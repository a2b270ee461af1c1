"""Pictures of a plan: the AND/OR graph, the assembly state graph and the intention graph, as PNG files.

Each graph is drawn in layers with matplotlib from its ``to_networkx()`` view, on a ``Figure`` of its own (no
pyplot, no screen, no change to the process's backend: this also runs inside FreeCAD's GUI), and written
atomically:

- AND/OR graph (Fig. 1 of the paper): subassemblies by number of parts, the complete product on top; each
  operation is a small dot joining its parent to its two children;
- assembly state graph (Fig. 2): states by number of subassemblies, the finished product on top;
- intention graph (Fig. 3): intentions by length, the final intention on top, each edge one step.

Cost: linear in the number of nodes and edges; graphs larger than ``limit`` nodes are not drawn
(:class:`~planner.errors.LimitExceededError`), as a picture of them would say nothing.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import LimitExceededError
from ..files import save_figure
from .intentions import intention_graph
from .plan import Plan

__all__ = ["draw_andor", "draw_states", "draw_intentions", "draw_plan", "DEFAULT_DRAW_LIMIT"]

DEFAULT_DRAW_LIMIT = 400


def _check(what: str, count: int, limit: int) -> None:
    if count > limit:
        raise LimitExceededError(what, count, limit, "Pictures are drawn for small products only; use the "
                                 "statistics and `aplan intentions` for large ones.")


def _save(graph, layer: dict, labels: dict, path: str | Path, title: str, small: set = frozenset()) -> str:
    import networkx as nx
    from matplotlib.figure import Figure  # no pyplot: its backend and figures are process-wide state

    for node in graph.nodes:
        graph.nodes[node]["layer"] = layer[node]
    position = {node: (x, -y) for node, (x, y) in
                nx.multipartite_layout(graph, subset_key="layer", align="horizontal").items()}  # layer 0 on top
    widest = max(sum(1 for v in layer.values() if v == k) for k in set(layer.values()))
    fig = Figure(figsize=(min(4 + 0.9 * widest, 24), 2 + 1.2 * len(set(layer.values()))))
    ax = fig.subplots()
    big = [n for n in graph.nodes if n not in small]
    nx.draw_networkx_edges(graph, position, ax=ax, arrows=False, edge_color="#7a7a7a", width=0.8)
    nx.draw_networkx_nodes(graph, position, nodelist=big, ax=ax, node_size=260, node_color="#1f4e79")
    if small:
        nx.draw_networkx_nodes(graph, position, nodelist=list(small), ax=ax, node_size=30, node_color="#f5b400")
    nx.draw_networkx_labels(graph, position, labels, ax=ax, font_size=6,
                            verticalalignment="bottom", bbox={"facecolor": "white", "edgecolor": "none",
                                                              "alpha": 0.7, "pad": 0.5})
    ax.set_title(title, fontsize=10)
    ax.axis("off")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def draw_andor(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the AND/OR graph of ``plan`` into the PNG file ``path``; returns the path."""
    andor = plan.andor
    _check("AND/OR graph nodes", len(andor.subassemblies) + len(andor.operations), limit)
    graph = andor.to_networkx()
    n = len(andor.parts)
    layer, labels = {}, {}
    for node in graph.nodes:
        kind, i = node
        if kind == "S":
            size = len(andor.parts_of(i))
            layer[node] = 2 * (n - size)
            labels[node] = ",".join(sorted(andor.parts_of(i))) if size <= 3 else f"{size} parts"
        else:
            layer[node] = 2 * (n - len(andor.parts_of(andor.operations[i].parent))) + 1
    title = f"AND/OR graph: {len(andor.subassemblies)} subassemblies, {len(andor.operations)} operations"
    return _save(graph, layer, labels, path, title, {node for node in graph.nodes if node[0] == "O"})


def draw_states(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the assembly state graph of ``plan`` (Alg. 1) into ``path``."""
    states = plan.states
    _check("assembly states", states.n_states, limit)
    graph = states.to_networkx()
    layer = {s: len(states.subassemblies_of(s)) for s in graph.nodes}
    labels = {s: str(s) for s in graph.nodes}
    return _save(graph, layer, labels, path, f"Assembly state graph: {states.n_states} states, "
                 f"{states.n_edges} edges (0: finished product)")


def draw_intentions(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the intention graph of ``plan`` (Alg. 2, a tree) into ``path``."""
    graph_data = intention_graph(plan.states, limit)
    _check("intentions", graph_data.n_intentions, limit)
    graph = graph_data.to_networkx()
    layer = {i: len(graph_data.path(i)) for i in graph.nodes}
    labels = {i: str(i) for i in graph.nodes}
    return _save(graph, layer, labels, path, f"Intention graph: {graph_data.n_intentions} intentions "
                 "(0: final intention)")


def draw_plan(plan: Plan, folder: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> dict[str, str]:
    """The three pictures in ``folder`` (``andor.png``, ``states.png``, ``intentions.png``).

    Returns name -> path, or name -> the reason it was not drawn (a graph above ``limit`` nodes).
    """
    Path(folder).mkdir(parents=True, exist_ok=True)
    out = {}
    for name, draw in (("andor", draw_andor), ("states", draw_states), ("intentions", draw_intentions)):
        try:
            out[name] = draw(plan, Path(folder) / f"{name}.png", limit)
        except LimitExceededError as exc:
            out[name] = str(exc)
    return out
