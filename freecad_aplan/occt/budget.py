"""The exact engine's time budget per pair of parts, its progress lines, and the culling of pairs whose faces
are clearly apart."""
from __future__ import annotations

import time
from typing import Callable

import numpy as np

from .solids import bounding_box

SHOWN = 10  # undecided pairs told one per line; the others in one line

__all__ = ["PairClock", "face_boxes", "face_gap", "sweep_meets"]


class PairClock:
    """The work OCCT spends per unordered pair of parts, against per-pair bounds and an overall time limit,
    and progress reports.

    A pair is *undecided* when its work would go beyond its bounds: ``steps`` OCCT operations (a distance,
    a common, one prism's test: counted at each :meth:`exhausted` that lets one start; None: no bound), or
    ``budget`` CPU seconds (``budgets[{a, b}]`` for the pair of ids ``a``, ``b``), or when ``time_limit``
    seconds of ``clock`` (CPU seconds of this process by default, as the budgets, so that a machine loaded
    by other work does not leave pairs undecided; injectable for tests) have passed since the clock was made: the engine
    stops working on it, reports it and goes on with the others (after the time limit, every pair left is
    undecided at once). OCCT's booleans cannot be interrupted, so the bounds are checked between them: a
    pair may overrun by one boolean (the weight and triangle bounds below keep that boolean bounded). CPU time of this process (OCCT's booleans run in it, on one core), so
    that a loaded machine does not make pairs undecided; ``progress`` receives a line at most every
    ``every`` seconds of wall clock (and the last of each phase).

    So that no single call overruns, a pair is also undecided at once, before any call, when one of its parts
    is *heavy* (:attr:`heavy`: part index -> why, set from :func:`~.complexity.shape_weight` over
    :data:`~planner.defaults.OCCT_FACE_WEIGHT`), or when a sweep it needs is over its bound (the ``reason``
    of :meth:`give_up`); the warnings then give that reason instead of the budget.
    """

    def __init__(self, ids: list[str], budget: float, budgets: dict | None = None,
                 progress: Callable[[str], None] | None = None, every: float = 5.0, steps: int | None = None,
                 time_limit: float | None = None, clock: Callable[[], float] = time.process_time) -> None:
        self.ids, self.budget, self.progress, self.every = ids, budget, progress, every
        self.steps, self.time_limit, self.clock = steps, time_limit, clock
        index = {part_id: k for k, part_id in enumerate(ids)}
        self.budgets = {}
        for pair, seconds in (budgets or {}).items():
            a, b = (index.get(p) for p in pair)
            if a is not None and b is not None:
                self.budgets[min(a, b), max(a, b)] = float(seconds)
        self.spent: dict[tuple[int, int], float] = {}
        self.work: dict[tuple[int, int], int] = {}
        self.undecided: dict[tuple[int, int], list[str]] = {}
        self.counts = {"far": 0, "far_faces": 0, "exact": 0, "sweep_candidates": 0, "sweep_exact": 0}
        self.timed_out = False
        self.heavy: dict[int, str] = {}  # parts no OCCT call is made on (why), see the class docstring
        self.reasons: dict[tuple[int, int], str] = {}  # why a pair was left undecided, when not its budget
        self.selected: set[tuple[int, int]] | None = None  # the pairs to decide (None: all), by index
        self._current: tuple[tuple[int, int], float] | None = None
        self._start = self.clock()
        self._began = self._last = time.perf_counter()

    def wanted(self, i: int, j: int) -> bool:
        """True when the pair (i, j) is one the engine was asked to decide (:attr:`selected`)."""
        return self.selected is None or self._key(i, j) in self.selected

    def out_of_time(self) -> bool:
        """True once ``time_limit`` seconds of ``clock`` have passed (it stays True)."""
        if not self.timed_out and self.time_limit is not None and self.clock() - self._start >= self.time_limit:
            self.timed_out = True
        return self.timed_out

    def _key(self, i: int, j: int) -> tuple[int, int]:
        return (i, j) if i < j else (j, i)

    def too_heavy(self, i: int, j: int) -> bool:
        """True when part i or part j is :attr:`heavy` (no work is counted)."""
        return i in self.heavy or j in self.heavy

    def exhausted(self, i: int, j: int) -> bool:
        """True when the pair (i, j) has a heavy part, or has used up its steps or its budget (its current
        work included), or the time limit has passed; else one more step of its work is counted."""
        if self.too_heavy(i, j):
            return True
        key = self._key(i, j)
        spent = self.spent.get(key, 0.0)
        if self._current is not None and self._current[0] == key:
            spent += time.process_time() - self._current[1]
        if self.out_of_time() or spent >= self.budgets.get(key, self.budget):
            return True
        if self.steps is not None and self.work.get(key, 0) >= self.steps:
            return True
        self.work[key] = self.work.get(key, 0) + 1
        return False

    def start(self, i: int, j: int) -> None:
        self._current = (self._key(i, j), time.process_time())

    def stop(self) -> None:
        if self._current is not None:
            key, began = self._current
            self.spent[key] = self.spent.get(key, 0.0) + time.process_time() - began
            self._current = None

    def give_up(self, i: int, j: int, what: str, reason: str | None = None) -> None:
        """Record that the pair's ``what`` (contact, obstruction along an axis) was not decided in time, or
        for ``reason`` (a heavy part's is taken from :attr:`heavy`)."""
        self.stop()
        key = self._key(i, j)
        self.undecided.setdefault(key, []).append(what)
        reason = reason or self.heavy.get(i) or self.heavy.get(j)
        if reason and key not in self.reasons:
            self.reasons[key] = reason

    def tick(self, phase: str, done: int, total: int) -> None:
        now = time.perf_counter()
        if self.progress is not None and (now - self._last >= self.every or done == total):
            self._last = now
            self.progress(f"occt: {phase} {done}/{total} ({now - self._began:.0f} s, "
                          f"{len(self.undecided)} pairs undecided)")

    def warnings(self, fallback: str = "counted as touching and blocking") -> list[str]:
        """One line per undecided pair (``fallback``: what its relations are taken to be), and one for the time
        limit when it was reached."""
        shown = sorted(self.undecided.items())[:SHOWN]
        lines = [f"OCCT did not decide {', '.join(whats)} for {self.ids[i]!r} and {self.ids[j]!r}: "
                 f"{self.reasons[i, j]}; {fallback}" if (i, j) in self.reasons else
                 f"OCCT did not decide {', '.join(whats)} for {self.ids[i]!r} and {self.ids[j]!r} within the "
                 f"budget of {self.budgets.get((i, j), self.budget):g} CPU s"
                 f"{'' if self.steps is None else f' and {self.steps} operations'} per pair (spent "
                 f"{self.spent.get((i, j), 0.0):.1f} s, {self.work.get((i, j), 0)} operations"
                 f"{', time limit reached' if self.timed_out else ''}); {fallback}: check this pair "
                 "(or raise --pair-budget, --time-limit)" for (i, j), whats in shown]
        if len(self.undecided) > SHOWN:
            lines.append(f"OCCT left {len(self.undecided) - SHOWN} more pairs undecided: "
                         + ", ".join(f"{self.ids[i]}/{self.ids[j]}" for i, j in sorted(self.undecided)[SHOWN:]))
        if self.timed_out:
            lines.insert(0, f"OCCT reached its time limit of {self.time_limit:g} s: {len(self.undecided)} pairs "
                            f"undecided ({fallback})")
        return lines


def face_boxes(shape) -> np.ndarray:
    """The bounding boxes of ``shape``'s faces, ``(n, 2, 3) float`` (min and max corners)."""
    return np.array([bounding_box(face) for face in shape.Faces], dtype=float).reshape(-1, 2, 3)


def face_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The smallest gap between a box of ``a`` and a box of ``b`` (face boxes, :func:`face_boxes`): a lower
    bound of the distance between the two surfaces (<= 0 when two boxes overlap). Cost O(len(a) len(b))."""
    if len(a) == 0 or len(b) == 0:
        return 0.0
    lo_a, hi_a = a[:, None, 0, :], a[:, None, 1, :]
    lo_b, hi_b = b[None, :, 0, :], b[None, :, 1, :]
    gaps = np.maximum(lo_b - hi_a, lo_a - hi_b).max(axis=2)
    return float(gaps.min())


def sweep_meets(moving: np.ndarray, other: np.ndarray, axis: int, contact: float, depth: float) -> bool:
    """False when the part of face boxes ``moving``, swept along +``axis`` without limit, clearly misses the
    part of face boxes ``other``: no box of ``moving`` overlaps a box of ``other`` by more than ``contact``
    across the axis with the ``other`` box reaching more than ``depth`` beyond its start.

    Sound: a part's sweep is the union of its faces' sweeps (a point inside it lies ahead of one of its
    faces), and a sweep that meets a part meets its boundary (from a point inside, go along the axis until
    leaving the part). Cost O(len(moving) len(other))."""
    if len(moving) == 0 or len(other) == 0:
        return True
    across = [k for k in range(3) if k != axis]
    lo_m, hi_m = moving[:, None, 0, :], moving[:, None, 1, :]
    lo_o, hi_o = other[None, :, 0, :], other[None, :, 1, :]
    overlap = (np.minimum(hi_m, hi_o) - np.maximum(lo_m, lo_o))[..., across].min(axis=2) > contact
    ahead = hi_o[..., axis] > lo_m[..., axis] + depth
    return bool((overlap & ahead).any())

