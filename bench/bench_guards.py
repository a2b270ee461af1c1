"""`aplan stats` on every FreeCAD document in ../shared/models: wall time, peak memory, and what it printed.

Each document runs in a fresh process, as a user would run it:

    /usr/bin/time -v timeout 120 prlimit --as=8000000000 aplan stats MODEL.FCStd --json

(FreeCADCmd exports the document into a temporary bundle, the mesh engine analyses it, the planner counts).
Peak MiB is GNU time's maximum resident set size: that of the largest process of the run (FreeCADCmd or the
planner). Prints a Markdown table for bench/README.md.

    .venv/bin/python bench/bench_guards.py                 # about 5 minutes (33 documents)
    .venv/bin/python bench/bench_guards.py --only asm_      # the assemblies alone
    .venv/bin/python bench/bench_guards.py --synthetic      # synthetic products past each limit (2 minutes)
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
MODELS = REPO.parent / "shared" / "models"
APLAN = [sys.executable, "-m", "planner"]


# Synthetic products past each limit: (label, product, command and options). "fastened P S": P parts in a
# chain joined by S screws (planner.product.synthetic.fastened_product).
SYNTHETIC = [
    ("stats", "fastened 2 40", ["stats"]),        # the lower bound on connected sets: refused at once
    ("stats", "chain 1500", ["stats"]),           # 1,125,750 connected sets: refused after enumerating 1,000,000
    ("stats", "complete 16", ["stats"]),          # 65,535 sets but 21.5 M cuts: refused after 2 M cuts
    ("stats", "complete 12", ["stats"]),          # every figure (4.2 M states)
    ("stats", "complete 13", ["stats"]),          # the AND/OR figures; the state graph passes 4 GiB
    ("pomdp", "chain 10", ["pomdp", "-o", "model.pomdpx"]),   # flat model about 4.3 GiB: refused
    ("pomdp", "chain 11", ["pomdp", "-o", "model.pomdpx"]),   # flat model about 59 GiB: refused
    ("intentions", "chain 12", ["intentions", "--limit", "1000000000"]),  # 108 M intentions: 5.7 GiB, refused
]


def write_product(spec: str, folder: Path) -> Path:
    from planner import product_to_dict
    from planner.product.synthetic import SYNTHETIC as KINDS
    from planner.product.synthetic import fastened_product

    kind, *sizes = spec.split()
    product = fastened_product(*map(int, sizes)) if kind == "fastened" else KINDS[kind](int(sizes[0]))
    path = folder / (spec.replace(" ", "_") + ".json")
    path.write_text(json.dumps(product_to_dict(product)))
    return path


def run_stats(model: Path, timeout: int, address_space: int, command: list[str] | None = None) -> dict:
    command = ["/usr/bin/time", "-v", "timeout", str(timeout), "prlimit", f"--as={address_space}", *APLAN,
               *(command or ["stats"]), str(model), *([] if command else ["--json"])]
    done = subprocess.run(command, capture_output=True, text=True, cwd=model.parent)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", done.stderr).group(1)
    seconds = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall.split(":"))))
    peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1)) / 1024
    status = int(re.search(r"Exit status: (\d+)", done.stderr).group(1))
    return {"seconds": seconds, "peak_mib": peak, "status": status, "stdout": done.stdout,
            "stderr": "\n".join(line for line in done.stderr.splitlines() if line.startswith("aplan"))}


def summary(result: dict) -> str:
    """The figures printed, or the refusal's first words."""
    if result["status"] == 124:
        return "killed by timeout"
    try:
        data = json.loads(result["stdout"])
        if not isinstance(data, dict):
            raise ValueError
    except ValueError:
        if result["status"] == 0:
            return result["stdout"].splitlines()[0] if result["stdout"] else ""
        message = result["stderr"].splitlines()[-1].removeprefix("aplan: error: ") if result["stderr"] else ""
        return "error: " + (message[:110] + " ..." if len(message) > 110 else message)
    figures = ", ".join(f"{k} {v:,}" if isinstance(v, int) else f"{k} {v}" for k, v in data.items()
                        if v is not None and k in ("parts", "contacts", "subassemblies", "states", "intentions",
                                                   "sequences"))
    if "not_computed" in data:
        reason = data["not_computed"]["reason"]
        figures += "; not computed: " + reason.split(". ")[0]
    return figures


def synthetic(args: argparse.Namespace) -> None:
    print("load average before: %.2f %.2f %.2f" % os.getloadavg())
    print("| command | product | exit | wall s | peak MiB | printed |")
    print("|---|---|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as folder:
        for label, spec, command in SYNTHETIC:
            path = write_product(spec, Path(folder))
            result = run_stats(path, args.timeout, args.address_space, command if label != "stats" else None)
            print(f"| {label} | {spec} | {result['status']} | {result['seconds']:.1f} | {result['peak_mib']:.0f} | "
                  f"{summary(result)} |", flush=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="only documents whose name contains this")
    parser.add_argument("--synthetic", action="store_true", help="synthetic products past each limit instead")
    parser.add_argument("--timeout", type=int, default=120)
    parser.add_argument("--address-space", type=int, default=8_000_000_000)
    args = parser.parse_args()
    if args.synthetic:
        synthetic(args)
        return
    models = sorted(p for p in MODELS.rglob("*.FCStd") if args.only in p.name)
    print("load average before: %.2f %.2f %.2f" % os.getloadavg())
    print("| document | exit | wall s | peak MiB | printed |")
    print("|---|---:|---:|---:|---|")
    for model in models:
        result = run_stats(model, args.timeout, args.address_space)
        print(f"| {model.relative_to(MODELS)} | {result['status']} | {result['seconds']:.1f} | "
              f"{result['peak_mib']:.0f} | {summary(result)} |", flush=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
