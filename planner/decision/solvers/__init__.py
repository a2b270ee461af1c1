"""Solvers: ``solver.solve(model) -> SolveResult`` for any :class:`~planner.pomdp.POMDP`."""
from .point_based import PointBasedSolver, SolveResult

__all__ = ["PointBasedSolver", "SolveResult"]
