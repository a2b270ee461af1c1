"""Stage 3 of the API: the decision model of Alg. 3 of a product (over intentions, over classes, or lumped onto the
classes), a POMDP read from a file, and writing one as POMDPX or ``.pomdp`` within the file and memory budgets."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

from ..assembly.guards import OPTIONS, SizeLimits, memory_options
from ..assembly.intentions import count_intentions
from ..assembly.plan import Plan
from ..decision.factored_model import FactoredIntentionModel, factored_model
from ..decision.deviations import Deviations
from ..decision.habits import Habits, HabitsError
from ..decision.io.habits_file import read_habits, write_habits
from ..decision.orders import check_orders_parameters, prior_inputs
from ..decision.intention_model import IntentionModel, Rewards, intention_model
from ..decision.io.cassandra import read_cassandra, write_cassandra
from ..decision.io.pomdpx import read_pomdpx, write_pomdpx
from ..decision.io.size import model_file_bytes
from ..decision.budget import (
    check_flat_solver_memory,
    check_lumped_memory,
    check_parallel_memory,
    flat_limits,
    lumped_limits,
)
from ..decision.lumped_model import LumpedModel
from ..decision.parallel import parallel_flag
from ..decision.models import tables
from ..decision.lumped_model import lumped_model as build_lumped_model
from ..decision.pomdp import POMDP
from ..decision.step_observations import STATE, of_step, refuse_step_tables
from ..decision.step_pomdp import step_pomdp, step_pomdp_states
from ..decision.lumped_model import lumped_pomdp_bytes
from ..decision.presets import PRESETS, ModelPreset, preset_habits
from ..defaults import DISCOUNT, FILE_LIMIT
from ..errors import FileLimitError, MemoryLimitError, PlannerError, gib
from ..product import Product
from ..validation import InputLimits

from .plans import _decidable, base_part_of, plan_of
from .specs import ModelSpec

__all__ = ["MODEL_SUFFIXES", "Model", "decision_model", "factored_decision_model", "lumped_model",
           "check_parallel_flat", "load_model", "model_of", "check_model_file", "save_model", "tables",
           "MODEL_PRESETS", "habits_for", "session_habits", "learn_habits", "read_habits", "write_habits"]

MODEL_SUFFIXES = (".pomdpx", ".pomdpx.gz", ".pomdp")


FILE_OPTION = ("--max-file", "--max-file GIB raises the file size budget")


Model = IntentionModel | LumpedModel | POMDP

#: The named models (``--model NAME``, the workbench's model choice), by name: :data:`planner.decision.presets.PRESETS`.
MODEL_PRESETS: dict[str, ModelPreset] = PRESETS


def habits_for(model: str | None, path: str | os.PathLike | None,
               inputs: InputLimits = InputLimits()) -> Habits | None:
    """The habits a model-building command uses: the file at ``path`` read and checked
    (:func:`~planner.decision.io.habits_file.read_habits`), with the preset ``model``'s prior in place of the
    file's (``confident``), or None (``model`` a preset without habits, e.g. ``paper``; or no ``path``). A
    preset that needs habits without ``path`` is a :class:`~planner.errors.PlannerError`, so is an unknown name.
    ``aplan --habits FILE --model NAME`` and the workbench's session panel both read habits here. Cost: reading
    the file (within ``inputs``)."""
    if model is not None and model not in PRESETS:
        raise PlannerError(f"unknown model {model!r}; use one of {', '.join(PRESETS)}")
    preset = PRESETS.get(model)
    if preset is not None and not preset.habits:
        return None
    if path is None:
        if preset is not None:
            raise PlannerError(f"--model {model} needs the habits: --habits FILE (aplan habits LOG... -o FILE)")
        return None
    return preset_habits(preset, read_habits(path, inputs))


def session_habits(product: str | os.PathLike | Product | Plan, model: str | None, path: str | os.PathLike | None,
                   technical: bool | None = None, inputs: InputLimits = InputLimits()) -> Habits | None:
    """:func:`habits_for`, then checked to be of ``product``'s plan (the product's name, its state graph's
    fingerprint, every key one of its state edges, every recorded order one of its sequences:
    :func:`~planner.decision.orders.prior_inputs`), as the model built from them checks; a :class:`~planner.decision.habits.HabitsError` naming the file and the fix
    otherwise. What a session checks before it starts. Cost: reading the file and one plan of ``product``."""
    habits = habits_for(model, path, inputs)
    if habits is not None:
        plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical))
        prior_inputs(plan, habits)
    return habits


def learn_habits(logs, product: Product | Plan | None = None, prior: float | None = None,
                 prior_per: str | None = None, technical: bool | None = None,
                 add: str | os.PathLike | None = None, inputs: InputLimits = InputLimits(),
                 concentration: float | None = None, discount: float | None = None,
                 notes: list[str] | None = None) -> tuple[Habits, float]:
    """The habits counted from the session logs ``logs`` (``aplan habits LOG...``; docs/habits.md, Learning from
    logs) and the operator's steps counted: of ``product``'s plan (None: the first log's product), added to the
    counts of the habits file ``add`` when given (``product`` is then needed, to check them against), with the
    prior ``prior`` (None: ``add``'s, else the default) spread ``prior_per`` (None: ``add``'s, else per edge), and
    the recorded orders' Pitman-Yor ``concentration`` and ``discount`` (None: ``add``'s, else the defaults;
    :mod:`~planner.decision.orders`); ``notes``, if given, gets a line per finished log whose explanations are too
    many to record as orders (the operator's steps counted are expected counts: docs/habits.md, Learning from
    logs). A log of another product version, one with no step, or ``add`` of another product is a
    :class:`~planner.decision.habits.HabitsError`. Cost: one replay per log (a model build, one belief update per
    step)."""
    from dataclasses import replace

    from ..runtime.habits_logs import habits_from_logs

    plan = None if product is None else product if isinstance(product, Plan) else _decidable(plan_of(product,
                                                                                                     technical))
    start = read_habits(add, inputs) if add else None
    if start is not None and plan is None:
        raise HabitsError(f"--add {add}: give the product too (--product PRODUCT), to check the counts against it")
    habits, steps = habits_from_logs(plan, list(logs), prior, technical, start, inputs, notes)
    habits = replace(habits, prior_per=prior_per or (start.prior_per if start is not None else "edge"))
    concentration = concentration if concentration is not None else habits.concentration
    discount = discount if discount is not None else habits.discount
    checked = check_orders_parameters(concentration, discount, "--concentration/--discount")
    return replace(habits, **dict(zip(("concentration", "discount"), checked))), steps


def decision_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                   rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                   base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                   habits: Habits | None = None, solving: bool = False,
                   deviations: Deviations | None = None) -> IntentionModel:
    """The decision model of Alg. 3 of a product, PRODUCT argument or plan; ``base_part``: only the sequences
    that start from it (``"auto"``: the most connected part, :func:`base_part_of`); refused, with the estimate,
    past ``limits`` (the plan's, and the flat model's memory:
    :func:`~planner.decision.intention_model.flat_model_bytes`); with ``solving``, also when the solver would
    not fit beside it (:func:`~planner.decision.budget.check_flat_solver_memory`), before it is built.
    ``habits``: the operator's habits in place of the uniform choice (:mod:`~planner.decision.habits`; checked
    to be this product's), None for the paper's; ``deviations``: change of mind and mistakes
    (:mod:`~planner.decision.deviations`), None for the paper's."""
    plan = product if isinstance(product, Plan) else \
        _decidable(plan_of(product, technical, flat_limits(limits, solving) if base_part is None else limits))
    base = base_part_of(plan, base_part)
    if solving:  # refused before the flat model is built when the solver would not fit beside it
        check_flat_solver_memory(plan, count_intentions(plan.states, base_part=base), limits.memory)
    weights, orders = prior_inputs(plan, habits)
    return intention_model(plan, rewards, discount, base_part=base, max_bytes=limits.memory,
                           weights=weights, deviations=deviations, orders=orders)


def factored_decision_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                            rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                            base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                            habits: Habits | None = None, parallel: bool = False,
                            deviations: Deviations | None = None, observe: str = STATE) -> FactoredIntentionModel:
    """The same decision model without enumerating intentions (paper Sec. V): beliefs over classes;
    ``parallel``: the parallel model (docs/parallel.md); ``deviations``: change of mind and mistakes;
    ``observe``: the paper's observations (``"state"``) or a camera's (``"step"``, ``"join"``: docs/camera.md)."""
    plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical, limits))
    if parallel:
        check_parallel_memory(plan, limits.memory, parallel)
    return factored_model(plan, rewards, discount, base_part_of(plan, base_part), *_parts(plan, habits, parallel,
                                                                                         deviations), observe)


def lumped_model(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                 rewards: Rewards = Rewards(), discount: float = DISCOUNT, base_part: str | None = None,
                 limits: SizeLimits = SizeLimits(), habits: Habits | None = None,
                 parallel: bool = False, deviations: Deviations | None = None) -> LumpedModel:
    """The decision model of Alg. 3 lumped onto the factored model's classes (state edges and the finished
    product; :mod:`~planner.decision.lumped_model`): the same value as the flat model, far fewer states.
    ``.factored`` filters beliefs over classes, ``.pomdp`` (named ``<product>:lumped``) is what solvers take."""
    plan = product if isinstance(product, Plan) else _decidable(plan_of(product, technical, lumped_limits(limits)))
    check_lumped_memory(plan, limits.memory)
    if parallel:
        check_parallel_memory(plan, limits.memory, parallel)
    return build_lumped_model(plan, rewards, discount, base_part_of(plan, base_part),
                              *_parts(plan, habits, parallel, deviations))


def _parts(plan: Plan, habits: Habits | None, parallel, deviations) -> tuple:
    """``(weights, parallel, deviations, orders)`` as the factored and lumped builders take them."""
    weights, orders = prior_inputs(plan, habits)
    return weights, parallel, deviations, orders


def check_parallel_flat(parallel: bool, where: str) -> None:
    """The parallel model lives on the classes (docs/parallel.md): the flat model over intentions cannot hold
    it (a wrong parallel action would condition the distribution within a class), so ``where`` with it is a
    :class:`PlannerError` naming what helps."""
    if parallel:
        flag = parallel_flag(parallel)
        raise PlannerError(f"{flag} is a model over the factored model's classes, and {where} would build the "
                           "flat model over intentions, which cannot hold it: use the online planner (--planner "
                           f"online), or a policy over the classes (aplan solve PRODUCT {flag} -o P.policy), or "
                           f"leave out {flag}")


def _model_file_kind(path: str | os.PathLike) -> str | None:
    name = str(path).lower()
    return next((s for s in MODEL_SUFFIXES if name.endswith(s)), None)


def load_model(argument: str | os.PathLike | Product, technical: bool | None = None, rewards: Rewards = Rewards(),
               discount: float = DISCOUNT, base_part: str | None = None, limits: SizeLimits = SizeLimits(),
               lumped: bool = False, inputs: InputLimits = InputLimits(), habits: Habits | None = None,
               solving: bool = False, parallel: bool = False, deviations: Deviations | None = None) -> Model:
    """MODEL: a ``.pomdpx`` (or ``.pomdpx.gz``) or ``.pomdp`` file (a bare :class:`POMDP`, read within
    ``inputs``: :class:`~planner.validation.InputLimits`), else a PRODUCT
    (its :class:`IntentionModel`, or with ``lumped`` its :class:`LumpedModel`; ``technical``, ``rewards``,
    ``discount``, ``base_part`` and ``limits`` apply to it only: a base part with a model file is a
    :class:`PlannerError`, since the file's intentions are fixed). ``parallel``: the parallel model
    (docs/parallel.md), which is on the classes: it builds the :class:`LumpedModel` as ``lumped`` does."""
    kind = None if isinstance(argument, Product) else _model_file_kind(argument)
    if kind is not None and base_part:
        raise PlannerError(f"{argument}: a base part applies to products only, and this is a model file whose "
                           "intentions are fixed; leave out the base part (--base-part), or give the PRODUCT")
    if kind is not None and habits is not None:
        raise PlannerError(f"{argument}: --habits applies to a PRODUCT; a model file's initial belief and "
                           "transitions are fixed (give the PRODUCT, or leave out --habits)")
    if kind is not None and parallel:
        raise PlannerError(f"{argument}: {parallel_flag(parallel)} applies to a PRODUCT; a model file's transitions "
                           f"are fixed (give the PRODUCT, or leave out {parallel_flag(parallel)})")
    if kind is not None and deviations is not None:
        raise PlannerError(f"{argument}: --switch and --mistakes apply to a PRODUCT; a model file's transitions and "
                           "observations are fixed (give the PRODUCT, or leave them out)")
    if kind is not None and lumped:
        raise PlannerError(f"{argument}: --lumped builds the lumped model of a PRODUCT; a model file is solved "
                           "as it is (write the lumped model with aplan pomdp PRODUCT --lumped -o FILE)")
    if kind in (".pomdpx", ".pomdp") and os.path.isfile(argument):
        _check_model_read(argument, limits.memory)
    if kind in (".pomdpx", ".pomdpx.gz"):
        return read_pomdpx(argument, inputs)
    if kind == ".pomdp":
        return read_cassandra(argument, inputs)
    if lumped or parallel:
        return lumped_model(argument, technical, rewards, discount, base_part, limits, habits, parallel, deviations)
    return decision_model(argument, technical, rewards, discount, base_part, limits, habits, solving, deviations)


def model_of(argument: str | os.PathLike | Product | Plan, spec: ModelSpec = ModelSpec(), lumped: bool = False,
             solving: bool = False, flat: bool = False) -> Model:
    """The model :func:`load_model` gives for ``spec`` (:class:`~planner.api.specs.ModelSpec`): a model file as
    it is, else the PRODUCT's decision model (``lumped``: its :class:`LumpedModel`). ``flat``: the flat
    :class:`IntentionModel` whatever ``spec.parallel`` asks (a command that needs intentions: the parallel model
    is on the classes), and a plan may be given. Cost: that of the model built. ``spec.observe`` ``"step"``: with
    ``lumped``, the POMDP over (class, the step's observation) pairs (:func:`~planner.decision.step_pomdp.
    step_pomdp`: a bare POMDP, for files and solvers), else refused (the flat model cannot hold it)."""
    if of_step(spec.observe):
        return _step_tables(argument, spec, lumped and not flat)
    if flat or isinstance(argument, Plan):
        return decision_model(argument, spec.technical, spec.rewards, spec.discount, spec.base_part, spec.limits,
                              spec.habits, solving, spec.deviations)
    return load_model(argument, spec.technical, spec.rewards, spec.discount, spec.base_part, spec.limits, lumped,
                      spec.inputs, spec.habits, solving, spec.parallel, spec.deviations)


def _step_tables(argument, spec: ModelSpec, lumped: bool) -> POMDP:
    """The POMDP of ``--observe step|join`` on a PRODUCT (:func:`~planner.decision.step_pomdp.step_pomdp`), after
    the factored model's and the lumped model's memory checks (its states: the classes and their pairs with the
    observations into them, refused past the budget with the count)."""
    if not lumped or isinstance(argument, Plan) or _model_file_kind(argument):
        refuse_step_tables(spec, "the flat model over intentions (or a model file)",
                           "add --lumped for the POMDP over (class, seen observation) pairs (docs/camera.md), use "
                           "the online planner (aplan simulate/session), or leave out --observe")
    plan = _decidable(plan_of(argument, spec.technical, lumped_limits(spec.limits)))
    check_lumped_memory(plan, spec.limits.memory)
    model = factored_decision_model(plan, spec.technical, spec.rewards, spec.discount, spec.base_part, spec.limits,
                                    spec.habits, spec.parallel, spec.deviations, spec.observe)
    n = step_pomdp_states(model)
    needed = lumped_pomdp_bytes(n, len(model.actions))
    if needed > spec.limits.memory:
        raise MemoryLimitError(f"the POMDP of --observe {spec.observe} would hold {n:,} states (the classes and their "
                               f"pairs with the observations into them) x {len(model.actions):,} actions, about "
                               f"{gib(needed)}, past the memory budget of {gib(spec.limits.memory)}; use the online "
                               f"planner (aplan simulate/session --observe {spec.observe}), or --base-part")
    return step_pomdp(model)


# Reading a model file peaks at about 3 bytes of memory per byte of file (bench/README.md, model files).
_READ_BYTES_PER_FILE_BYTE = 3


def _check_model_read(path: str | os.PathLike, max_bytes: int) -> None:
    """Refuse to read a model file whose reading would pass the memory budget (estimated from its size)."""
    size = os.path.getsize(path)
    needed = _READ_BYTES_PER_FILE_BYTE * size
    if needed > max_bytes:
        raise MemoryLimitError(f"reading {path}", needed, max_bytes, f"{_READ_BYTES_PER_FILE_BYTE} x its "
                               f"{gib(size)}", "A model file that large holds more than the "
                               "solvers can use; plan the product with fewer parts or a base part instead.",
                               memory_options(needed))


def check_model_file(model: Model, path: str | os.PathLike, max_bytes: int = FILE_LIMIT,
                     read_budget: int | None = None) -> int:
    """The bytes :func:`save_model` would write to ``path`` (:func:`~planner.decision.io.size.model_file_bytes`),
    after checking them against ``max_bytes`` and the free space of the target's disk: past either,
    :class:`~planner.errors.FileLimitError` with the estimate. With ``read_budget`` (bytes of memory, as
    :func:`load_model`'s ``limits.memory``): a file that :func:`load_model` would refuse to read back within it
    is refused before it is written (:class:`~planner.errors.MemoryLimitError`), so aplan reads what it writes
    with the same options. Cost: O(non-zeros) in numpy."""
    kind = _model_file_kind(path)
    if kind not in (".pomdpx", ".pomdp"):
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")
    pomdp = tables(model)
    needed = model_file_bytes(pomdp, "pomdpx" if kind == ".pomdpx" else "cassandra")
    folder = Path(path).resolve().parent
    free = shutil.disk_usage(folder).free if folder.is_dir() else None
    detail = (f"{pomdp.n_states:,} states, {pomdp.n_actions:,} actions, "
              f"{sum(t.nnz for t in pomdp.transition):,} non-zero transitions")
    hint = "A smaller model (fewer intentions) makes a smaller file."
    if free is not None and needed > free:
        raise FileLimitError(f"{path}", needed, free, detail, hint, budget_name=f"the free space in {folder}")
    if needed > max_bytes:
        raise FileLimitError(f"{path}", needed, max_bytes, detail, hint, [FILE_OPTION, OPTIONS["base_part"]])
    reading = _READ_BYTES_PER_FILE_BYTE * needed
    if read_budget is not None and reading > read_budget:
        raise MemoryLimitError(f"reading {path} back (aplan solve, evaluate)", reading, read_budget,
                               f"{_READ_BYTES_PER_FILE_BYTE} x the {gib(needed)} it would take",
                               "Refused before writing: aplan would not read the file it wrote. A POMDPX file (.pomdpx) "
                               "is smaller than a .pomdp; fewer intentions make both smaller.",
                               memory_options(reading) + [OPTIONS["base_part"]])
    return needed


def save_model(model: Model, path: str | os.PathLike, max_bytes: int = FILE_LIMIT,
               read_budget: int | None = None) -> None:
    """Write POMDPX (``.pomdpx``) or Cassandra (``.pomdp``), by the file name (atomically), after estimating
    its size (:func:`check_model_file`: refused past ``max_bytes``, the free disk space or, with
    ``read_budget``, what :func:`load_model` reads back within that memory)."""
    check_model_file(model, path, max_bytes, read_budget)
    kind = _model_file_kind(path)
    if kind == ".pomdpx":
        write_pomdpx(tables(model), path)
    elif kind == ".pomdp":
        write_cassandra(tables(model), path)
    else:
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")
