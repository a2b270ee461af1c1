"""The planner's application interface: what every front end (the ``aplan`` command line, the FreeCAD
workbench, batch jobs, user scripts) does with a product, in one place.

Front ends only parse their input and show results; the steps of the method live here, each a plain function:

1. :func:`resolve_product`: a PRODUCT argument (a product file, a bundle folder, a CAD file read through
   a plugin, or an embedded example) -> :class:`~planner.product.Product`;
2. :func:`plan_statistics_of`: the plan of a product and its figures (``aplan stats``);
3. :func:`decision_model` / :func:`lumped_model` / :func:`load_model` / :func:`save_model`: the decision model
   of Alg. 3 (over intentions, or lumped over the factored model's classes), or a POMDP read from a file, and
   writing it as POMDPX or ``.pomdp``;
4. :func:`solve`, :func:`policy_for`: a policy from a solver (the built-in point-based one, or SARSOP);
5. :func:`simulate`, :func:`evaluate`: episodes of an operator against a policy.

>>> from planner import api
>>> model = api.decision_model("pen")
>>> model.pomdp.n_states, model.pomdp.n_actions, model.pomdp.n_observations
(69, 22, 12)
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .assembly.intentions import most_connected_part
from .assembly.plan import Plan, make_plan
from .assembly.stats import PlanStatistics, plan_statistics
from .decision.intention_model import IntentionModel, Rewards, intention_model
from .decision.io.cassandra import read_cassandra, write_cassandra
from .decision.io.pomdpx import read_pomdpx, write_pomdpx
from .decision.lumped_model import LumpedModel
from .decision.lumped_model import lumped_model as build_lumped_model
from .decision.policy import AlphaVectorPolicy, read_policy
from .decision.pomdp import POMDP
from .decision.simulate import Episode, evaluate_policy, simulate_episode
from .decision.solvers import PointBasedSolver, SolveResult
from .defaults import DISCOUNT, POLICY_TIME_LIMIT, SOLVE_PRECISION, SOLVE_TIME_LIMIT
from .errors import PlannerError, UnknownProductError
from .product import Product, load_product
from .product.examples import EXAMPLES, example_path

__all__ = ["resolve_product", "plan_of", "plan_statistics_of", "decision_model", "lumped_model", "load_model",
           "save_model",
           "tables", "MODEL_SUFFIXES", "SOLVER_ENGINES", "solve", "policy_for", "simulate", "evaluate"]

MODEL_SUFFIXES = (".pomdpx", ".pomdpx.gz", ".pomdp")
SOLVER_ENGINES = ("builtin", "sarsop")

Model = IntentionModel | LumpedModel | POMDP


def resolve_product(argument: str | os.PathLike) -> Product:
    """Load PRODUCT: a product file, a bundle folder, a CAD file a plugin reads (``.FCStd``, STEP: through
    FreeCAD), or the name of an embedded example (``pen``).

    A bundle whose geometry has not been analysed yet is analysed in memory with the mesh engine.
    """
    from .geometry.bundle import PRODUCT_FILE, analyze_product, apply_report, is_analysed
    from .plugins import registry

    path = Path(argument)
    if path.is_dir():
        if not (path / PRODUCT_FILE).is_file():
            raise UnknownProductError(f"{argument}: is a folder without {PRODUCT_FILE}, so not a product bundle")
        product = load_product(path / PRODUCT_FILE)
        return product if is_analysed(product) else apply_report(product, analyze_product(product))
    if path.is_file():
        loader = registry().loaders.get(path.suffix.lower())
        if loader is not None:
            return loader(path)
        if path.suffix.lower() in (".fcstd", ".step", ".stp"):
            raise UnknownProductError(f"{argument}: reading {path.suffix} files needs APLAN's FreeCAD side "
                                      "(install the project with `pip install -e .` and FreeCAD)")
        return load_product(path)
    if str(argument) in EXAMPLES:
        return load_product(example_path(str(argument)))
    raise UnknownProductError(
        f"{argument}: no such file, and no embedded example of that name (embedded: {', '.join(EXAMPLES)})")


def plan_of(product: str | os.PathLike | Product, technical: bool | None = None) -> Plan:
    """The plan (AND/OR graph, assembly states, tags) of a product or PRODUCT argument; ``technical``:
    ``True``/``False`` switches every technical constraint on/off, ``None`` keeps the file's."""
    return make_plan(product if isinstance(product, Product) else resolve_product(product), technical)


def plan_statistics_of(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                       base_part: str | None = None) -> tuple[Plan, PlanStatistics]:
    """The plan and its figures (``aplan stats``). ``base_part``: count only the sequences whose first
    operation joins it; ``"auto"``: the most connected part."""
    plan = product if isinstance(product, Plan) else plan_of(product, technical)
    base = most_connected_part(plan.product) if base_part == "auto" else base_part
    return plan, plan_statistics(plan, base)


def decision_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                   rewards: Rewards = Rewards(), discount: float = DISCOUNT) -> IntentionModel:
    """The decision model of Alg. 3 of a product, PRODUCT argument or plan."""
    plan = product if isinstance(product, Plan) else plan_of(product, technical)
    return intention_model(plan, rewards, discount)


def lumped_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                 rewards: Rewards = Rewards(), discount: float = DISCOUNT) -> LumpedModel:
    """The decision model of Alg. 3 lumped onto the factored model's classes (state edges and the finished
    product; :mod:`~planner.decision.lumped_model`): the same value as the flat model, far fewer states.
    ``.factored`` filters beliefs over classes, ``.pomdp`` (named ``<product>:lumped``) is what solvers take."""
    plan = product if isinstance(product, Plan) else plan_of(product, technical)
    return build_lumped_model(plan, rewards, discount)


def _model_file_kind(path: str | os.PathLike) -> str | None:
    name = str(path).lower()
    return next((s for s in MODEL_SUFFIXES if name.endswith(s)), None)


def load_model(argument: str | os.PathLike, technical: bool | None = None, rewards: Rewards = Rewards(),
               discount: float = DISCOUNT, lumped: bool = False) -> Model:
    """MODEL: a ``.pomdpx`` (or ``.pomdpx.gz``) or ``.pomdp`` file (a bare :class:`POMDP`), else a PRODUCT
    (its :class:`IntentionModel`, or with ``lumped`` its :class:`LumpedModel`; ``technical``, ``rewards`` and
    ``discount`` apply to it only)."""
    kind = _model_file_kind(argument)
    if kind is not None and lumped:
        raise PlannerError(f"{argument}: --lumped builds the lumped model of a PRODUCT; a model file is solved "
                           "as it is (write the lumped model with aplan pomdp PRODUCT --lumped -o FILE)")
    if kind in (".pomdpx", ".pomdpx.gz"):
        return read_pomdpx(argument)
    if kind == ".pomdp":
        return read_cassandra(argument)
    if lumped:
        return lumped_model(argument, technical, rewards, discount)
    return decision_model(argument, technical, rewards, discount)


def tables(model: Model) -> POMDP:
    """The POMDP tables of a decision model (a :class:`POMDP` is its own tables)."""
    return model.pomdp if isinstance(model, (IntentionModel, LumpedModel)) else model


def save_model(model: Model, path: str | os.PathLike) -> None:
    """Write POMDPX (``.pomdpx``) or Cassandra (``.pomdp``), by the file name (atomically)."""
    kind = _model_file_kind(path)
    if kind == ".pomdpx":
        write_pomdpx(tables(model), path)
    elif kind == ".pomdp":
        write_cassandra(tables(model), path)
    else:
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")


def solve(model: Model, time_limit: float = SOLVE_TIME_LIMIT, precision: float = SOLVE_PRECISION,
          engine: str = "builtin", progress: Callable[[float, float, float], None] | None = None,
          iterations: int | None = None) -> SolveResult:
    """Solve ``model`` offline: ``engine`` ``builtin`` (:class:`PointBasedSolver`, ``progress(seconds,
    lower, upper)`` after each step) or ``sarsop`` (APPL's ``pomdpsol``, when it is on PATH). The solver
    stops at ``time_limit`` seconds, at a gap of ``precision``, or after ``iterations`` trials (builtin only:
    a fixed amount of work gives the same policy on any machine)."""
    if engine == "sarsop":
        from .decision.solvers.sarsop import solve_with_sarsop

        return solve_with_sarsop(tables(model), time_limit, precision)
    if engine != "builtin":
        raise PlannerError(f"unknown solver engine {engine!r}; use one of {', '.join(SOLVER_ENGINES)}")
    solver = PointBasedSolver(time_limit=time_limit, precision=precision, max_iterations=iterations)
    return solver.solve(tables(model), progress)


def policy_for(model: Model, policy: str | os.PathLike | None = None,
               time_limit: float = POLICY_TIME_LIMIT) -> tuple[AlphaVectorPolicy, SolveResult | None]:
    """The policy in the file ``policy`` (checked against the model), or, without one, the built-in solver's
    after ``time_limit`` seconds, with its result (bounds, time)."""
    if policy:
        return read_policy(policy, tables(model)), None
    result = solve(model, time_limit, SOLVE_PRECISION)
    return result.policy, result


def simulate(model: IntentionModel, policy, sequences: Sequence[int] | None = None, every: bool = False,
             random: int | None = None, seed: int = 0, max_steps: int = 100, operator: str = "model",
             what: str = "--sequence") -> list[Episode]:
    """One episode per full sequence played (``Episode.start``): ``every`` one, ``random`` ones drawn at
    random, the listed ``sequences`` (each checked), or by default the first. The operator follows its
    sequence (``operator``: ``model`` or ``turns``, see :func:`~planner.decision.simulate.simulate_episode`);
    one random stream, seeded by ``seed``, draws the sequences and then every episode."""
    starts = [int(s) for s in model.full_sequences()]
    rng = np.random.default_rng(seed)
    if every:
        chosen = starts
    elif random:
        chosen = [int(s) for s in rng.choice(starts, size=random)]
    else:
        chosen = [model.full_sequence(s, what) for s in (sequences or [starts[0]])]
    return [simulate_episode(model.pomdp, policy, start, rng, max_steps, model.graph.successor, model.final_state,
                             operator) for start in chosen]


def evaluate(model: Model, policy, episodes: int, seed: int = 0, max_steps: int = 100) -> tuple[float, float]:
    """The mean discounted return over ``episodes`` simulated episodes and its 95 % confidence half-width;
    episodes of an intention model end at the finished product."""
    final = model.final_state if isinstance(model, IntentionModel) else None
    mean, half, _ = evaluate_policy(tables(model), policy, episodes, seed, max_steps, final)
    return mean, half
