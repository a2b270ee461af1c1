"""Pictures of a plan: the AND/OR graph, the assembly state graph and the intention graph, as PNG files.

Each graph is drawn by level (a layered drawing) with matplotlib from its ``to_networkx()`` view, on a
``Figure`` of its own (no pyplot, no screen, no change to the process's backend: this also runs inside
FreeCAD's GUI), and written atomically:

- AND/OR graph (Fig. 1 of the paper): subassemblies by number of parts, the complete product on top; each
  operation is a small dot joining its parent to its two children;
- assembly state graph (Fig. 2): states by number of subassemblies, the finished product on top;
- intention graph (Fig. 3): intentions by the steps left, the final intention on top, each edge one step.

Within a level the nodes are ordered to cut edge crossings (:func:`order_layers`, the barycentre
heuristic of Sugiyama et al. 1981), and each level is named on the left. A graph of more than ``limit``
nodes, or with a level wider than :data:`MAX_LEVEL_WIDTH`, would be a grey tangle: it is *summarised* instead,
as its node counts per level (bars, with a note saying so). The intention graph's counts come from path
counts over the state graph (:func:`~planner.assembly.intentions.paths_to_final`), without enumerating it.

Cost: a drawing is linear in nodes and edges per sweep (:data:`SWEEPS` sweeps, sorting each level); a
summary is linear in the graph (or in the state graph's edges for the intentions).
"""
from __future__ import annotations

from collections import defaultdict
from collections.abc import Hashable, Iterable
from pathlib import Path

from ..files import save_figure
from .intentions import intention_graph, paths_to_final
from .plan import Plan

__all__ = ["DEFAULT_DRAW_LIMIT", "MAX_LEVEL_WIDTH", "count_crossings", "draw_andor", "draw_intentions",
           "draw_plan", "draw_states", "intentions_per_level", "needs_summary", "order_layers"]

DEFAULT_DRAW_LIMIT = 160  # nodes drawn one by one; larger graphs are summarised (counts per level)
MAX_LEVEL_WIDTH = 40      # nodes side by side in a level that stay legible in a picture
SWEEPS = 8                # barycentre sweeps (down and up alternately); the best order seen is kept
DPI = 110


def order_layers(layer: dict[Hashable, int], edges: Iterable[tuple[Hashable, Hashable]]) -> dict[int, list]:
    """An order of the nodes within each level that cuts edge crossings: the barycentre heuristic.

    ``layer`` maps each node to its level (0 on top); ``edges`` join nodes of different levels. Starting
    from the nodes sorted, sweeps alternately downwards and upwards sort each level by the mean position of
    its neighbours in the levels already placed (nodes without such neighbours keep their place; ties keep
    the current order), and the order with the fewest crossings (:func:`count_crossings`) is returned,
    level -> nodes left to right. A tree drawn from its root comes out without crossings.
    Cost: O(SWEEPS * (E + V log V)) plus the crossing counts.
    """
    edges = [(u, v) for u, v in edges if layer[u] != layer[v]]
    neighbours: dict[Hashable, list] = defaultdict(list)
    for u, v in edges:
        neighbours[u].append(v)
        neighbours[v].append(u)
    levels = sorted(set(layer.values()))
    order = {k: _sorted([n for n in layer if layer[n] == k]) for k in levels}
    best, fewest = {k: list(v) for k, v in order.items()}, count_crossings(order, layer, edges)
    for sweep in range(SWEEPS):
        downwards = sweep % 2 == 0
        for k in (levels[1:] if downwards else levels[-2::-1]):
            position = {n: i for level in order.values() for i, n in enumerate(level)}
            placed = (lambda m: layer[m] < k) if downwards else (lambda m: layer[m] > k)  # noqa: B023

            def key(item):
                i, n = item
                near = [position[m] for m in neighbours[n] if placed(m)]  # noqa: B023
                return sum(near) / len(near) if near else i

            order[k] = [n for _, n in sorted(enumerate(order[k]), key=key)]
        crossings = count_crossings(order, layer, edges)
        if crossings < fewest:
            best, fewest = {k: list(v) for k, v in order.items()}, crossings
    return best


def _sorted(nodes: list) -> list:
    try:
        return sorted(nodes)
    except TypeError:  # nodes of different kinds
        return sorted(nodes, key=repr)


def count_crossings(order: dict[int, list], layer: dict[Hashable, int],
                    edges: Iterable[tuple[Hashable, Hashable]]) -> int:
    """The pairs of edges that cross when each level is drawn in ``order`` (straight edges between levels at
    unit spacing, nodes centred in their level). Edges spanning the same pair of levels cross when their ends
    are in opposite orders; edges of different level pairs are not counted. Cost: O(E^2) per level pair."""
    x = {}
    for level in order.values():
        for i, n in enumerate(level):
            x[n] = i - (len(level) - 1) / 2
    groups: dict[tuple[int, int], list[tuple[float, float]]] = defaultdict(list)
    for u, v in edges:
        if layer[u] > layer[v]:
            u, v = v, u
        groups[layer[u], layer[v]].append((x[u], x[v]))
    crossings = 0
    for pairs in groups.values():
        for i, (a0, a1) in enumerate(pairs):
            for b0, b1 in pairs[i + 1:]:
                crossings += (a0 - b0) * (a1 - b1) < 0
    return crossings


def _draw(graph, layer: dict, labels: dict, names: dict[int, str], path: str | Path, title: str,
          small: set = frozenset()) -> str:
    """The layered drawing of ``graph``: levels top to bottom, ``names[level]`` on the left."""
    import networkx as nx
    from matplotlib.figure import Figure  # no pyplot: its backend and figures are process-wide state

    order = order_layers(layer, graph.edges)
    position = {n: (i - (len(nodes) - 1) / 2, -k) for k, nodes in order.items() for i, n in enumerate(nodes)}
    widest = max(len(nodes) for nodes in order.values())
    fig = Figure(figsize=(min(max(12.0, 3 + 0.55 * widest), 30), 1.5 + 0.9 * len(order)), layout="constrained")
    ax = fig.subplots()
    big = [n for n in graph.nodes if n not in small]
    nx.draw_networkx_edges(graph, position, ax=ax, arrows=False, edge_color="#8a8a8a", width=0.8)
    nx.draw_networkx_nodes(graph, position, nodelist=big, ax=ax, node_size=420, node_color="#dbe8f5",
                           edgecolors="#1f4e79", linewidths=1.0)
    if small:
        nx.draw_networkx_nodes(graph, position, nodelist=list(small), ax=ax, node_size=40, node_color="#f5b400")
    nx.draw_networkx_labels(graph, position, labels, ax=ax, font_size=7, font_color="#10253f")
    left = -(widest - 1) / 2 - 0.8
    for k, name in names.items():
        if k in order:
            ax.text(left, -k, name, ha="right", va="center", fontsize=8, color="#555555")
    ax.set_xlim(left - 0.2 - 0.09 * max(len(n) for n in names.values()), (widest - 1) / 2 + 0.6)
    ax.set_title(title, fontsize=11)
    ax.axis("off")
    return save_figure(fig, path, dpi=DPI)


def _summary(counts: list[tuple[str, int]], path: str | Path, title: str, what: str, note: str,
             colours: list[str] | None = None) -> str:
    """Bars of the node counts per level (top level first), each labelled with its count, and ``note``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12.0, 1.8 + 0.32 * len(counts)), layout="constrained")
    ax = fig.subplots()
    names = [name for name, _ in counts]
    values = [count for _, count in counts]
    ax.barh(range(len(counts)), values, color=colours or "#1f4e79")
    ax.set_yticks(range(len(counts)), names, fontsize=8)
    ax.invert_yaxis()  # the top level on top, as in the drawings
    if max(values) > 100 * max(1, min(v for v in values if v > 0)):
        ax.set_xscale("log")
    for k, value in enumerate(values):
        ax.annotate(f"{value:,}", (value, k), xytext=(4, 0), textcoords="offset points", va="center", fontsize=8)
    ax.set_xlabel(f"{what} per level" + (" (log scale)" if ax.get_xscale() == "log" else ""))
    ax.set_title(title + "\n" + note, fontsize=10)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    return save_figure(fig, path, dpi=DPI)


def needs_summary(nodes: int, layer: dict, limit: int) -> bool:
    """True when a graph of ``nodes`` nodes in levels ``layer`` (node -> level) is summarised rather than drawn:
    more than ``limit`` nodes, or more than :data:`MAX_LEVEL_WIDTH` in a level."""
    widths = defaultdict(int)
    for k in layer.values():
        widths[k] += 1
    return nodes > limit or max(widths.values(), default=0) > MAX_LEVEL_WIDTH


def _note(nodes: int, limit: int) -> str:
    return (f"summarised: {nodes:,} nodes are too many to draw one by one (more than {limit:,}, or more than "
            f"{MAX_LEVEL_WIDTH} in a level)")


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word[:-1]}ies" if word.endswith("y") else f"{n} {word}s"


def draw_andor(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the AND/OR graph of ``plan`` into the PNG file ``path`` (summarised past ``limit`` nodes)."""
    andor = plan.andor
    n = len(andor.parts)
    size = {i: len(andor.parts_of(i)) for i in range(len(andor.subassemblies))}
    title = f"AND/OR graph: {len(andor.subassemblies)} subassemblies, {len(andor.operations)} operations"
    nodes = len(andor.subassemblies) + len(andor.operations)
    layer = {("S", i): 2 * (n - s) for i, s in size.items()}
    layer.update({("O", j): 2 * (n - size[op.parent]) + 1 for j, op in enumerate(andor.operations)})
    if needs_summary(nodes, layer, limit):
        per = defaultdict(lambda: [0, 0])
        for s in size.values():
            per[s][0] += 1
        for op in andor.operations:
            per[size[op.parent]][1] += 1
        counts = []
        for s in sorted(per, reverse=True):
            counts.append((f"{_plural(s, 'part')}: subassemblies", per[s][0]))
            if per[s][1]:
                counts.append((f"{_plural(s, 'part')}: operations taking them apart", per[s][1]))
        colours = ["#f5b400" if name.endswith("apart") else "#1f4e79" for name, _ in counts]  # as in the drawing
        return _summary(counts, path, title, "nodes", _note(nodes, limit), colours)
    graph = andor.to_networkx()
    labels = {("S", i): ",".join(sorted(andor.parts_of(i))) if s <= 2 else f"{s} parts" for i, s in size.items()}
    names = {2 * (n - s): _plural(s, "part") for s in set(size.values())}
    return _draw(graph, layer, labels, names, path, title, {node for node in graph.nodes if node[0] == "O"})


def draw_states(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the assembly state graph of ``plan`` (Alg. 1) into ``path`` (summarised past ``limit`` nodes)."""
    states = plan.states
    layer = {s: len(states.subassemblies_of(s)) for s in range(states.n_states)}
    title = f"Assembly state graph: {states.n_states} states, {states.n_edges} edges (0: finished product)"
    if needs_summary(states.n_states, layer, limit):
        per = defaultdict(int)
        for k in layer.values():
            per[k] += 1
        return _summary([(f"{_plural(k, 'subassembly')}", per[k]) for k in sorted(per)], path, title, "states",
                        _note(states.n_states, limit))
    names = {k: _plural(k, "block") for k in set(layer.values())}
    return _draw(states.to_networkx(), layer, {s: str(s) for s in layer}, names, path, title)


def intentions_per_level(plan: Plan) -> list[int]:
    """The number of intentions with 0, 1, 2, ... steps left, without enumerating them: every path from a
    state with ``k`` blocks to the finished product takes ``k - 1`` steps, and the paths from each state are
    counted by :func:`~planner.assembly.intentions.paths_to_final`. Cost: O(state edges)."""
    return [sum(int(c) for c in level) for level in paths_to_final(plan.states)]


def draw_intentions(plan: Plan, path: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> str:
    """Draw the intention graph of ``plan`` (Alg. 2, a tree) into ``path``; past ``limit`` intentions, its
    counts per level from path counts (never enumerated)."""
    counts = intentions_per_level(plan)
    total = sum(counts)
    title = f"Intention graph: {total:,} intentions (0: final intention)"
    if total > limit or max(counts) > MAX_LEVEL_WIDTH:
        return _summary([(f"{_plural(k - 1, 'step')} left", c) for k, c in enumerate(counts, start=1)], path,
                        title, "intentions", _note(total, limit) + "; counted from paths, not enumerated")
    graph_data = intention_graph(plan.states, limit)
    graph = graph_data.to_networkx()
    layer = {i: len(graph_data.path(i)) - 1 for i in graph.nodes}
    names = {k: _plural(k, "step") + " left" for k in set(layer.values())}
    return _draw(graph, layer, {i: str(i) for i in graph.nodes}, names, path, title)


def draw_plan(plan: Plan, folder: str | Path, limit: int = DEFAULT_DRAW_LIMIT) -> dict[str, str]:
    """The three pictures in ``folder`` (``andor.png``, ``states.png``, ``intentions.png``); name -> path.
    Graphs above ``limit`` nodes are summarised (counts per level) rather than drawn node by node."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    return {name: draw(plan, Path(folder) / f"{name}.png", limit)
            for name, draw in (("andor", draw_andor), ("states", draw_states), ("intentions", draw_intentions))}
