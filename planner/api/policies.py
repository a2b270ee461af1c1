"""Stage 4 of the API: a policy from a solver (the built-in point-based one, or SARSOP), refused when it is no better
than the blind policies, or read from a file."""
from __future__ import annotations

import logging
import math
import os
from contextlib import nullcontext
from dataclasses import replace
from typing import Callable

from ..assembly.guards import default_memory_budget
from ..decision.budget import check_solver_memory, lumped_start_fits
from ..decision.models import is_flat, is_lumped, solver_plan, tables
from ..decision.policy import AlphaVectorPolicy, read_policy
from ..decision.solvers import PointBasedSolver, SarsopSolver, SolveResult
from ..decision.solvers.warm_start import WarmStart
from ..defaults import POLICY_TIME_LIMIT, SOLVE_PRECISION, SOLVE_TIME_LIMIT
from ..errors import PlannerError, SolveTimeError
from ..interrupts import deferred_interrupts
from ..validation import InputLimits

from .models import Model

__all__ = ["SOLVER_ENGINES", "solve", "check_solved", "policy_for"]

log = logging.getLogger(__name__)


SOLVER_ENGINES = ("builtin", "sarsop")


def solve(model: Model, time_limit: float = SOLVE_TIME_LIMIT, precision: float = SOLVE_PRECISION,
          engine: str = "builtin", progress: Callable[[float, float, float], None] | None = None,
          iterations: int | None = None, keep_on_interrupt: bool = False, max_bytes: int | None = None,
          started: float | None = None, write_seconds: float = 0.0) -> SolveResult:
    """Solve ``model`` offline: ``engine`` ``builtin`` (:class:`PointBasedSolver`, ``progress(seconds,
    lower, upper)`` after each step) or ``sarsop`` (APPL's ``pomdpsol``, when it is on PATH). The solver
    stops at ``time_limit`` seconds (its set-up included), at a gap of ``precision``, or after ``iterations``
    trials (builtin only: a fixed amount of work gives the same policy on any machine). ``started``: the
    ``time.perf_counter()`` value the limit counts from (default: now; the command line passes its own start,
    so the model's building counts too); ``write_seconds``: seconds per policy number kept before the limit
    for writing the policy after it. ``keep_on_interrupt`` (builtin only): Ctrl-C or SIGTERM, from the warm
    start on, stops it with the policy so far (``SolveResult.interrupted``; the warm start, the bounds'
    set-up and every long step check the flag). ``max_bytes`` (builtin only; default the machine's budget):
    the memory the model and the solver may take together, estimated before the solver starts
    (:func:`~planner.decision.solvers.tables.solver_bytes`)."""
    if engine == "sarsop":
        return SarsopSolver(time_limit, precision).solve(tables(model))
    if engine != "builtin":
        raise PlannerError(f"unknown solver engine {engine!r}; use one of {', '.join(SOLVER_ENGINES)}")
    budget = default_memory_budget() if max_bytes is None else max_bytes
    check_solver_memory(tables(model), budget, solver_plan(model), is_flat(model))
    solver = PointBasedSolver(time_limit=time_limit, precision=precision, max_iterations=iterations,
                              keep_on_interrupt=keep_on_interrupt, write_seconds=write_seconds)
    started = solver.clock() if started is None else started  # the time limit counts the bounds' set-up too
    if is_lumped(model):  # relaxed bounds (the state told, or told late) start the upper bound lower
        groups, points = lumped_start_fits(model.pomdp, model.factored.plan, budget)  # optional: left out past it
        solver = replace(solver, warm_start=WarmStart(model, points=points, groups=groups))
    with deferred_interrupts() if keep_on_interrupt else nullcontext(lambda: 0) as pending:
        # the warm start checks ``pending``: an interrupt before the solver had anything stops it at once
        return solver.solve(tables(model), progress, started=started, stopped=pending)


def check_solved(result: SolveResult, precision: float, time_limit: float, what: str = "--time-limit",
                 smaller: str = "--lumped on a PRODUCT, --base-part") -> str | None:
    """Refuse a policy no better than the blind ones the solver starts from (each repeats one action, whatever
    it observes; or the floor ``min R / (1 - gamma)`` when even they did not fit: what a solver cut short by
    its time limit leaves), unless its gap is within ``precision`` anyway: :class:`~planner.errors.SolveTimeError`
    naming the bound, the time and what helps (``what``: the time option; ``smaller``: the options that make
    a smaller model). Returns a warning when the policy beats them by ``precision`` or less, else None."""
    if result.gap <= precision or result.improved(precision):
        return None
    more = (f"Give it more time ({what} {_more_time(time_limit)}), or a smaller model ({smaller})")
    if not result.improved(1e-9 * max(1.0, abs(result.blind_lower))):
        limit = f"of the {time_limit:g} s limit " if time_limit is not None else ""
        raise SolveTimeError(f"no policy written: after {result.seconds:.1f} s {limit}the "
                             f"solver's lower bound at the initial belief is still the blind policies' "
                             f"({result.lower_bound:.6f}; {result.iterations} trials): such a policy repeats one "
                             f"action whatever it observes. {more}")
    return (f"the policy is within {precision:g} of the blind policies at the initial belief (lower bound "
            f"{result.lower_bound:.6f} against {result.blind_lower:.6f}, upper bound {result.upper_bound:.6f}, "
            f"after {result.seconds:.1f} s): it does little better than one action repeated. {more}")


def _more_time(limit: float | None) -> str:
    return f"{max(2 * limit, limit + 30):g}" if limit is not None and math.isfinite(limit) else "larger"


def policy_for(model: Model, policy: str | os.PathLike | None = None, time_limit: float = POLICY_TIME_LIMIT,
               inputs: InputLimits = InputLimits()) -> tuple[AlphaVectorPolicy, SolveResult | None]:
    """The policy in the file ``policy`` (checked against the model; read within ``inputs``), or, without
    one, the built-in solver's after ``time_limit`` seconds, with its result (bounds, time); one no better
    than the blind policies is refused (:func:`check_solved`)."""
    if policy:
        return read_policy(policy, tables(model), inputs), None
    result = solve(model, time_limit, SOLVE_PRECISION)
    warning = check_solved(result, SOLVE_PRECISION, time_limit)
    if warning:
        log.warning("%s", warning)
    return result.policy, result
