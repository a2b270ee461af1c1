"""Work sharing between the solver's two processes, by counted work rather than by the clock.

Each process ``p`` (``"sweeps"``, ``"trials"``) has a *rate*: the gap at ``b0`` it closed per unit of work,
both decayed with half-life ``rate_horizon`` units of its own work (``g_p / w_p``; infinite before its first
step). The sweeps' target share of the work is ``r_sweeps / (r_sweeps + r_trials)`` (one half while a rate
is unknown), clamped to ``[min_share, 1 - min_share]``; the next step goes to the sweeps when they are at or
below that share of the work done so far, else to the trials. So each process keeps at least ``min_share``
of the work (up to one step), and the choice depends only on the work, never on the machine's speed.

Cost: O(1) per step.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["PROCESSES", "WorkSharing"]

PROCESSES = ("sweeps", "trials")


@dataclass
class WorkSharing:
    """The scheduler's state (module docstring): ``recent[p] = [decayed gap closed, decayed work]`` and
    ``done[p]``, the work done so far, for each process ``p``."""

    min_share: float = 0.2
    rate_horizon: float = 1e9
    recent: dict = field(default_factory=lambda: {p: [0.0, 0.0] for p in PROCESSES})
    done: dict = field(default_factory=lambda: {p: 0.0 for p in PROCESSES})

    def share(self) -> float:
        """The sweeps' target share of the work, in ``[min_share, 1 - min_share]``."""
        rates = {p: (g / w if w > 0 else np.inf) for p, (g, w) in self.recent.items()}
        total = rates["sweeps"] + rates["trials"]
        share = 0.5 if not np.isfinite(total) or total <= 0 else rates["sweeps"] / total
        return min(max(share, self.min_share), 1 - self.min_share)

    def choose(self) -> str:
        """The process that takes the next step."""
        share = self.share()
        return "sweeps" if self.done["sweeps"] * (1 - share) <= self.done["trials"] * share else "trials"

    def record(self, process: str, closed: float, work: float) -> None:
        """Count a step of ``process`` that closed the gap at ``b0`` by ``closed`` with ``work`` units."""
        decay = 0.5 ** (work / self.rate_horizon)
        gap, spent = self.recent[process]
        self.recent[process] = [gap * decay + closed, spent * decay + work]
        self.done[process] += work
