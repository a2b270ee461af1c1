"""Model files at scale: write and read POMDPX and Cassandra ``.pomdp`` for the pen and synthetic products.

Run: ``.venv/bin/python bench/bench_model_files.py [--limit-gb 6] [--cases pen chain6 ...] [--formats pomdpx]``
(about 5 minutes; ``--cases chain9`` adds the 109,601-intention chain of 9).
Each write and each read runs in a fresh process under an address-space limit (``--limit-gb``), so a reader
that asks for a dense actions x states x states array fails with a MemoryError instead of taking the machine.
Columns: states, non-zero entries of the transition and observation tables, file size, then seconds and peak
resident memory (MiB, the whole process, Python and numpy included) of the write (model built in the same
process: "base" is the peak before the write starts) and of the read.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

CASES = {"pen": ("pen", 0), "chain6": ("chain", 6), "chain7": ("chain", 7), "chain8": ("chain", 8),
         "complete5": ("complete", 5), "complete6": ("complete", 6), "chain9": ("chain", 9)}
DEFAULT = ["pen", "chain6", "chain7", "chain8", "complete5", "complete6"]  # chain9: on request (minutes)
FORMATS = {"pomdpx": ".pomdpx", "cassandra": ".pomdp"}


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux


def _model(case: str):
    from planner import chain_product, complete_product, make_plan, resolve_product
    from planner.decision import intention_pomdp
    kind, n = CASES[case]
    product = resolve_product("pen") if kind == "pen" else \
        (chain_product if kind == "chain" else complete_product)(n)
    return intention_pomdp(make_plan(product))


def child(operation: str, case: str, fmt: str, path: str) -> dict:
    """One write or read in this process; the figures as a dict."""
    from planner.decision.io import read_cassandra, read_pomdpx, write_cassandra, write_pomdpx
    if operation == "write":
        model = _model(case)
        base = _peak_mib()
        start = time.perf_counter()
        (write_pomdpx if fmt == "pomdpx" else write_cassandra)(model, path)
        seconds = time.perf_counter() - start
    else:
        base = _peak_mib()
        start = time.perf_counter()
        model = (read_pomdpx if fmt == "pomdpx" else read_cassandra)(path)
        seconds = time.perf_counter() - start
    nnz = sum(t.nnz for t in model.transition) + sum(o.nnz for o in model.observation)
    return {"states": model.n_states, "actions": model.n_actions, "nnz": nnz, "seconds": seconds,
            "base_mib": base, "peak_mib": _peak_mib(), "bytes": os.path.getsize(path)}


def run(operation: str, case: str, fmt: str, path: str, limit_gb: float) -> dict:
    """``child`` in a fresh process limited to ``limit_gb`` of address space; ``{"error": ...}`` on failure."""
    limit = int(limit_gb * 2 ** 30)

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    done = subprocess.run([sys.executable, __file__, "--child", operation, case, fmt, path],
                          capture_output=True, text=True, preexec_fn=cap,
                          env={**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"})
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["exit status %d" % done.returncode])[-1]
        return {"error": last[:90]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limit-gb", type=float, default=6.0)
    parser.add_argument("--cases", nargs="+", default=DEFAULT, choices=list(CASES))
    parser.add_argument("--formats", nargs="+", default=list(FORMATS), choices=list(FORMATS))
    parser.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    print(f"load average {os.getloadavg()[0]:.2f}, address-space limit {args.limit_gb:g} GiB per process")
    print("| model | format | states | nnz | file MiB | write s | write MiB (base) | read s | read MiB (base) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory(prefix="aplan-bench-files-") as folder:
        for case in args.cases:
            for fmt in args.formats:
                path = str(Path(folder) / (case + FORMATS[fmt]))
                w = run("write", case, fmt, path, args.limit_gb)
                if "error" in w:
                    print(f"| {case} | {fmt} | | | | write failed: {w['error']} | | | |", flush=True)
                    continue
                r = run("read", case, fmt, path, args.limit_gb)
                read = (f"{r['seconds']:.2f} | {r['peak_mib']:.0f} ({r['base_mib']:.0f})" if "error" not in r
                        else f"failed: {r['error']} | ")
                print(f"| {case} | {fmt} | {w['states']:,} | {w['nnz']:,} | {w['bytes'] / 2 ** 20:.1f} | "
                      f"{w['seconds']:.2f} | {w['peak_mib']:.0f} ({w['base_mib']:.0f}) | {read} |", flush=True)
                Path(path).unlink(missing_ok=True)


if __name__ == "__main__":
    main()
