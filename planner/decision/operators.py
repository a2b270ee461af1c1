"""Simulated operators to measure with: which full sequence the operator does, and whether it changes its mind.

An operator model draws, for each episode, the operator's *plan*: the full sequence it sets out to do (a
flat model's intention number, or a factored model's state edges) and, optionally, a :class:`Switch`: after
``after`` operations (by anyone) it takes another completion from the assembly state it is in. The world of
:mod:`.simulate` and :mod:`.factored_simulate` then plays the plan (the operator's timing and the
observations stay the model's).

- :class:`UniformOperator`: every full sequence equally likely (the paper's operator). Its draws are today's
  ``aplan simulate --random N`` draws on the paper's model, number for number.
- :class:`HabitualOperator`: one given sequence with probability ``strength``, otherwise uniform.
- :class:`ChangingOperator`: a base operator that, with probability ``p`` per episode, switches once, to
  another completion of the state it is in, uniformly among those other than its own, at a point drawn
  uniformly among the *switch points* of its sequence (:func:`switch_points`: the positions 1 to length - 1
  whose state has another completion). So ``p`` is the share of episodes that switch, on any product whose
  sequences have a switch point (a sequence with none does not switch). In the episode the switch comes at the
  first decision step with at least that many operations done (one step may do two, the robot's and the
  operator's: then at the first later state that has another completion, or not at all: ``switched_at`` stays
  None).
- Any of them with ``mistakes`` = q > 0 (``...,mistakes:Q``): at each decision step, with probability q, it
  takes a wrong part and puts it back: the camera sees another non-blank observation than the world's, drawn
  uniformly (:func:`mistaken_observation`), and the assembly does not change. These draws come from a stream
  per episode (:func:`mistake_stream`), so q = 0 plays the same episodes as no mistakes.

Every plan is drawn before the first episode, from the seeded stream (the switches from a stream of their
own, so ``changing:0`` equals its base operator): the operator does not depend on the robot, and two planners
given the same seed face the same sequences and switches. Cost: O(episodes x length x out-degree).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import PlannerError

__all__ = ["Switch", "OperatorPlan", "UniformOperator", "HabitualOperator", "ChangingOperator", "CrossingOperator",
           "crossing_pair", "parse_operator", "switch_intention", "switch_path", "switch_points",
           "mistaken_observation", "mistake_stream", "OPERATOR_SPELLING"]

OPERATOR_SPELLING = ("uniform, habitual:K:STRENGTH, changing:P, mistakes:Q, or a base (uniform or habitual) "
                     "followed by changing and mistakes, comma-separated (habitual:5:0.8,changing:0.1,mistakes:0.05)")


@dataclass(frozen=True)
class Switch:
    """The operator changes its mind at the first decision step with at least ``after`` operations done;
    ``draw`` in [0, 1) picks which other completion of that state it takes (by rank)."""

    after: int
    draw: float


@dataclass(frozen=True)
class OperatorPlan:
    sequence: int | list[int]       # the flat model's intention, or the factored model's state edges
    switch: Switch | None = None


def _is_flat(model) -> bool:
    return hasattr(model, "graph")


def _uniform_sequences(model, count: int, rng: np.random.Generator) -> list:
    """``count`` full sequences drawn uniformly, with exactly today's calls on the paper's model."""
    if _is_flat(model):
        return [int(s) for s in rng.choice(model.full_sequences(), size=count)]
    if model.weights is None:
        return [model.sample_sequence(rng) for _ in range(count)]
    return [_uniform_completion(model, model.plan.states.initial, rng) for _ in range(count)]


def _paper_fractions(model, options: np.ndarray) -> np.ndarray:
    """The paper's choice N(target) / N(state) among ``options`` (normalised: a base part may drop some)."""
    sizes = np.array([float(model.paths[model.class_target[c]]) for c in options])
    return sizes / sizes.sum()


def _uniform_completion(model, state: int, rng: np.random.Generator) -> list[int]:
    edges = []
    while state != model.final_state:
        options = model._sequence_options(state)
        c = int(rng.choice(options, p=_paper_fractions(model, options)))
        edges.append(c)
        state = int(model.class_target[c])
    return edges


class UniformOperator:
    """Every full sequence equally likely, whatever the robot's model assumes."""

    mistakes = 0.0  # the probability per decision step of a wrong part taken (module docstring)

    def plans(self, model, count: int, rng: np.random.Generator, switch_rng: np.random.Generator
              ) -> list[OperatorPlan]:
        return [OperatorPlan(s) for s in _uniform_sequences(model, count, rng)]

    def __repr__(self) -> str:
        return "uniform" + _mistakes(self)


class HabitualOperator:
    """Sequence ``sequence`` (an intention number on the flat model, a rank on the factored one, as
    ``--sequence`` numbers them) with probability ``strength``, otherwise a uniformly drawn one (which may be
    it too: it is done with probability ``strength + (1 - strength) / sequences``)."""

    def __init__(self, sequence: int, strength: float):
        if not 0.0 <= strength <= 1.0:
            raise PlannerError(f"habitual operator: strength {strength!r} is not in [0, 1]")
        self.sequence, self.strength, self.mistakes = int(sequence), float(strength), 0.0

    def plans(self, model, count: int, rng: np.random.Generator, switch_rng: np.random.Generator
              ) -> list[OperatorPlan]:
        habit = self._habit(model)
        follows = rng.random(count) < self.strength
        others = iter(_uniform_sequences(model, int((~follows).sum()), rng))
        return [OperatorPlan(habit if f else next(others)) for f in follows]

    def _habit(self, model):
        if _is_flat(model):
            return model.full_sequence(self.sequence, "habitual operator: sequence")
        if not 0 <= self.sequence < model.n_sequences:
            raise PlannerError(f"habitual operator: sequence {self.sequence} does not exist; on the factored model "
                               f"sequences are numbered by rank, from 0 to {model.n_sequences - 1:,}")
        return model.sequence(self.sequence)

    def __repr__(self) -> str:
        return f"habitual:{self.sequence}:{self.strength:g}" + _mistakes(self)


class ChangingOperator:
    """``base``'s plans; with probability ``p`` an episode's operator switches once, at one of its sequence's
    :func:`switch_points` drawn uniformly (module docstring)."""

    def __init__(self, p: float, base=None):
        if not 0.0 <= p < 1.0:
            raise PlannerError(f"changing operator: probability {p!r} is not in [0, 1)")
        self.p, self.base = float(p), base if base is not None else UniformOperator()
        self.mistakes = 0.0  # its own (parse_operator sets them on the outermost operator, which plays them)

    def plans(self, model, count: int, rng: np.random.Generator, switch_rng: np.random.Generator
              ) -> list[OperatorPlan]:
        plans = self.base.plans(model, count, rng, switch_rng)
        draws = switch_rng.random((count, 3))  # switch?, at which switch point, which other completion
        completions = np.bincount(model.graph.first_state) if _is_flat(model) else None
        out = []
        for plan, (u, v, w) in zip(plans, draws):
            points = switch_points(model, plan.sequence, completions) if u < self.p else []
            if points:
                plan = OperatorPlan(plan.sequence, Switch(points[min(int(v * len(points)), len(points) - 1)],
                                                          float(w)))
            out.append(plan)
        return out

    def __repr__(self) -> str:
        return f"{self.base!r},changing:{self.p:g}" + _mistakes(self)


class CrossingOperator:
    """Two habitual full sequences of a factored model, ``first`` and ``second`` (state edges), that cross: both
    are at the same assembly state after ``position`` operations and go on differently from it. Each episode's
    operator sets out on one of them, 1/2 each, and with probability ``p`` changes its mind at that state, to the
    other's completion (the first one's operations up to the crossing, then the second one's). So an operator
    with two habits who switches between them: its habits learned from its own logs put weight on both
    completions at the crossing and on one at each state after it, so the belief can concentrate on the whole new
    sequence (docs/deviations.md, reading (c)). A step that passes the crossing (the robot's operation and the
    operator's at once) moves the switch to the next state with another completion, as for
    :class:`ChangingOperator`. See :func:`crossing_pair`. Cost: O(count x length x degree)."""

    def __init__(self, first: list[int], second: list[int], position: int, p: float):
        if not 0.0 <= p < 1.0:
            raise PlannerError(f"crossing operator: probability {p!r} is not in [0, 1)")
        self.first, self.second, self.position, self.p = list(first), list(second), int(position), float(p)
        self.mistakes = 0.0

    def plans(self, model, count: int, rng: np.random.Generator, switch_rng: np.random.Generator
              ) -> list[OperatorPlan]:
        second = rng.random(count) < 0.5
        switches = switch_rng.random(count) < self.p
        out = []
        for b, s in zip(second, switches):
            own, other = (self.second, self.first) if b else (self.first, self.second)
            switch = Switch(self.position, completion_draw(model, own, self.position, other)) if s else None
            out.append(OperatorPlan(list(own), switch))
        return out

    def done(self, plan: OperatorPlan) -> list[int]:
        """The sequence the operator of ``plan`` does when nothing jumps over the crossing (an observer)."""
        if plan.switch is None:
            return list(plan.sequence)
        other = self.second if plan.sequence == self.first else self.first
        return list(plan.sequence[:self.position]) + list(other[self.position:])

    def __repr__(self) -> str:
        return f"crossing:{self.p:g}" + _mistakes(self)


def completion_draw(model, path: list[int], position: int, other: list[int]) -> float:
    """The ``draw`` of a :class:`Switch` at ``position`` of ``path`` that :func:`switch_path` turns into
    ``other``'s completion (``other`` at the same state there, with another completion)."""
    total = int(model.paths[model.class_source[path[position]]])
    own, target = _completion_rank(model, path[position:]), _completion_rank(model, other[position:])
    if target == own or total < 2:
        raise PlannerError("crossing operator: the two sequences do not part at the crossing")
    return (target - (target > own) + 0.5) / (total - 1)


def crossing_pair(model, rng: np.random.Generator, tries: int = 400) -> tuple[list[int], list[int], int]:
    """Two full sequences of a factored model that cross (:class:`CrossingOperator`) and the crossing position:
    the first drawn uniformly; the crossing the switch point of it nearest its middle (:func:`switch_points`);
    the second's operations up to the crossing those of a uniformly drawn sequence through that state at that
    position, other than the first's when one is found in ``tries`` draws (else the first's: they share their
    start), and from there another completion of the state, drawn uniformly. Raises a :class:`PlannerError`
    when the first has no switch point (a single sequence from every state). Cost: O(tries x length x degree)."""
    first = model.sample_sequence(rng)
    points = switch_points(model, first)
    if not points:
        raise PlannerError("crossing operator: no state of the sequence has another completion")
    position = min(points, key=lambda q: (abs(2 * q - len(first)), q))
    state = int(model.class_source[first[position]])
    start = first[:position]
    for _ in range(tries):
        drawn = model.sample_sequence(rng)
        if len(drawn) > position and int(model.class_source[drawn[position]]) == state and drawn[:position] != start:
            start = drawn[:position]
            break
    rest = switch_path(model, first, position, float(rng.random()))[position:]
    return first, list(start) + rest, position


def _mistakes(operator) -> str:
    return f",mistakes:{operator.mistakes:g}" if operator.mistakes else ""


def mistake_stream(seed: int, episode: int) -> np.random.Generator:
    """The stream of an episode's mistakes: its own, so that they change nothing else."""
    return np.random.default_rng([seed, 2, episode])


def mistaken_observation(observation: int, n_observations: int, draw: float) -> int:
    """The wrong part's observation: a non-blank one (observation 0 is blank) other than ``observation``,
    picked by ``draw`` in [0, 1); ``observation`` itself when there is no other."""
    others = [z for z in range(1, n_observations) if z != observation]
    return observation if not others else others[min(int(draw * len(others)), len(others) - 1)]


def switch_points(model, sequence, completions: np.ndarray | None = None) -> list[int]:
    """The positions ``1 <= q < length`` of a full sequence (a flat model's intention number, or a factored
    model's state edges) at which the operator can change its mind: the assembly state after ``q`` operations
    has another completion. Position 0 is not one (a change before the first operation is another sequence from
    the start). ``completions``: on the flat model, the intentions per state (``np.bincount`` of the graph's
    ``first_state``; computed when None, O(intentions)). Cost: O(length)."""
    if _is_flat(model):
        if completions is None:
            completions = np.bincount(model.graph.first_state)
        states = model.graph.path(int(sequence))
        return [q for q in range(1, len(states) - 1) if completions[states[q]] >= 2]
    return [q for q in range(1, len(sequence)) if int(model.paths[model.class_source[sequence[q]]]) >= 2]


def switch_intention(first_state: np.ndarray, intention: int, draw: float) -> int:
    """The flat model's intention the operator switches to from ``intention``: another one starting at its
    assembly state (``first_state``: the intention graph's), picked by ``draw`` in [0, 1) (itself when there
    is no other). Cost: O(intentions)."""
    others = np.flatnonzero(first_state == first_state[intention])
    others = others[others != intention]
    return intention if others.size == 0 else int(others[min(int(draw * others.size), others.size - 1)])


def switch_path(model, path: list[int], position: int, draw: float) -> list[int]:
    """``path`` with its completion from ``position`` replaced by another of that state, picked by rank with
    ``draw`` in [0, 1) among the others (``path`` itself when there is no other). Cost: O(length x degree)."""
    state = int(model.class_source[path[position]])
    total = int(model.paths[state])
    if total < 2:
        return list(path)
    own = _completion_rank(model, path[position:])
    rank = min(int(draw * (total - 1)), total - 2)
    rank += rank >= own  # skip its own completion
    return list(path[:position]) + _completion(model, state, rank)


def _completion_rank(model, edges: list[int]) -> int:
    rank = 0
    for c in edges:
        for other in model.classes_from(int(model.class_source[c])):
            if other == c:
                break
            rank += int(model.paths[model.class_target[other]])
    return rank


def _completion(model, state: int, rank: int) -> list[int]:
    edges = []
    while state != model.final_state:
        for c in model.classes_from(state):
            size = int(model.paths[model.class_target[c]])
            if rank < size:
                edges.append(int(c))
                state = int(model.class_target[c])
                break
            rank -= size
    return edges


def parse_operator(text: str):
    """The operator ``text`` spells (:data:`OPERATOR_SPELLING`); a :class:`PlannerError` saying what is wrong."""
    base, changing, mistakes = None, None, None
    for term in str(text).split(","):
        name, *values = term.strip().split(":")
        try:
            numbers = [float(v) for v in values]
        except ValueError:
            numbers = None
        in_order = changing is None and mistakes is None  # the base first, then changing, then mistakes
        if name == "uniform" and not values and base is None and in_order:
            base = UniformOperator()
        elif name == "habitual" and numbers is not None and len(numbers) == 2 and base is None and in_order:
            rank, strength = numbers
            if not (np.isfinite(rank) and rank >= 0 and rank == int(rank)):
                raise PlannerError(f"operator {text!r}: the sequence K of habitual:K:STRENGTH is a number from 0")
            if not (np.isfinite(strength) and 0 <= strength <= 1):
                raise PlannerError(f"operator {text!r}: STRENGTH must be in [0, 1], got {values[1]}")
            base = HabitualOperator(int(rank), strength)
        elif name == "changing" and numbers is not None and len(numbers) == 1 and in_order:
            if not (np.isfinite(numbers[0]) and 0 <= numbers[0] < 1):
                raise PlannerError(f"operator {text!r}: P of changing:P must be in [0, 1), got {values[0]}")
            changing = numbers[0]
        elif name == "mistakes" and numbers is not None and len(numbers) == 1 and mistakes is None:
            if not (np.isfinite(numbers[0]) and 0 <= numbers[0] < 1):
                raise PlannerError(f"operator {text!r}: Q of mistakes:Q must be in [0, 1), got {values[0]}")
            mistakes = numbers[0]
        else:
            raise PlannerError(f"operator {text!r}: use {OPERATOR_SPELLING}")
    operator = base if base is not None else UniformOperator()
    operator = operator if changing is None else ChangingOperator(changing, operator)
    if mistakes is not None:
        operator.mistakes = mistakes
    return operator
