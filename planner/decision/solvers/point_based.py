"""An anytime point-based POMDP solver with certified bounds: heuristic search for the upper bound, value
iteration over reachable beliefs for the lower bound.

The value ``V*(b0)`` is bracketed by a lower bound (:mod:`.lower`: alpha vectors, the value of a policy that
can be executed) and an upper bound (:mod:`.upper`: the fast informed bound and belief points interpolated
by the sawtooth rule). Two processes share the work (:mod:`.scheduler`):

- *trials* (:mod:`.trials`, HSVI2) descend from ``b0`` along the largest weighted excess gap and back up
  both bounds on the way up; every other trial follows the lower bound's policy instead;
- *sweeps* (:mod:`.sweeps`, :mod:`.belief_set`) grow a set of beliefs reachable under the lower bound's
  policy, heaviest first, and back up all of them at once, which tightens the lower bound far faster than
  one belief per trial step (on the pen: within 0.001 of the optimum in about half a second).

It stops at the time limit, at the trial limit, or when ``upper - lower <= precision`` at ``b0``: the gap is
a certificate, ``V*(b0)`` lies between the bounds. Without a time limit the result depends only on the
configuration and the model. The parts follow NativeSARSOP.jl's layout (solver, bounds, sample, backup,
prune); :mod:`.threads` picks the BLAS thread count.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Callable

import numpy as np

from ...interrupts import Interrupted, deferred_interrupts
from ..policy import AlphaVectorPolicy
from ..pomdp import POMDP
from .belief_set import BeliefSet
from .lower import LowerBound
from .scheduler import WorkSharing
from .sweeps import sweep_rounds
from .tables import Tables, fast_informed_bound
from .threads import blas_threads, limited_blas
from .trials import backup_groups, bounds_at, trial
from .upper import CornerGroups, RelaxedQ, UpperBound

if TYPE_CHECKING:
    from .warm_start import WarmStart

__all__ = ["PointBasedSolver", "SolveResult"]


@dataclass(frozen=True)
class SolveResult:
    """The policy (lower-bound alpha vectors), the bounds at ``b0`` and how they evolved."""

    policy: AlphaVectorPolicy
    lower_bound: float
    upper_bound: float
    seconds: float
    iterations: int
    history: list = field(default_factory=list)  # (seconds, lower, upper) after each trial or sweep
    interrupted: int = 0  # the signal (SIGINT: Ctrl-C) that stopped the solver early, 0 when none did
    blind_lower: float = -math.inf  # the lower bound at b0 after the set-up: the blind policies' (or the floor)

    def improved(self, by: float = 0.0) -> bool:
        """Whether the policy is better at b0, by more than ``by``, than the blind policies the solver starts
        from (each repeats one action whatever it observes; the floor ``min R / (1 - gamma)`` where their
        time ran out)."""
        return self.lower_bound - self.blind_lower > by

    @property
    def gap(self) -> float:
        return self.upper_bound - self.lower_bound

    def as_dict(self) -> dict:
        return {"lower_bound": self.lower_bound, "upper_bound": self.upper_bound, "gap": self.gap,
                "alpha_vectors": int(self.policy.alphas.shape[0]), "seconds": round(self.seconds, 3),
                "iterations": self.iterations}


@dataclass(frozen=True)
class PointBasedSolver:
    """The solver's configuration (module docstring); :meth:`solve` runs it. Same configuration and no time
    limit, same result: the processes are balanced by counted work, not by the clock.

    Stopping: ``time_limit`` (s; None or ``math.inf``: none), ``precision`` (target gap at b0),
    ``max_iterations`` (trials; None: none).
    Upper bound: ``informed_tolerance`` and ``informed_sweeps`` stop the fast informed bound (and, with a
    time limit, a quarter of it); ``prune_points_at``: the upper-bound points are pruned when their number
    reaches it, then whenever it doubles; ``seed`` draws the fingerprint that keys beliefs.
    Trials: ``max_depth``; ``gap_fraction``: each trial aims at this fraction of the current gap at b0 (at
    least ``precision``; close to 1: shallow trials, more of them, which on the lumped models tightens the
    upper bound faster: chain 7 at 60 CPU-s 0.263 / 0.308 with 0.99 against 0.264 / 0.323 with 0.9); every ``lower_trial_every``-th trial follows the lower bound's policy.
    Sweeps: ``theta`` is the first reach-weight threshold for growing the belief set, divided by
    ``theta_factor`` whenever no belief above it is left to grow; ``sweeps_per_round`` sweeps follow each
    growth, over ``chunk`` beliefs at a time; the set stops growing at ``belief_memory`` stored numbers
    (400 MB).
    Sharing: work is counted in estimated multiply-adds; it goes to the process that has recently closed
    the gap at b0 the fastest per unit of work (half-life ``rate_horizon`` units), each keeping at least
    ``min_share`` of it.
    Threads: ``blas_threads``, the BLAS threads during the solve (None: chosen from the model's size,
    unless OMP_NUM_THREADS or the like is set; :mod:`.threads`).
    Interrupts: with ``keep_on_interrupt``, SIGINT (Ctrl-C) or SIGTERM ends the solve with the policy so far
    (``SolveResult.interrupted`` says which signal; a second one interrupts at once); they are deferred to
    the end of the step under way (:func:`planner.interrupts.deferred_interrupts`), so the bounds stay
    consistent. Otherwise an interrupt propagates.
    ``clock``: the time source of ``time_limit`` (tests inject a counter). The limit covers the whole solve
    but building the tables, the bounds' set-up included, from ``solve``'s ``started`` (what came before it
    counts too): of the time then left, the blind policies get an eighth (the rest of the actions then the
    floor ``min R / (1 - gamma)``), the upper bound's value iterations and the known points a quarter (they
    stop inside a sweep; the points left out are optional), a trial stops descending at the limit, and a
    sweep of the belief set or its growth stops between blocks of back-ups (keeping the vectors backed up so
    far). ``write_seconds``: seconds per number of the policy so far kept before the limit for writing it
    after the solve (0: none; the command line's estimate of its writing speed).
    """

    time_limit: float | None = 60.0
    precision: float = 1e-3
    max_iterations: int | None = None
    informed_tolerance: float = 1e-3
    informed_sweeps: int = 1000
    prune_points_at: int = 512
    group_passes: int = 100
    group_every: int = 20
    max_depth: int = 300
    gap_fraction: float = 0.99
    lower_trial_every: int = 2
    theta: float = 1e-3
    theta_factor: float = 3.0
    sweeps_per_round: int = 3
    chunk: int = 4096
    belief_memory: int = 50_000_000
    min_share: float = 0.35
    rate_horizon: float = 1e9
    seed: int = 0
    blas_threads: int | None = None
    keep_on_interrupt: bool = False
    write_seconds: float = 0.0
    warm_start: WarmStart | None = field(default=None, repr=False, compare=False)
    clock: Callable[[], float] = field(default=time.perf_counter, repr=False, compare=False)

    def solve(self, model: POMDP, progress: Callable[[float, float, float], None] | None = None,
              upper: np.ndarray | None = None, groups: CornerGroups | None = None,
              started: float | None = None, points: tuple[np.ndarray, np.ndarray] | None = None,
              relaxed: RelaxedQ | None = None, stopped: Callable[[], int] | None = None) -> SolveResult:
        """Solve ``model``; ``progress(seconds, lower, upper)`` is called after each step; ``upper``: a known
        upper bound on Q* (actions x states) to start the informed bound from, ``groups``: corner groups of
        the upper bound (the lumped model's :func:`~.warm_start.solver_bounds` gives both);
        ``started``: the ``clock()`` value the time limit counts from (default: now), e.g. before building them;
        ``points``: beliefs (N, S) and upper values at them (N,), stored as sawtooth points where below the
        bound; ``relaxed``: Q-values of a relaxed problem (:class:`~.upper.RelaxedQ`), one more upper bound
        at every belief (the lumped model's :func:`~.warm_start.solver_start` gives all). With a ``warm_start``
        in the configuration and no ``upper`` given, they come from it, within its share of the time limit;
        ``stopped()`` non-zero (an interrupt the caller deferred) cuts it short and raises
        :class:`~planner.interrupts.Interrupted` before the solver starts (nothing to keep yet)."""
        start = self.clock() if started is None else started
        if self.warm_start is not None and upper is None:
            stopped = stopped if stopped is not None else (lambda: 0)
            options = self.warm_start.options(self.clock, start, self.time_limit, stopped)
            if stopped():
                raise Interrupted(stopped())
            upper, groups, points, relaxed = (options["upper"], options["groups"], options["points"],
                                              options["relaxed"])
        m = Tables(model)
        if upper is not None and np.shape(upper) != (m.A, m.S):
            raise ValueError(f"the starting upper bound is {np.shape(upper)}, the model needs {(m.A, m.S)}")
        with limited_blas(blas_threads(m, self.blas_threads)):
            return self._solve(m, np.asarray(model.initial, dtype=float), start, progress, upper, groups,
                               (points, relaxed))

    def _solve(self, m: Tables, b0: np.ndarray, start: float, progress, start_upper=None,
               groups: CornerGroups | None = None, known=None) -> SolveResult:
        if not self.keep_on_interrupt:
            return self._improve(m, b0, start, progress, start_upper, groups, self.clock, known)
        with deferred_interrupts() as pending:
            # An interrupt makes the clock run out: every stopping rule, in the set-up too, then holds at once.
            result = self._improve(m, b0, start, progress, start_upper, groups,
                                   lambda: math.inf if pending() else self.clock(), known)
            return replace(result, seconds=self.clock() - start, interrupted=pending())

    def _improve(self, m: Tables, b0: np.ndarray, start: float, progress, start_upper, groups,
                 clock: Callable[[], float], known=None) -> SolveResult:
        """Set up both bounds, then trials and sweeps until a stopping rule holds (class docstring)."""
        limit = math.inf if self.time_limit is None else self.time_limit
        lower: LowerBound | None = None

        def out_of_time() -> bool:  # the limit, less the time writing the policy so far will take
            kept = self.write_seconds * (lower.n * m.S if lower is not None else 0)
            return clock() - start + kept >= limit

        # The set-up gets a quarter of the time left (what came before, a warm start, counted): the blind
        # policies an eighth (then constant floors), the informed bound the rest (any iterate is an upper bound).
        now = self.clock()
        left = start + limit - now if math.isfinite(limit) else math.inf
        deadline = now + left / 4 if math.isfinite(limit) else math.inf
        lower = LowerBound.blind(m, now + left / 8 if math.isfinite(limit) else math.inf, clock)
        Q = fast_informed_bound(m, self.informed_tolerance, self.informed_sweeps, deadline, start=start_upper,
                                clock=clock)
        points, relaxed = known if known is not None else (None, None)  # what solve() was given
        upper = UpperBound(Q, np.random.default_rng(self.seed).random(m.S), groups, relaxed)
        if points is not None:  # known upper values at beliefs: kept where they lie below the bound
            _add_points(upper, *points, self.prune_points_at, lambda: clock() >= deadline)
        beliefs = BeliefSet(m.S)
        beliefs.add(b0[None], np.ones(1))
        sweeps = sweep_rounds(m, lower, beliefs, Q, self.theta, self.theta_factor, self.sweeps_per_round,
                              self.chunk, self.belief_memory, stop=out_of_time)
        sharing = WorkSharing(self.min_share, self.rate_horizon)
        iterations, pruned_at = 0, 0  # pruned_at: upper-bound points after the last pruning
        lb, ub = lower.value(b0), upper.value(b0)
        blind = lb  # the blind policies' value at b0 (or the floor): what a policy must beat to be worth keeping
        history = [(self.clock() - start, lb, ub)]
        at_b0 = None  # the bounds at b0 as the trials need them (bounds_at), while still current
        for _ in range(self.group_passes if groups is not None else 0):
            if ub - lb <= self.precision or clock() >= deadline:
                break
            backup_groups(m, lower, upper, lambda: clock() >= deadline)  # within the set-up's quarter
            before, (lb, ub) = ub, (lower.value(b0), upper.value(b0))
            history.append((self.clock() - start, lb, ub))
            if before - ub < self.informed_tolerance:
                break
        while (ub - lb > self.precision and not out_of_time()
               and (self.max_iterations is None or iterations < self.max_iterations)):
            process = sharing.choose()
            if process == "sweeps":
                work = float(next(sweeps))
            else:
                iterations += 1
                # Trials aim at a fraction of the current gap, so early trials stay shallow (HSVI's epsilon).
                epsilon = max(self.precision, self.gap_fraction * (ub - lb))
                work = trial(m, b0, lower, upper, beliefs, epsilon, iterations % self.lower_trial_every == 0,
                             self.max_depth, stop=out_of_time, start=at_b0)
                if groups is not None and iterations % self.group_every == 0:
                    work += backup_groups(m, lower, upper, out_of_time)
                if upper.n >= max(self.prune_points_at, 2 * pruned_at):
                    upper.prune(stop=out_of_time)
                    pruned_at = upper.n
            gap = ub - lb
            # The sweeps change only the lower bound: the upper one at b0 is the same number as before.
            at_b0 = bounds_at(b0, lower, upper, None if process == "trials" else ub)
            lb, ub = at_b0[0], at_b0[2]
            sharing.record(process, gap - (ub - lb), work)
            history.append((self.clock() - start, lb, ub))
            if progress is not None:
                progress(*history[-1])
        return SolveResult(lower.policy(), lb, ub, self.clock() - start, iterations, history, blind_lower=blind)


def _add_points(upper: UpperBound, B: np.ndarray, values: np.ndarray, prune_at: int, late: Callable[[], bool],
                block: int = 256) -> None:
    """Store the known upper values at the beliefs ``B`` (N, S) where they lie below ``upper``, ``block`` beliefs
    at a time until ``late()``: the points are optional (the bound holds without them), so the rest are left
    out once the set-up's time is up. Cost: O(N S (A + points)) for the bounds at B."""
    for first in range(0, len(B), block):
        if late():
            break
        part, known = B[first:first + block], values[first:first + block]
        keep = known < upper.at(part) - 1e-12
        for b, value in zip(part[keep], known[keep]):
            upper.update(b, float(value))
    if upper.n >= prune_at:
        upper.prune(stop=late)
