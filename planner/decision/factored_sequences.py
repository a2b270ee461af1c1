"""The full sequences of the factored decision model (paper Sec. V) and one true intention along one: what a
simulator and a session's scripted operator ask of it. :class:`FactoredSequences` holds the methods; the model
(:class:`~planner.decision.factored_model.FactoredIntentionModel`) inherits them, with the tables they read
(``paths``, ``class_target``, ``class_fraction``, ``class_operation``, ``class_action``, ...).

A sequence is numbered by rank: at each state its classes in the edges' order, each covering the ``N(target)``
sequences through it (exact integers), so rank ``k`` is found without enumerating the sequences.
"""
from __future__ import annotations

import numpy as np

from ..defaults import STAY
from ..errors import PlannerError

__all__ = ["FactoredSequences"]


class FactoredSequences:
    """The model's full sequences (by rank, or drawn from the initial belief) and the flat model's transition
    along one of them (by position), over the factored model's tables."""

    def sequence(self, rank: int) -> list[int]:
        """The state edges of full sequence number ``rank`` (0 <= rank < :attr:`n_sequences`; the order is the
        edges' order at each state). Cost: O(length x out-degree)."""
        rank = int(rank)
        if not 0 <= rank < self.n_sequences:
            raise PlannerError(f"sequence {rank} does not exist: there are {self.n_sequences} full sequences")
        edges, state = [], self.plan.states.initial
        while state != self.final_state:
            for c in self._sequence_options(state):
                size = int(self.paths[self.class_target[c]])
                if rank < size:
                    edges.append(int(c))
                    state = int(self.class_target[c])
                    break
                rank -= size
        return edges

    def sample_sequence(self, rng: np.random.Generator) -> list[int]:
        """A full sequence drawn uniformly (the initial belief), as state edges. Cost: O(length x out-degree)."""
        edges, state = [], self.plan.states.initial
        while state != self.final_state:
            options = self._sequence_options(state)
            p = self.class_fraction[options]
            c = int(rng.choice(options, p=p if self.base_part is None or state != self.plan.states.initial
                               else p / p.sum()))
            edges.append(c)
            state = int(self.class_target[c])
        return edges

    def _sequence_options(self, state: int) -> np.ndarray:
        """The classes a full sequence may take at ``state``: the allowed first ones at the initial state."""
        return self.initial_classes if state == self.plan.states.initial else self.classes_from(state)

    def sequence_operations(self, edges: list[int]) -> list[int]:
        """The operations of a path of state edges, in order."""
        return [int(self.class_operation[e]) for e in edges]

    def describe_operations(self, edges: list[int]) -> list[str]:
        """:meth:`sequence_operations` as text (``ink+cartridge``, ...)."""
        return [self.plan.andor.describe(o) for o in self.sequence_operations(edges)]

    # --- one true intention: a full sequence's edges and how far along it the world is ------------------

    def position_transition(self, path: list[int], position: int, action: int) -> list[tuple[int, float]]:
        """T of the intention ``path[position:]`` (``path``: state edges to the final state) under ``action``,
        as (next position, probability) pairs: the flat model's transition row, by position along ``path``."""
        end = len(path)
        if position >= end:
            return [(end, 1.0)]
        if action == self.wait:
            return [(position, STAY), (position + 1, 1 - STAY)]
        if self.class_action[path[position]] != action:
            return [(position, 1.0)]
        if position + 1 == end:
            return [(end, 1.0)]
        return [(position + 1, STAY), (position + 2, 1 - STAY)]

    def sample_position(self, path: list[int], position: int, action: int, rng: np.random.Generator) -> int:
        """The next position along ``path`` drawn from :meth:`position_transition` (a simulator's step)."""
        options = self.position_transition(path, position, action)
        return options[0][0] if len(options) == 1 else options[int(rng.random() < options[1][1])][0]

    def sample_observation(self, path: list[int], position: int, rng: np.random.Generator) -> int:
        """An observation drawn from the table of the state the world is in (blank included)."""
        state = int(self.class_source[path[position]]) if position < len(path) else self.final_state
        observations, p = self.state_observations(state)
        return int(rng.choice(observations, p=p))
