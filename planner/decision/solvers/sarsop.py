"""APPL SARSOP (``pomdpsol``) as an engine, when it is installed; nothing is ever downloaded."""
from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from ...errors import PlannerError
from ..io.pomdpx import write_pomdpx
from ..policy import read_policy
from ..pomdp import POMDP
from .point_based import SolveResult

__all__ = ["SarsopSolver", "solve_with_sarsop"]


@dataclass(frozen=True)
class SarsopSolver:
    """APPL SARSOP (``pomdpsol``, when it is on PATH) as a solver: the configuration (``time_limit`` s,
    ``precision``: the target gap at the initial belief, ``executable``), :meth:`solve` runs it, as
    :class:`~.point_based.PointBasedSolver` does."""

    time_limit: float = 60.0
    precision: float = 1e-3
    executable: str = "pomdpsol"

    def solve(self, model: POMDP) -> SolveResult:
        """Run ``pomdpsol`` on ``model`` (written as POMDPX to a temporary folder); its last reported bounds and
        its policy make the result. A missing ``pomdpsol`` or a failed run is a :class:`PlannerError`."""
        return solve_with_sarsop(model, self.time_limit, self.precision, self.executable)


def solve_with_sarsop(model: POMDP, time_limit: float, precision: float, executable: str = "pomdpsol") -> SolveResult:
    """Run ``pomdpsol`` on ``model``; its last reported bounds and its policy make the result
    (:class:`SarsopSolver` is the solver object)."""
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
