"""The command line's option bundles (planner/cli/options/, issue 24): each kind of argument is read into one
value, built once per command: the decision model into a ModelSpec, who decides into a PlannerChoice, the episodes
played into an EpisodeChoice."""
from __future__ import annotations

import pytest

from planner import api
from planner.cli import build_parser
from planner.cli import options
from planner.decision.deviations import Deviations
from planner.decision.intention_model import Rewards


def _args(*argv: str):
    return build_parser().parse_args(list(argv))


def test_the_model_bundle_reads_into_one_spec():
    args = _args("simulate", "pen", "--base-part", "--switch", "0.1", "--mistakes", "0.05", "--discount", "0.9",
                 "--reward-wait", "-1", "--no-technical", "--max-memory", "2")
    spec = options.model_spec_from(args)
    assert spec == api.ModelSpec(technical=False, rewards=Rewards(wait=-1.0), discount=0.9, base_part="auto",
                                 limits=options.limits_from(args), inputs=options.inputs_from(args),
                                 deviations=Deviations(0.1, 0.05))
    assert spec.limits.memory == 2 * 2 ** 30


def test_model_paper_turns_the_extensions_off():
    spec = options.model_spec_from(_args("simulate", "pen", "--switch", "0.1", "--parallel", "--model", "paper"))
    assert spec.deviations is None and spec.parallel is False and spec.habits is None


def test_the_planner_bundle_reads_into_one_choice():
    assert options.planner_choice_from(_args("simulate", "pen", "--planner", "online", "--expansions", "30")) == \
        api.PlannerChoice("online", None, None, 30)
    default = options.planner_choice_from(_args("evaluate", "pen"))
    assert default == api.PlannerChoice() and default.planner is None  # chosen by choose_planner


def test_the_episode_bundle_reads_into_one_choice():
    """simulate's --sequence/--all/--random and --operator, evaluate's --episodes (drawn at random), both commands'
    --seed, --max-steps and --operator-sequence: one EpisodeChoice."""
    assert options.episode_choice_from(_args("simulate", "pen", "--sequence", "45", "50", "--operator", "turns",
                                             "--seed", "3", "--max-steps", "40")) == \
        api.EpisodeChoice(sequences=(45, 50), seed=3, max_steps=40, operator="turns")
    assert options.episode_choice_from(_args("simulate", "pen", "--all")) == api.EpisodeChoice(every=True)
    played = options.episode_choice_from(_args("evaluate", "pen", "--episodes", "20", "--operator-sequence",
                                               "changing:0.2"))
    assert (played.random, played.operator, repr(played.operator_model)) == (20, "model", "uniform,changing:0.2")
    assert options.episode_choice_from(_args("evaluate", "pen")).random == 1000  # the default --episodes
    with pytest.raises(SystemExit) as refused:  # numpy seeds from 0: a usage error, not a traceback
        _args("simulate", "pen", "--seed", "-1")
    assert refused.value.code == 2


def test_the_product_bundle_is_one_set_of_options_for_stats_intentions_and_sequence():
    def offered(command: str) -> set[str]:
        parser = build_parser()
        sub = next(a for a in parser._subparsers._group_actions if a.choices).choices[command]
        return set(sub._option_string_actions)

    bundle = {"--technical", "--base-part", "--subassemblies", "--max-components", "--level", "--fasteners",
              "--interlocks", "--support-contacts", "--group", "--exclude", "--max-subassemblies", "--max-memory"}
    for command in ("stats", "intentions", "sequence"):
        assert bundle <= offered(command), command
