"""``aplan stats``, ``aplan intentions``, ``aplan fasteners`` and ``aplan synth``: the plan of a product (the
paper's Sec. III-B)."""
from __future__ import annotations

import argparse
import json
import logging
import os
import sys
from dataclasses import replace
from pathlib import Path

from .. import api
from ..assembly.guards import SizeLimits, default_memory_budget
from ..assembly.intentions import DEFAULT_INTENTION_LIMIT, intention_graph
from ..assembly.stats import STAT_KEYS, PlanStatistics
from ..defaults import SUBASSEMBLY_LIMIT
from ..errors import MemoryLimitError, PlannerError
from ..files import write_atomic
from ..product import product_to_dict, save_product
from ..product.synthetic import SYNTHETIC, synthetic_bytes, synthetic_contacts
from .geometry import contact_choice
from .options import (
    PRODUCT_HELP,
    add_contact_options,
    add_force,
    add_input_options,
    add_product_options,
    advice,
    contact_tolerances_from,
    explain,
    index,
    inputs_from,
    limits_from,
    positive,
    positive_length,
    product_from,
)

__all__ = ["add_commands"]

log = logging.getLogger(__name__)


# aplan stats: some figures were not computed (they would exceed a size limit); those printed are exact.
PARTIAL = 3


# The flat plan of a hierarchy is only counted for comparison: within these limits (a few seconds), else refused.
_FLAT_LIMITS = SizeLimits(SUBASSEMBLY_LIMIT, 2 ** 30)


def _print_designer(product) -> None:
    """The designer's directions and not-blocking marks, and the interlocked pairs the marks released."""
    from ..assembly.feasibility import released_interlocks
    from ..product.designer import designer_lines

    for line in designer_lines(product):
        print(f"  {line}")
    for pair in released_interlocks(product):
        print(f"  designer marks released the interlocked pair {pair.first} and {pair.second} (they blocked each "
              "other along every direction tried)")


def _stats(args: argparse.Namespace) -> int:
    # Fasteners and subassemblies chosen once (the product's own, or proposed), then planned as they are.
    product = product_from(args, args.product, contact_tolerances_from(args))
    if args.contact is not None:  # analysed again here: say what the analysis found, as aplan analyze does
        for warning in product.geometry.get("analysis", {}).get("warnings", []):
            log.warning("%s", warning)
    if args.level is None and len(api.levels_of(product)) > 1:
        if args.base_part:
            raise PlannerError("--base-part picks the first part of one workstation's sequences: add --level ID")
        return _level_stats(args, product)
    product = api.level_product(product, "designer", args.level)
    plan, stats = api.plan_statistics_of(product, args.technical, args.base_part, limits_from(args), partial=True)
    refused = stats.refused
    reason = f"{refused} {advice(refused, args)}".strip() if refused else None  # in full: the JSON's
    if args.json:
        data = stats.as_dict()
        if refused:
            data["not_computed"] = {"figures": list(stats.not_computed), "reason": reason}
        designer = product.geometry.get("designer")
        if designer:
            data["designer"] = {**designer, **product.geometry.get("analysis", {}).get("designer", {})}
        if stats.fasteners:
            data["fasteners"] = {"parts": stats.folded_parts, "groups": {
                g.id: {"parts": list(g.parts), "hosts": sorted(g.hosts), "tool": g.tool,
                       "install_operations": None if stats.installs is None else stats.installs[k]}
                for k, g in enumerate(stats.fasteners)}}
        print(json.dumps(data))
        return PARTIAL if refused else 0
    print(f"{product.name or str(args.product)} ({product.source})")
    choice = contact_choice(product.geometry.get("analysis", {})) if args.contact is not None else None
    if choice:
        print(f"  {choice}")
    values = stats.as_dict()
    for key in STAT_KEYS:
        value = values[key]
        shown = "not computed" if value is None else f"{value:.2f}" if isinstance(value, float) else f"{value:,}"
        print(f"  {key:<14}{shown:>22}")
    if stats.fasteners:
        _print_folded(stats)
    _print_designer(product)
    if refused:
        print(f"  not computed: {', '.join(stats.not_computed)}: {explain(refused, args)}")
        return PARTIAL
    if stats.base_part:
        print(f"  (only the sequences that start from the base part {stats.base_part!r}, whose first operation "
              "joins it, and their intentions)")
    print(f"  factored view: {stats.states:,} assembly states x {stats.sequences:,} sequences "
          f"instead of {stats.intentions:,} intentions")
    for k in plan.tags.unmatched:
        log.warning("operations[%d] tags an operation that is not in the AND/OR graph", k)
    return 0


def _level_stats(args: argparse.Namespace, product) -> int:
    """``aplan stats`` of a product planned as several workstations: each level, the total, and flat."""
    limits = limits_from(args)
    flat_limits = SizeLimits(min(limits.subassemblies, _FLAT_LIMITS.subassemblies),
                             min(limits.memory, _FLAT_LIMITS.memory))
    levels, flat = api.hierarchy_statistics_of(product, args.technical, limits, flat_limits=flat_limits)
    report = api.level_table(product, levels, flat)  # the figures, as the workbench's level_report gives them
    failed = [(level.id, error) for level, error in levels if not isinstance(error, PlanStatistics)]
    refused = [(level.id, stats.refused) for level, stats in levels
               if isinstance(stats, PlanStatistics) and stats.refused]
    total, flat_dict, flat_reason = report["total"], report["flat"], report.get("flat_not_computed")
    figures = {row["level"]: row for row in report["levels"]}
    if args.json:
        print(json.dumps(report))
        return 1 if failed else PARTIAL if refused else 0
    print(f"{product.name or str(args.product)} ({product.source}): {len(product.parts)} parts in {len(levels)} "
          f"levels (workstations), planned bottom-up")
    shown = lambda v: "-" if v is None else f"{v:,}"  # noqa: E731
    names = {"parts": "members", "subassemblies": "and_or_nodes", "operations": "and_arcs"}
    built = {level.id: sum(m not in product.part_ids for m in level.members) for level, _ in levels}
    rows = [(level.id, len(level.members), built[level.id], figures[level.id]) for level, _ in levels]
    rows.append(("total", total["parts"], sum(built.values()), total))
    if flat_dict is not None:
        rows.append(("flat", flat_dict["parts"], 0, flat_dict))
    keys = api.LEVEL_KEYS[1:]
    # Each column as wide as its widest figure (a product of the levels' sequence counts can be long).
    width = {k: 2 + max(len(names.get(k, k)), *(len(shown(d[k])) for *_, d in rows)) for k in keys}
    first = max(8, *(len(str(name)) + 1 for name, *_ in rows))
    print(f"  {'level':<{first}}{names['parts']:>9}{'built':>7}" + "".join(f"{names.get(k, k):>{width[k]}}" for k in keys))
    for name, members, count, d in rows:
        print(f"  {name:<{first}}{members:>9}{count:>7}" + "".join(f"{shown(d[k]):>{width[k]}}" for k in keys))
    print("  (built: members that are subassemblies built at another workstation; total: the sums over the levels, "
          "but parts: the product's, sequences: the product of the levels', each workstation following its own)")
    for level, stats in levels:
        print(f"  {level.id}: {', '.join(level.members)}")
    if flat_reason:
        flat_error = flat.refused if isinstance(flat, PlanStatistics) else flat
        same = [name for name, error in failed if isinstance(flat_error, PlannerError) and
                error.summary == flat_error.summary]  # said once, below
        shown = f"as level {same[0]} (below)" if same else \
            explain(flat_error, args, options=False) if isinstance(flat_error, PlannerError) else flat_reason
        print(f"  flat: not counted: {shown}")
    for name, error in refused:
        print(f"  {name}: not computed: {explain(error, args)}")
    for name, error in failed:
        print(f"aplan: error: level {name}: {explain(error, args)}", file=sys.stderr)
    return 1 if failed else PARTIAL if refused else 0


def _print_folded(stats) -> None:
    print(f"  fasteners folded: {stats.folded_parts} parts in {len(stats.fasteners)} groups (not counted in parts)")
    for k, group in enumerate(stats.fasteners):
        count = "not computed" if stats.installs is None else f"{stats.installs[k]:,}"
        tool = f", tool {group.tool}" if group.tool else ""
        parts = f"{len(group.parts)} part{'' if len(group.parts) == 1 else 's'}"
        hosts = ", ".join(sorted(group.hosts))
        print(f"    {group.id}: {parts} joining {hosts}{tool}; installed by {count} operations")


def _intentions(args: argparse.Namespace) -> int:
    limits = limits_from(args)
    product = api.level_product(product_from(args, args.product), "designer", args.level)
    plan = api.plan_of(product, args.technical, limits)
    graph = intention_graph(plan.states, limit=args.limit, base_part=api.base_part_of(plan, args.base_part),
                            max_bytes=limits.memory)
    for i in (graph.full_sequences() if args.full else range(graph.n_intentions)):
        states = [plan.states.describe(s) for s in graph.path(int(i))]
        if args.json:
            operations = [plan.andor.describe(o) for o in graph.operations(int(i))]
            print(json.dumps({"intention": int(i), "states": states, "operations": operations}))
        else:
            print(f"{int(i)}: " + " -> ".join(states))
    return 0


def _sequence(args: argparse.Namespace) -> int:
    """``aplan sequence``: one full assembly sequence step by step, as the workbench's "Plan in 3D" shows it."""
    level = args.level
    if args.session_log and level is None and args.subassemblies != "none":  # a level's log says which
        from ..runtime.log import read_log

        settings = read_log(args.session_log, inputs_from(args))[0].get("settings")
        level = settings.get("level") if isinstance(settings, dict) and isinstance(settings.get("level"), str) else None
    product = api.level_product(product_from(args, args.product), "designer", level)
    plan = api.plan_of(product, args.technical, limits_from(args))
    args.rank = args.rank or 0
    title = f"sequence {args.rank}"
    if args.session_log:
        operations, logged = api.sequence_from_log(args.session_log, plan, inputs_from(args))
        done = len(logged.operations)
        title = f"the sequence {args.session_log} recorded" + ("" if logged.complete else (
            f" ({done} operation{'s' if done != 1 else ''}, then the first way to finish)"))
        view = api.plan_in_3d(plan, operations, args.spacing, args.base_part)
    else:
        view = api.plan_in_3d(plan, args.rank, args.spacing, args.base_part)
    if args.json:
        print(json.dumps({"sequence": None if args.session_log else args.rank, "spacing": view.spacing, "steps": [
            {"operation": step.operation, "joins": step.description, "moving": sorted(step.moving),
             "fixed": sorted(step.fixed), "free_direction": step.direction.name,
             "vector": list(step.direction.vector), "offsets": {p: list(v) for p, v in view.offsets[k].items()}}
            for k, step in enumerate(view.steps)]}))
        return 0
    print(f"{plan.product.name or args.product}: {title}, {len(view.steps)} operations; the moving side goes in "
          "along the reverse of its free direction")
    for k, step in enumerate(view.steps, start=1):
        verb = "moves" if len(step.moving) == 1 else "move"
        print(f"  {k}. {step.description}: {', '.join(sorted(step.moving))} {verb} in along "
              f"{step.direction.reverse.name} (free along {step.direction.name})")
    return 0


def _fasteners(args: argparse.Namespace) -> int:
    # The file's diagrams as they are: -o writes this product back (the interlock and support-contact rules are the planning's).
    product = api.resolve_product(args.product, interlocks="keep", supports="keep")
    designed, proposals = api.fastener_report(product)
    if args.json:
        print(json.dumps({"designer": [_group_json(g) for g in designed],
                          "proposed": [_group_json(g) for g in proposals.groups],
                          "left_out": [{"part": p, "reason": r} for p, r in proposals.left_out]}))
    else:
        print(f"{product.name or str(args.product)} ({product.source}): {len(product.parts)} parts")
        for title, groups in (("designer's fastener groups", designed), ("proposed fastener groups", proposals.groups)):
            print(f"  {title}: {len(groups)} ({sum(len(g.parts) for g in groups)} parts)")
            for group in groups:
                tool = f"; tool {group.tool}" if group.tool else ""
                print(f"    {group.id}: {', '.join(group.parts)}\n      joins {', '.join(sorted(group.hosts))}{tool}")
                if group.reason:
                    print(f"      why: {group.reason}")
        for part, reason in proposals.left_out:
            print(f"  not proposed: {part}: {reason}")
    if args.output:
        accepted = api.accept_fasteners(product)
        save_product(_relocated(accepted, args.output), args.output)
        if not args.json:
            print(f"{args.output}: {len(accepted.fasteners)} fastener groups "
                  f"({len(accepted.fasteners) - len(product.fasteners)} proposals accepted)")
    return 0


def _relocated(product, output: str):
    """``product`` with its mesh and B-rep paths relative to ``output``'s folder instead of its own file's.
    A product read from a CAD model lives in a temporary bundle (``geometry.x-temporary-bundle``) that is
    removed when the command ends: its paths are left out, with a warning saying how to keep them."""
    temporary = (product.geometry or {}).get("x-temporary-bundle")
    if temporary:
        def kept(path: str | None) -> str | None:
            return None if path is not None and path.startswith(temporary) else path

        product = replace(product, parts=tuple(replace(p, mesh=kept(p.mesh), brep=kept(p.brep)) for p in product.parts),
                          geometry={k: v for k, v in product.geometry.items() if k != "x-temporary-bundle"})
        log.warning("%s: no mesh or B-rep paths: %s was read into a temporary bundle, removed at the end; to keep "
                    "them, write a bundle with `aplan export-freecad MODEL -o BUNDLE` and run aplan fasteners on "
                    "BUNDLE", output, Path(product.source).name)
        return product
    source = Path(product.source)
    here, there = source.resolve().parent, Path(output).resolve().parent
    if not source.is_file() or here == there:
        return product

    def moved(path: str | None) -> str | None:
        return path if path is None or os.path.isabs(path) else os.path.relpath(here / path, there)

    return replace(product, parts=tuple(replace(p, mesh=moved(p.mesh), brep=moved(p.brep)) for p in product.parts))


def _group_json(group) -> dict:
    return {"id": group.id, "parts": list(group.parts), "hosts": sorted(group.hosts), "tool": group.tool,
            "source": group.source, "reason": group.reason}


def _synth(args: argparse.Namespace) -> int:
    needed, budget = synthetic_bytes(args.kind, args.parts), default_memory_budget()
    if needed > budget:  # refused before any part is made
        raise MemoryLimitError(f"aplan synth {args.kind} {args.parts}", needed, budget,
                               f"{synthetic_contacts(args.kind, args.parts):,} contacts",
                               "Choose a smaller N (the planner refuses far smaller products anyway).")
    text = json.dumps(product_to_dict(SYNTHETIC[args.kind](args.parts)), indent=1) + "\n"
    if args.output:
        write_atomic(args.output, text)
    else:
        sys.stdout.write(text)
    return 0


def add_commands(commands) -> None:
    stats = commands.add_parser(
        "stats", help="count subassemblies, operations, states, intentions, ...",
        description="Print the figures of a product's plan: " + ", ".join(STAT_KEYS) + ". Parts, contacts and "
                    "complexity are always printed; a figure whose graph would exceed a size limit is not "
                    "computed, and the reason (the size reached, what helps) is printed instead.",
        epilog=f"Exit status: 0 when every figure was computed, {PARTIAL} when some were not (they would exceed "
               "a size limit: the others are printed, with the reason), 1 on bad input (a product that cannot be "
               "read or planned: not connected, not disassemblable), 2 on a usage error.")
    stats.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    stats.add_argument("--json", action="store_true",
                       help="print one JSON object with exactly those keys (null when not computed, and then "
                            "not_computed: the figures and the reason)")
    add_product_options(stats)
    add_contact_options(stats)
    stats.set_defaults(run=_stats)

    intentions = commands.add_parser("intentions", help="enumerate operator intentions (paths of assembly states)")
    intentions.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    intentions.add_argument("--limit", type=positive, default=DEFAULT_INTENTION_LIMIT,
                            help=f"refuse to enumerate more intentions than this (default {DEFAULT_INTENTION_LIMIT:,})")
    intentions.add_argument("--full", action="store_true", help="only the full assembly sequences")
    intentions.add_argument("--json", action="store_true", help="one JSON object per line")
    add_product_options(intentions)
    intentions.set_defaults(run=_intentions)

    sequence = commands.add_parser(
        "sequence", help="one full assembly sequence step by step: what moves, along which free direction",
        description="Show a full assembly sequence (by rank, or the one a session log recorded) as the workbench's "
                    "Plan in 3D steps through it: per operation the side that moves (the one without the base part, "
                    "else the smaller), the free direction it leaves the other side along (it goes in along the "
                    "reverse), and with --json every part's exploded offset before the step.")
    sequence.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    which = sequence.add_mutually_exclusive_group()
    which.add_argument("--rank", type=index, default=None, metavar="K",  # None: argparse sees --rank 0 beside --log
                       help="the sequence of rank K (from 0; sequences in the order of the state graph's edges)")
    which.add_argument("--log", dest="session_log", metavar="LOG",  # not "log": that names an output to check
                       help="the sequence the session log LOG (aplan session --log) recorded")
    sequence.add_argument("--spacing", type=positive_length, default=1.0, metavar="D",
                          help="how far the first moving side sits away in the exploded offsets (default 1)")
    sequence.add_argument("--json", action="store_true", help="print one JSON object with the steps and offsets")
    add_product_options(sequence)
    add_input_options(sequence)
    sequence.set_defaults(run=_sequence)

    fasteners = commands.add_parser(
        "fasteners", help="list the fastener groups: the designer's and those the planner proposes",
        description="List the product's fastener groups (its 'fasteners' section) and the groups the planner "
                    "proposes for its other parts: by name (screw, bolt, nut, washer, pin, rivet, clip) or by "
                    "geometry (a small part joining two parts each ten times its volume), fasteners with the same "
                    "hosts in one group, each with the reason. With -o, write the product with the proposals "
                    "accepted; plans fold them (--fasteners tagged, the default). Mesh paths are rewritten relative to "
                    "the new file.")
    fasteners.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    fasteners.add_argument("-o", "--output", metavar="FILE",
                           help="write the product file with the proposed groups accepted (atomically)")
    fasteners.add_argument("--json", action="store_true",
                           help="print one JSON object: designer, proposed (groups), left_out (parts and why)")
    add_force(fasteners)
    fasteners.set_defaults(run=_fasteners)

    synth = commands.add_parser("synth", help="write a synthetic product of Table I",
                                description="chain: weakly connected (each part touches the next); "
                                            "complete: strongly connected (every part touches every other).")
    synth.add_argument("kind", choices=sorted(SYNTHETIC))
    synth.add_argument("parts", type=positive, metavar="N", help="number of parts")
    synth.add_argument("-o", "--output", metavar="FILE", help="write here (default: standard output)")
    add_force(synth)
    synth.set_defaults(run=_synth)
