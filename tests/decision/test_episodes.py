"""Which episodes are played (planner.decision.episodes.EpisodeChoice, re-exported as planner.api.EpisodeChoice):
a frozen value, its numbers checked when it is built, read the same by simulate and evaluate."""
from __future__ import annotations

import dataclasses
import math

import pytest

from planner import api
from planner.decision.episodes import EpisodeChoice, evaluate, evaluate_operator
from planner.decision.operators import parse_operator
from planner.defaults import EPISODE_LIMIT, STEP_LIMIT
from planner.errors import PlannerError, UsageError
from planner.validation import InputError


def test_the_choice_is_a_frozen_value_of_plain_numbers():
    choice = EpisodeChoice(sequences=[45, 50], seed=3, max_steps=40)
    assert choice.sequences == (45, 50) and api.EpisodeChoice is EpisodeChoice
    with pytest.raises(dataclasses.FrozenInstanceError):
        choice.seed = 4
    assert choice == EpisodeChoice(sequences=(45, 50), seed=3, max_steps=40.0)  # 40.0 is the whole number 40
    assert hash(choice) == hash(EpisodeChoice(sequences=(45, 50), seed=3, max_steps=40))
    assert EpisodeChoice(random=5, operator_model=parse_operator("changing:0.3")).random == 5


@pytest.mark.parametrize("fields, message", [
    ({"max_steps": 0}, f"episodes: max_steps: must be a whole number at least 1 and at most {STEP_LIMIT:,}, got 0"),
    ({"max_steps": 2.5}, "episodes: max_steps: must be a whole number"),
    ({"random": 0}, f"episodes: random: must be a whole number at least 1 and at most {EPISODE_LIMIT:,}, got 0"),
    ({"random": math.nan}, "episodes: random: must be a whole number"),
    ({"seed": -1}, "episodes: seed: must be a whole number"),
    ({"seed": math.inf}, "episodes: seed: must be a whole number"),
    ({"sequences": (3, -2)}, "episodes: --sequence: must be a whole number"),
    ({"sequences": ("x",), "what": "sequence"}, "episodes: sequence: must be a whole number"),
])
def test_a_number_out_of_range_is_refused_when_the_choice_is_built(fields, message):
    with pytest.raises(InputError, match="^" + message.replace(".", r"\.").replace("(", r"\(")):
        EpisodeChoice(**fields)


@pytest.mark.parametrize("fields, message", [
    ({"random": True}, "episodes: random must be a whole number, got True"),
    ({"every": 1}, "episodes: every must be True or False, got 1"),
    ({"operator": "fast"}, "episodes: unknown operator 'fast'; use one of turns, model"),
    ({"every": True, "random": 3}, "episodes: give the listed sequences, every one or random ones, not several"),
    ({"sequences": (45,), "every": True}, "not several"),
])
def test_choices_that_do_not_go_together_are_usage_errors(fields, message):
    with pytest.raises(UsageError, match=message):
        EpisodeChoice(**fields)


def test_an_operator_model_draws_random_sequences_only():
    with pytest.raises(PlannerError, match=r"--operator-sequence draws the sequences the operator does: give "
                                           r"--random N \(not --sequence or --all\)"):
        EpisodeChoice(every=True, operator_model=parse_operator("uniform"))


def test_evaluation_needs_the_number_of_episodes():
    model = api.decision_model("pen")
    with pytest.raises(UsageError, match="evaluate draws its episodes from the initial belief"):
        evaluate(model, None, EpisodeChoice())
    with pytest.raises(UsageError, match="evaluate_operator plays an operator model"):
        evaluate_operator(model, None, EpisodeChoice(random=3))
    with pytest.raises(PlannerError, match="simulate needs a PRODUCT"):
        api.simulate(model.pomdp, None, EpisodeChoice())  # a file's POMDP names no sequences
