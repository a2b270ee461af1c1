"""Solvers: ``solver.solve(model) -> SolveResult`` for any :class:`~planner.decision.pomdp.POMDP`.

The builtin point-based solver in parts (as NativeSARSOP.jl): ``point_based`` (configuration and main
loop), ``tables`` (the model's tables, the initial bounds), ``lower`` and ``upper`` (the bounds), ``trials``
(HSVI2 trials and backups), ``belief_set`` and ``sweeps`` (the lower bound's sweeps), ``scheduler`` (work
sharing) and ``threads`` (BLAS threads); ``sarsop``: :class:`SarsopSolver` runs APPL SARSOP when it is installed;
``warm_start``: the lumped model's warm start, a field of the point-based solver's configuration
(:class:`~.warm_start.WarmStart`).
"""
from .point_based import PointBasedSolver, SolveResult
from .sarsop import SarsopSolver

__all__ = ["PointBasedSolver", "SarsopSolver", "SolveResult"]
