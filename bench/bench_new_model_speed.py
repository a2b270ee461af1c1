"""Issue 23, "Still fast": the online planner's decision time (median, 95th percentile, max) and the command's
peak memory on chain 11 and complete 9 with the new model's parts switched on, as a user runs it:

    .venv/bin/python bench/bench_new_model_speed.py [--episodes 5] [PRODUCT...] [-- EXTRA CLI FLAGS]

For each product (default ``chain:11 complete:9``, written by ``aplan synth``) it learns habits through the real
pipeline (20 session logs of an operator following one sequence 80 % of the time, then ``aplan habits``:
:func:`bench_habits.learn_habits`), then runs ``aplan simulate PRODUCT --planner online --random N --json
--habits H --operator-sequence habitual:K:0.8 EXTRA...`` under GNU time (``/usr/bin/time -v``: peak resident
set) and reads the decision times from its ``run`` line (the CLI's default budget: 0.1 s per decision). EXTRA
is passed through unchanged: ``-- --parallel`` or change-of-mind options as other parts of the model land
(``-- --model paper`` measures the paper's model the same way). Targets (printed): median <= 100 ms, p95 <= 250
ms, peak <= 2 GiB. Prints one line per product, or JSON with ``--json``.

``--every-part RULE,...`` (``projected``, ``joins``, ``parallel``): every new part switched on, one run per
rule on the same habits: ``--RULE --switch 0.05 --mistakes 0.02`` (help before the last step, a change of mind
and mistakes, beside the habits), then EXTRA.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_habits import APLAN, learn_habits, synth_product  # noqa: E402

TARGETS = {"median_ms": 100.0, "p95_ms": 250.0, "peak_mib": 2048.0}
EVERY_PART = ["--switch", "0.05", "--mistakes", "0.02"]  # beside the habits and one rule of help (--every-part)


def _simulate(product: Path, habits: Path, favourite: int, episodes: int, seed: int, extra: list[str]) -> dict:
    """The decision times and peak memory of one ``aplan simulate`` run (module docstring)."""
    command = ["/usr/bin/time", "-v", *APLAN, "simulate", str(product), "--planner", "online", "--random",
               str(episodes), "--seed", str(seed), "--json", "--habits", str(habits), "--operator-sequence",
               f"habitual:{favourite}:0.8", *extra]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{product.name}: aplan simulate failed ({done.returncode}): {done.stderr.strip()[-800:]}")
    run = next(json.loads(line)["run"] for line in done.stdout.splitlines() if line.startswith('{"run"'))
    peak = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    return {"decisions": run["decisions"], "median_ms": 1000 * run["decision_seconds_median"],
            "p95_ms": 1000 * run["decision_seconds_p95"], "max_ms": 1000 * run["decision_seconds_max"],
            "peak_mib": int(peak.group(1)) / 1024 if peak else float("nan"), "command": " ".join(command[2:])}


def main() -> None:
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[:argv.index("--")] if "--" in argv else argv
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("products", nargs="*", default=["chain:11", "complete:9"], metavar="PRODUCT")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--logs", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--every-part", metavar="RULE,...", default=None,
                        help="one run per rule (projected, joins, parallel) with --switch 0.05 --mistakes 0.02")
    args = parser.parse_args(argv)
    runs = [extra] if args.every_part is None else \
        [[f"--{rule}", *EVERY_PART, *extra] for rule in args.every_part.split(",") if rule]
    with tempfile.TemporaryDirectory() as folder:
        for k, spec in enumerate(args.products):
            path = synth_product(spec, Path(folder)) if ":" in spec else Path(spec)
            habits_path, favourite = learn_habits(path, args.logs, args.seed, Path(folder) / f"logs-{k}")
            for flags in runs:
                _report(args, spec, flags, _simulate(path, habits_path, favourite, args.episodes, args.seed, flags))


def _report(args, spec: str, extra: list[str], measured: dict) -> None:
    """One line (or JSON row) per run: the figures against the targets, and the command."""
    row = {"product": spec, "episodes": args.episodes, "extra": extra, **measured}
    met = {key: row[key] <= limit for key, limit in TARGETS.items()}
    row["targets_met"] = all(met.values())
    if args.json:
        print(json.dumps(row))
    else:
        print(f"{spec} {' '.join(extra)}: {row['decisions']} decisions, median {row['median_ms']:.1f} ms, p95 "
              f"{row['p95_ms']:.1f} ms, max {row['max_ms']:.1f} ms, peak {row['peak_mib']:.0f} MiB; targets "
              + ("met" if row["targets_met"] else "MISSED: " + ", ".join(k for k, ok in met.items() if not ok)))
        print(f"  {row['command']}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
