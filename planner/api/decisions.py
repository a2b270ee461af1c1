"""Stage 5 of the API: who decides in a session, a simulation or an evaluation: the offline policy on the flat model
(the paper's), a policy over the lumped model's classes, or the online planner on the factored model (paper Sec. V)."""
from __future__ import annotations

import os

from ..assembly.guards import SizeLimits
from ..assembly.intentions import count_intentions
from ..assembly.plan import Plan
from ..decision.factored_model import FactoredIntentionModel, factored_model
from ..decision.orders import prior_inputs
from ..decision.intention_model import flat_model_bytes, flat_model_fits, intention_model
from ..decision.budget import check_online_memory, check_parallel_memory, online_limits
from ..decision.episodes import evaluate, evaluate_operator, simulate
from ..decision.online import OnlinePlanner
from ..decision.policy import AlphaVectorPolicy, PolicyError, read_policy
from ..defaults import DECISION_TIME, INTENTION_LIMIT, ONLINE_EXPANSIONS
from ..errors import PlannerError, UsageError, gib
from ..product import Product

from .models import check_parallel_flat
from ..decision.step_observations import JOIN, of_step
from .plans import _decidable, base_part_of, plan_of
from .policies import policy_for
from .specs import PLANNERS, ModelSpec, PlannerChoice

__all__ = ["PLANNERS", "online_planner", "choose_planner", "decision_maker", "simulate", "evaluate",
           "evaluate_operator", "check_cell_observe"]


def online_planner(model: FactoredIntentionModel, decision_time: float | None = DECISION_TIME,
                   expansions: int | None = None, lower: AlphaVectorPolicy | None = None) -> OnlinePlanner:
    """The online planner on ``model``: at most ``decision_time`` seconds and ``expansions`` expansions per
    decision. ``expansions`` alone (``decision_time`` None) is a fixed amount of work: the same actions on any
    machine. ``lower``: an offline policy over the model's classes whose value the search starts from."""
    if decision_time is None and expansions is None:
        raise PlannerError("the online planner needs a decision time or a number of expansions")
    return OnlinePlanner(model, expansions if expansions is not None else ONLINE_EXPANSIONS, decision_time,
                         lower=lower)


def check_cell_observe(observe: str, keyboard: bool = False) -> None:
    """A session's camera (the parts tray) reports the loose parts and tool of a step, not the pieces joined:
    ``--observe join`` (their alphabet) is for the keyboard, where a person tells which pieces were joined, and
    for simulated worlds (``aplan simulate/evaluate --world camera``), until a camera that sees the pieces is
    built. A :class:`UsageError` naming the fix otherwise."""
    if observe == JOIN and not keyboard:
        raise UsageError("--observe join needs a camera that sees the pieces being joined, and a session's camera "
                         "(the parts tray) reports the loose parts and tool only: use --observe step (or --model "
                         "camera), --keyboard (a person types which pieces were joined), or simulate the join camera "
                         "with aplan simulate --world camera --observe join (docs/camera.md)")


def check_step_planner(observe: str, planner: str, policy) -> None:
    """Observations of the step (``--observe step``) are the online planner's alone, without a policy: the flat
    model and the lumped POMDP (which policy files and the offline solver are of) hold observations of the state
    reached, and a policy of theirs is no lower bound under a camera's. A :class:`PlannerError` naming the fix."""
    if of_step(observe) and (planner != "online" or policy):
        what = "--policy" if policy else "--planner offline"
        raise PlannerError(f"--observe {observe} is decided by the online planner alone: {what} is a policy of the "
                           "paper's observations (of the state reached), no bound under a camera's; leave out "
                           f"{what}, or --observe {observe}")


def choose_planner(plan: Plan, planner: str | None, policy: str | os.PathLike | None,
                   limit: int = INTENTION_LIMIT, base_part: str | None = None,
                   limits: SizeLimits = SizeLimits()) -> tuple[str, str | None]:
    """``offline`` or ``online``, and why when it was not asked for. ``planner`` None: offline with a policy
    file, else online (no policy to follow); a flat model of more than ``limit`` intentions or past
    ``limits.memory`` is never built: offline then needs a policy over the lumped model's classes, and without
    one the online planner decides."""
    if planner is not None and planner not in PLANNERS:
        raise PlannerError(f"unknown planner {planner!r}; use one of {', '.join(PLANNERS)}")
    if planner is not None:
        return planner, None
    if policy:
        return "offline", None
    intentions = count_intentions(plan.states, base_part=base_part)
    if not flat_model_fits(plan, limits.memory, limit, intentions):
        needed = flat_model_bytes(plan, intentions)
        passed = (f"about {gib(needed)}, past the memory budget of {gib(limits.memory)}" if needed > limits.memory
                  else f"past the intention limit of {limit:,}")
        return "online", (f"the flat model would hold {intentions:,} intentions ({passed}) and no --policy was "
                          "given: using the online planner")
    return "online", "no --policy: using the online planner"


def decision_maker(product: str | os.PathLike | Product | Plan, spec: ModelSpec = ModelSpec(),
                   choice: PlannerChoice = PlannerChoice()):
    """The model, the policy and a note (what was chosen and why, or None) that a session, a simulation or an
    evaluation runs on, for the model ``spec`` describes (:class:`~planner.api.specs.ModelSpec`) and the
    planner ``choice`` asks for (:class:`~planner.api.specs.PlannerChoice`):

    - online: the factored model and :func:`online_planner` (with ``choice.policy``, a policy over the classes,
      as the lower bound it starts from);
    - offline with a policy over the lumped model's classes: the factored model and that policy;
    - offline otherwise: the flat model of Alg. 3 (refused above ``choice.limit`` intentions, naming
      ``--planner online``) and the policy file, or the built-in solver's policy after ``choice.time_limit``
      seconds.

    The policy file is read within ``spec.inputs``; ``spec.habits`` and ``spec.deviations`` go into every
    model; ``spec.parallel`` is on the classes only: with it the flat model is refused
    (:func:`~planner.api.models.check_parallel_flat`).
    """
    limits, policy = spec.limits, choice.policy
    plan = product if isinstance(product, Plan) else \
        _decidable(plan_of(product, spec.technical, online_limits(limits)))
    base_part = base_part_of(plan, spec.base_part)
    weights, orders = prior_inputs(plan, spec.habits)
    chosen, note = choose_planner(plan, choice.planner, policy, choice.limit, base_part, limits)
    check_step_planner(spec.observe, chosen, policy)

    def factored() -> FactoredIntentionModel:
        check_online_memory(plan, limits.memory)
        if spec.parallel:
            check_parallel_memory(plan, limits.memory, spec.parallel)
        return factored_model(plan, spec.rewards, spec.discount, base_part, weights, spec.parallel, spec.deviations,
                              orders, spec.observe)

    if chosen == "online":
        model = factored()
        lower = read_policy(policy, limits=spec.inputs) if policy else None
        return model, online_planner(model, choice.decision_time, choice.expansions, lower), note
    intentions = count_intentions(plan.states, base_part=base_part)
    vectors = read_policy(policy, limits=spec.inputs) if policy else None
    if vectors is not None:
        # the factored model's classes: one per state edge (of the orders' augmented graph), and finished
        classes = (plan if orders is None else orders.plan).states.n_edges + 1
        length = vectors.alphas.shape[1]
        if length not in (intentions, classes):
            raise PolicyError(f"{policy}: vectors of length {length:,}, but this product's model has {intentions:,} "
                              f"intentions (flat) and {classes:,} classes (lumped): the policy belongs to "
                              "another model (check the product, --technical and --base-part)")
        if length == classes and length != intentions:
            lumped = factored()
            vectors.check_sizes(lumped.n_classes, len(lumped.actions), str(policy))
            return lumped, vectors, None
    check_parallel_flat(spec.parallel, "--planner offline")
    # Past the limits this raises, with the estimate and the options (--planner online among them).
    model = intention_model(plan, spec.rewards, spec.discount, limit=choice.limit, base_part=base_part,
                            max_bytes=limits.memory, weights=weights, deviations=spec.deviations, orders=orders)
    if vectors is not None:
        vectors.check(model.pomdp, str(policy))
        return model, vectors, note
    vectors, result = policy_for(model, None, choice.time_limit)
    note = (f"no --policy: solved for {result.seconds:.1f} s, lower bound {result.lower_bound:.5f}, upper "
            f"bound {result.upper_bound:.5f}")
    return model, vectors, note
