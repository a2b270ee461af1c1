"""Fasteners folded into operations (issue 13): the real models and a synthetic screwed product.

For the toy truck and the diaphragm pump: FreeCADCmd exports the document once (``aplan export-freecad``),
then the fastener proposals are checked against the hand count (tests/product/fastener_ground_truth.json),
the connected part sets the AND/OR step would enumerate are counted (up to a cap) with every part and with
the proposals folded, and ``aplan stats BUNDLE --fasteners auto --json`` runs in a fresh process:

    /usr/bin/time -v timeout 300 prlimit --as=8000000000 aplan stats BUNDLE --fasteners auto --json

For two parts and m screws (planner.product.synthetic.fastened_product): 3 * 2^m + m connected part sets
unfolded, 3 folded. Prints Markdown tables for bench/README.md.

    .venv/bin/python bench/bench_fasteners.py          # about 1 minute
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
MODELS = REPO.parent / "shared" / "models"
APLAN = [sys.executable, "-m", "planner"]
TRUTH = json.loads((REPO / "tests" / "product" / "fastener_ground_truth.json").read_text())
CAP = 20_000_000  # connected part sets counted at most


def connected_sets(product, cap: int = CAP) -> int | None:
    """The connected part sets of ``product`` (None past ``cap``): what the reverse cut-set step enumerates."""
    from planner.assembly.andor import liaison_adjacency
    from planner.assembly.bitsets import connected_subsets

    adjacency = liaison_adjacency(product)
    n, total = len(adjacency), 0
    for root in range(n):
        for _ in connected_subsets(adjacency, ((1 << n) - 1) & ~((1 << root) - 1), root):
            total += 1
            if total > cap:
                return None
    return total


def stats_run(bundle: Path) -> tuple[int, float, int, str]:
    done = subprocess.run(["/usr/bin/time", "-v", "timeout", "300", "prlimit", "--as=8000000000", *APLAN, "stats",
                           str(bundle), "--fasteners", "auto", "--json"], capture_output=True, text=True)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\d+):([\d.]+)", done.stderr)
    peak = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    seconds = int(wall.group(1)) * 60 + float(wall.group(2))
    try:
        data = json.loads(done.stdout)
        shown = ", ".join(f"{k} {v:,}" for k, v in data.items() if isinstance(v, int))
        if "not_computed" in data:
            shown += "; not computed: " + data["not_computed"]["reason"].split(". ")[0]
    except json.JSONDecodeError:
        errors = [line for line in done.stderr.splitlines() if line.startswith("aplan: error")]
        shown = errors[0][:200] if errors else "(nothing)"
    return done.returncode, seconds, int(peak.group(1)) // 1024, shown


def real_models(folder: Path) -> None:
    from planner import api, load_product
    from planner.product import fastener_proposals, fold

    print("| model | parts | designer's fasteners (hand count) | proposed of them | wrong proposals | groups | "
          "parts folded | connected sets, every part | connected sets, folded | stats exit | wall s | peak MiB | "
          "printed |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for name in ("toy_truck", "diaphragm_pump"):
        truth = TRUTH[name]
        bundle = folder / name
        subprocess.run([*APLAN, "export-freecad", str(MODELS / truth["model"]), "-o", str(bundle)], check=True,
                       capture_output=True)
        product = load_product(bundle / "product.json")
        proposals = fastener_proposals(product)
        proposed = {p for g in proposals.groups for p in g.parts}
        fasteners = set(truth["fasteners"])
        folded = fold(api.resolve_product(product, fasteners="auto"))
        every, few = connected_sets(product), connected_sets(folded.product)
        code, seconds, peak, shown = stats_run(bundle)
        print(f"| {name} | {len(product.parts)} | {len(fasteners)} | {len(proposed & fasteners)} | "
              f"{len(proposed - fasteners)} | {len(proposals.groups)} | {folded.folded_parts} | "
              f"{'more than ' + format(CAP, ',') if every is None else format(every, ',')} | "
              f"{'more than ' + format(CAP, ',') if few is None else format(few, ',')} | {code} | {seconds:.1f} | "
              f"{peak} | {shown} |")


def synthetic() -> None:
    from planner.assembly.stats import statistics_within
    from planner.product import FastenerGroup
    from planner.product.synthetic import fastened_product

    print("| screws m | connected sets unfolded (3 * 2^m + m) | subassemblies folded | operations folded | "
          "stats folded, s |")
    print("|---:|---:|---:|---:|---:|")
    for screws in (4, 10, 16, 39):
        product = fastened_product(2, screws)
        names = tuple(p for p in product.part_ids if p.startswith("screw"))
        start = time.perf_counter()
        _, stats = statistics_within(replace(product, fasteners=(FastenerGroup("screws", names),)))
        seconds = time.perf_counter() - start
        print(f"| {screws} | {3 * 2 ** screws + screws:,} | {stats.subassemblies} | {stats.operations} | "
              f"{seconds:.3f} |")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as work:
        real_models(Path(work))
    print()
    synthetic()
