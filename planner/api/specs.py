"""The values a front end builds once from its input and passes down the API's stages: which decision model a
product gets (:class:`ModelSpec`), who decides on it (:class:`PlannerChoice`) and which episodes a simulation or an
evaluation plays (:class:`~planner.decision.episodes.EpisodeChoice`, defined beside the simulator that reads it).

The command line builds them from its options (:func:`planner.cli.options.model_spec_from`,
:func:`planner.cli.options.planner_choice_from`, :func:`planner.cli.options.episode_choice_from`), the workbench
from its analysis and its panels' values; the stages read them and
never the front end's arguments, so one ``aplan session`` turns its options into a model once, however many
levels it runs.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

from ..assembly.guards import SizeLimits
from ..decision.deviations import Deviations
from ..decision.episodes import EpisodeChoice
from ..decision.habits import Habits
from ..decision.intention_model import Rewards
from ..decision.step_observations import STATE
from ..defaults import DECISION_TIME, DISCOUNT, INTENTION_LIMIT, POLICY_TIME_LIMIT
from ..errors import PlannerError
from ..validation import InputLimits

__all__ = ["ModelSpec", "PlannerChoice", "EpisodeChoice", "PLANNERS"]

#: Who decides: ``offline`` follows a policy (a file, or the solver's), ``online`` searches at every decision.
PLANNERS = ("offline", "online")


@dataclass(frozen=True)
class ModelSpec:
    """The decision model of Alg. 3 a product is given, and the budgets it is built and read within.

    ``technical``: ``True``/``False`` switches every technical constraint on/off, None keeps the file's;
    ``rewards``, ``discount``: Alg. 3's; ``base_part``: only the sequences whose first operation joins it (paper
    Sec. V; ``"auto"``: the most connected part, resolved by :func:`~planner.api.plans.base_part_of`), None for
    every sequence; ``limits``: the plan's and the model's size limits; ``inputs``: the limits model, policy and
    log files are read within; ``habits`` (:mod:`~planner.decision.habits`) and ``deviations`` (change of mind
    and mistakes, :mod:`~planner.decision.deviations`): None for the paper's model; ``parallel``: the parallel
    model (docs/parallel.md; on the classes only); ``observe``: ``"state"`` (the paper's observations) or
    ``"step"`` (a camera's, :mod:`~planner.decision.step_observations`; the online planner only). Cost: a few
    fields, compared by value.
    """

    technical: bool | None = None
    rewards: Rewards = field(default_factory=Rewards)
    discount: float = DISCOUNT
    base_part: str | None = None
    limits: SizeLimits = field(default_factory=SizeLimits)
    inputs: InputLimits = field(default_factory=InputLimits)
    habits: Habits | None = None
    parallel: bool | str = False
    deviations: Deviations | None = None
    observe: str = STATE  # what an observation depends on (planner/decision/step_observations.py)


@dataclass(frozen=True)
class PlannerChoice:
    """Who decides in a session, a simulation or an evaluation (:func:`~planner.api.decisions.decision_maker`).

    ``planner``: ``offline``, ``online`` or None (offline with a ``policy`` file, else online:
    :func:`~planner.api.decisions.choose_planner`); ``policy``: a ``.policy`` file (over intentions or the
    lumped model's classes; with the online planner, the lower bound its search starts from);
    ``decision_time`` (seconds) and ``expansions`` per online decision (``expansions`` alone: a fixed amount of
    work, the same actions on any machine); ``time_limit``: the offline solver's seconds without a policy file;
    ``limit``: the flat model's intentions at most.
    """

    planner: str | None = None
    policy: str | os.PathLike | None = None
    decision_time: float | None = DECISION_TIME
    expansions: int | None = None
    time_limit: float = POLICY_TIME_LIMIT
    limit: int = INTENTION_LIMIT

    def __post_init__(self) -> None:
        if self.planner is not None and self.planner not in PLANNERS:
            raise PlannerError(f"unknown planner {self.planner!r}; use one of {', '.join(PLANNERS)}")
