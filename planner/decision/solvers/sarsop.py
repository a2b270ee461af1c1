"""APPL SARSOP (``pomdpsol``) as an engine, when it is installed; nothing is ever downloaded."""
from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from ...errors import PlannerError
from ..io.pomdpx import write_pomdpx
from ..policy import read_policy
from ..pomdp import POMDP
from .point_based import SolveResult

__all__ = ["solve_with_sarsop"]


def solve_with_sarsop(model: POMDP, time_limit: float, precision: float, executable: str = "pomdpsol") -> SolveResult:
    """Run ``pomdpsol`` on ``model``; its last reported bounds and its policy make the result."""
    found = shutil.which(executable)
    if found is None:
        raise PlannerError(f"{executable!r} is not on PATH; install APPL SARSOP or use the builtin engine")
    with tempfile.TemporaryDirectory(prefix="aplan-sarsop-") as folder:
        model_path, policy_path = Path(folder) / "model.pomdpx", Path(folder) / "out.policy"
        write_pomdpx(model, model_path)
        start = time.perf_counter()
        done = subprocess.run([found, "--timeout", f"{time_limit:g}", "--precision", f"{precision:g}",
                               "--output", str(policy_path), str(model_path)], capture_output=True, text=True)
        seconds = time.perf_counter() - start
        if done.returncode != 0 or not policy_path.exists():
            raise PlannerError(f"pomdpsol failed (exit {done.returncode}): {done.stderr.strip()[-500:]}")
        policy = read_policy(policy_path, model)
    # The progress table's rows end with: ... time #Trial #Backup LBound UBound Precision #Alphas #Beliefs
    rows = [line.split() for line in done.stdout.splitlines() if re.match(r"^\s*\d", line)]
    lower = upper = float("nan")
    for row in rows:
        if len(row) >= 6:
            try:
                lower, upper = float(row[3]), float(row[4])
            except ValueError:
                continue
    return SolveResult(policy, lower, upper, seconds, len(rows), [])
