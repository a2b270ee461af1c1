"""``aplan habits LOG... -o habits.json``: the operator's habits learned from session logs (issue 23,
docs/habits.md), and ``--habits FILE`` / ``--model paper|habits`` for the commands that build a model."""
from __future__ import annotations

import argparse
import json

from ..decision.habits import PRIOR_PER
from ..decision.io.habits_file import write_habits
from ..defaults import HABITS_PRIOR, ORDERS_CONCENTRATION, ORDERS_DISCOUNT
from .options import (
    add_fasteners,
    add_force,
    add_input_options,
    add_technical,
    finite,
    habits_from,
    inputs_from,
    number,
    product_from,
)

__all__ = ["add_commands", "habits_from"]


def _habits(args: argparse.Namespace) -> int:
    from ..api import learn_habits

    product = None if args.product is None else product_from(args, args.product)
    notes: list[str] = []
    habits, steps = learn_habits(args.logs, product, args.prior, args.prior_per, args.technical, args.add,
                                 inputs_from(args), args.concentration, args.discount, notes)
    write_habits(args.output, habits, len(args.logs))
    if args.json:
        print(json.dumps({"product": habits.product, "fingerprint": habits.fingerprint, "prior": habits.prior,
                          "prior_per": habits.prior_per, "logs": len(args.logs), "steps": steps,
                          "unrecorded": len(notes),
                          "edges": len(habits.counts), "orders": len(habits.orders),
                          "concentration": habits.concentration, "discount": habits.discount}))
    else:
        for note in notes:
            print(f"note: {note}")
        print(f"{habits.product}: {steps:g} steps from {len(args.logs)} log{'s' if len(args.logs) != 1 else ''}, "
              f"{len(habits.counts)} state edges counted (prior {habits.prior:g} per {habits.prior_per}; state graph "
              f"{habits.fingerprint}); {len(habits.orders)} distinct orders recorded (concentration "
              f"{habits.concentration:g}, discount {habits.discount:g})")
        print(f"habits: {args.output}")
    return 0


def add_commands(commands) -> None:
    habits = commands.add_parser(
        "habits", help="learn the operator's habits (their choice at each assembly state) from session logs",
        description="Count, from session logs, how often the operator took each next operation at each assembly "
                    "state, and write the habits file that --habits FILE puts into the decision model in place of "
                    "the uniform choice of Alg. 3 (docs/habits.md), with the orders (whole sequences) of the finished "
                    "sessions that --model orders uses. Logs of another product version are refused.")
    habits.add_argument("logs", nargs="+", metavar="LOG", help="session logs (.jsonl) of one product version")
    habits.add_argument("-o", "--output", required=True, metavar="FILE", help="the habits file (JSON)")
    habits.add_argument("--product", metavar="PRODUCT",
                        help="the product the habits are for (default: the one the first log stores); every log "
                             "must be of its version")
    habits.add_argument("--prior", type=number(0, low_open=True), default=None, metavar="ALPHA",
                        help=f"the prior's pseudo-observations alpha, spread as the paper's model chooses "
                             f"(default {HABITS_PRIOR:g}; above 0)")
    habits.add_argument("--prior-per", choices=PRIOR_PER, default=None,
                        help="what alpha counts: edge, alpha per next operation (alpha d at a state of d; the "
                             "default, as files written before this option); state, alpha in all at each state, "
                             "so a state of many operations needs no more sessions (docs/habits.md)")
    habits.add_argument("--concentration", type=finite, default=None, metavar="A",
                        help=f"the orders' Pitman-Yor concentration a, above -d (default {ORDERS_CONCENTRATION:g}; "
                             "--model orders, docs/habits.md, Orders)")
    habits.add_argument("--discount", type=number(0, 1, high_open=True), default=None, metavar="D",
                        help=f"the orders' Pitman-Yor discount d, from 0 to below 1 (default {ORDERS_DISCOUNT:g})")
    habits.add_argument("--add", metavar="HABITS", help="a habits file whose counts the logs' are added to")
    habits.add_argument("--json", action="store_true", help="print product, fingerprint, prior, prior_per, logs, steps, "
                                                                     "edges")
    add_technical(habits)
    add_fasteners(habits)
    add_force(habits)
    add_input_options(habits)
    habits.set_defaults(run=_habits)
