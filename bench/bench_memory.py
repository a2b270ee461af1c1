"""The memory budget on every path: `simulate`, `session --demo`, `pomdp --lumped`, `solve` and `stats` over
chains and complete products, each run a fresh process under a time and an address-space limit above the
budget (so a run past the budget is measured, not a crashed machine):

    /usr/bin/time -v timeout 120 prlimit --as=6442450944 aplan COMMAND PRODUCT ...

Per run: the exit status, wall and CPU seconds, the peak resident memory (GNU time's maximum RSS), the
decision times where the product is planned (`simulate --json`: the episodes' medians and maxima, and p95
when it reports one; `session`: every `decision_ms` of its log) and the checks: peak at most the default
`--max-memory` (4 GiB), a refusal (exit 1, 2 or 3) within 5 s, decision p95 at most 250 ms and max at most
500 ms. Prints a Markdown table for bench/README.md.

    .venv/bin/python bench/bench_memory.py                              # chain 6 to 30, complete 5 to 13
    .venv/bin/python bench/bench_memory.py --chains 6 23 --completes 5 12 --commands stats simulate
"""
from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
APLAN = [sys.executable, "-m", "planner"]
BUDGET_MIB = 4 * 1024
COMMANDS = {
    "stats": ["stats", "{product}"],
    "simulate": ["simulate", "{product}", "--random", "3", "--json"],
    "session": ["session", "{product}", "--demo", "0", "--log", "{folder}/session.jsonl"],
    "pomdp": ["pomdp", "{product}", "--lumped", "-o", "{folder}/model.pomdpx"],
    "solve": ["solve", "{product}", "-o", "{folder}/model.policy", "--time-limit", "20"],
}


def write_product(kind: str, size: int, folder: Path) -> Path:
    from planner import product_to_dict
    from planner.product.synthetic import SYNTHETIC

    path = folder / f"{kind}{size}.json"
    path.write_text(json.dumps(product_to_dict(SYNTHETIC[kind](size))))
    return path


def decision_times(command: str, stdout: str, folder: Path) -> tuple[float, float, float] | None:
    """(median, p95, max) in ms: of every decision (session log), else over the episodes' figures (simulate)."""
    if command == "session":
        log = folder / "session.jsonl"
        if not log.exists():
            return None
        times = [e["decision_ms"] for e in map(json.loads, log.read_text().splitlines()) if "decision_ms" in e]
        if not times:
            return None
        times.sort()
        return statistics.median(times), times[min(len(times) - 1, int(0.95 * len(times)))], times[-1]
    if command != "simulate":
        return None
    lines = [json.loads(line) for line in stdout.splitlines() if line.startswith("{")]
    run_line = next((line["run"] for line in lines if "run" in line), None)
    if run_line is not None and run_line.get("decision_seconds_median") is not None:  # every decision of the run
        return tuple(1000 * run_line[f"decision_seconds_{k}"] for k in ("median", "p95", "max"))
    episodes = [line for line in lines if "run" not in line]
    medians = [e["decision_seconds_median"] for e in episodes if e.get("decision_seconds_median") is not None]
    if not medians:
        return None
    p95 = [e["decision_seconds_p95"] for e in episodes if e.get("decision_seconds_p95") is not None]
    top = max(e["decision_seconds_max"] for e in episodes)
    return 1000 * statistics.median(medians), (1000 * max(p95) if p95 else float("nan")), 1000 * top


def run(command: str, product: Path, timeout: int, address_space: int) -> dict:
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        words = [w.format(product=product, folder=folder) for w in COMMANDS[command]]
        done = subprocess.run(["/usr/bin/time", "-v", "timeout", str(timeout), "prlimit", f"--as={address_space}",
                               *APLAN, *words], capture_output=True, text=True, cwd=folder)
        err = done.stderr
        wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", err).group(1)
        cpu = sum(float(re.search(rf"{k} time \(seconds\): (\S+)", err).group(1)) for k in ("User", "System"))
        result = {"wall": sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall.split(":")))), "cpu": cpu,
                  "peak_mib": int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", err).group(1)) / 1024,
                  "status": int(re.search(r"Exit status: (\d+)", err).group(1)),
                  "decisions": decision_times(command, done.stdout, folder),
                  "traceback": "Traceback" in err,
                  "message": next((line.removeprefix("aplan: error: ") for line in err.splitlines()
                                   if line.startswith("aplan: error:")), "")}
    return result


def checks(result: dict) -> str:
    found = []
    if result["peak_mib"] > BUDGET_MIB:
        found.append("PEAK OVER BUDGET")
    if result["status"] in (1, 2, 3) and result["wall"] > 5:
        found.append("slow refusal")
    if result["traceback"]:
        found.append("TRACEBACK")
    if result["status"] == 124:
        found.append("timeout")
    d = result["decisions"]
    if d is not None and (d[1] > 250 or d[2] > 500):
        found.append("decision time")
    return ", ".join(found) or "ok"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chains", type=int, nargs="*", default=[6, 8, 10, 12, 14, 16, 18, 20, 22, 23, 24, 25, 30])
    parser.add_argument("--completes", type=int, nargs="*", default=list(range(5, 14)))
    parser.add_argument("--commands", nargs="*", default=list(COMMANDS), choices=list(COMMANDS))
    parser.add_argument("--timeout", type=int, default=120)
    parser.add_argument("--address-space", type=int, default=6 * 2 ** 30)
    args = parser.parse_args()
    print("load average before: %.2f %.2f %.2f" % os.getloadavg(), flush=True)
    print("| command | product | exit | wall s | CPU s | peak MiB | decision ms median / p95 / max | checks | "
          "message |")
    print("|---|---|---:|---:|---:|---:|---|---|---|", flush=True)
    with tempfile.TemporaryDirectory() as folder:
        products = [("chain", n) for n in args.chains] + [("complete", n) for n in args.completes]
        for kind, size in products:
            path = write_product(kind, size, Path(folder))
            for command in args.commands:
                r = run(command, path, args.timeout, args.address_space)
                d = r["decisions"]
                times = "" if d is None else f"{d[0]:.0f} / {d[1]:.0f} / {d[2]:.0f}"
                message = r["message"][:90] + (" ..." if len(r["message"]) > 90 else "")
                print(f"| {command} | {kind} {size} | {r['status']} | {r['wall']:.1f} | {r['cpu']:.1f} | "
                      f"{r['peak_mib']:.0f} | {times} | {checks(r)} | {message} |", flush=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
