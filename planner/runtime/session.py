"""The collaboration runtime's loop: observations -> belief -> action -> robot, until the product is assembled.

One decision step (as in :func:`planner.decision.simulate.simulate_episode` and the paper's Sec. IV loop):

1. the policy picks the action for the current belief (an operation for the robot, or ``wait``);
2. the observation source is told what the robot is about to do (its marker events are not the
   operator's), then the robot performs it and reports success or failure (an action named by a join,
   ``--joins``, is told as the join and the operation at the belief's most probable state where it applies:
   :func:`~planner.runtime.interfaces.instruction_for`; the assembly state applies the join's operation at each
   state it holds);
3. the source delivers the operator's observation for the step (what the operator was seen picking, or
   blank); a source with an ``offer(picks)`` method (the keyboard) is first given what the operator could be
   seen picking in the assembly state (:meth:`~planner.runtime.progress.AssemblyProgress.possible`);
4. the Bayes filter updates the belief with (action, observation).

*Assembled*: the session follows the assembly state from the operations actually done
(:class:`~planner.runtime.progress.AssemblyProgress`: the robot's confirmed operations and the operator's
observations that an operation explains) and stops when it is the finished product. A blank observation may
hide an operation (one joining two subassemblies without a tool): when the finished product is one of the
states it leaves open, the belief on the finished product (``finished_belief``) decides. The belief alone
never ends a session.

An observation that no operation explains in the assembly state (parts that cannot be joined now, a
combination no operation shows) is logged as a warning naming the picks and what the operator could do, and
counts as blank; the session goes on. So does a robot operation the assembly state does not allow. A step
undone (the source reports :class:`~planner.runtime.undo.Apart`) moves the belief to the completions of the
earlier state by the prior, and one the product cannot recover from stops the session (reason
``unrecoverable``): :mod:`planner.runtime.undo`.

The source and the robot are the protocols of :mod:`planner.runtime.interfaces`. Every event goes to an
:class:`~planner.runtime.log.EventLog` (format in :mod:`planner.runtime.log`). A robot failure or a
source error ends the loop cleanly: the belief stays the last consistent one, the log holds every event up to
the stop, and the result says why. A signal ends the log with an ``interrupted`` end event and is raised
again (the command exits 128 + N).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..assembly.intentions import count_intentions
from ..assembly.tags import BLANK, Observation
from ..decision.belief import UnexplainedObservation
from ..decision.factored_model import FactoredBelief, FactoredIntentionModel
from ..decision.intention_model import IntentionModel
from ..decision.models import BELIEF_OVER, belief_at, belief_over, belief_prefix, final_of, top_intentions, updater_for
from ..decision.step_observations import STATE
from ..errors import PlannerError
from ..product import product_to_dict
from .interfaces import Instruction, ObservationSource, Robot, instruction_for
from .log import LOG_VERSION, EventLog
from .progress import AssemblyProgress
from .undo import Apart, apart_state, belief_after_apart, in_model, predicted

__all__ = ["SessionResult", "run_session", "status_line"]


@dataclass
class SessionResult:
    """How a session ended. ``reason``: ``assembled``, ``source ended``, ``robot failed``, ``error``,
    ``unrecoverable`` (a step undone left a state no plan finishes) or ``step limit``; ``message`` says more.
    (An interrupt has no result: the log's end event says ``interrupted`` and the interrupt is raised again.)"""

    reason: str
    message: str
    steps: int
    operations: int
    belief: np.ndarray | FactoredBelief
    beliefs: list = field(default_factory=list)
    actions: list[int] = field(default_factory=list)
    observations: list[int] = field(default_factory=list)
    decision_seconds: list[float] = field(default_factory=list)  # the time the policy took for each action

    @property
    def assembled(self) -> bool:
        return self.reason == "assembled"


def status_line(step: int, belief, observation: str, next_action: str, k: int = 3) -> str:
    """``step 3 | belief i12 0.71 i15 0.20 i3 0.05 | seen ink+[hammer] | next a4:...`` (classes ``c12`` on the
    factored model)"""
    prefix = belief_prefix(belief)
    top = " ".join(f"{prefix}{i} {p:.2f}" for i, p in top_intentions(belief, k))
    return f"step {step} | belief {top} | seen {observation} | next {next_action}"


def run_session(model: IntentionModel | FactoredIntentionModel, policy, source: ObservationSource, robot: Robot,
                log: EventLog | None = None, status: Callable[[str], None] | None = None, max_steps: int = 500,
                finished_belief: float = 0.99, settings: dict | None = None) -> SessionResult:
    """Run the decision loop (module docstring) until the product is assembled or the loop has to stop.

    ``model``: the decision model of the product, flat (:func:`planner.decision.intention_model`, beliefs over
    intentions) or factored (:func:`planner.decision.factored_model`, beliefs over classes); ``policy`` has
    ``action(belief)`` for that belief (an offline policy, or the online planner); ``status`` receives a :func:`status_line` after each step;
    ``settings`` (e.g. the policy file, rewards, discount) go into the log's start event. Never raises for a
    robot failure or a source error: the result says what happened. An interrupt
    (Ctrl-C, SIGTERM) ends the log with an ``interrupted`` end event and is raised again.
    Cost per step: one policy lookup and one belief update, plus what the source and the robot take.
    """
    run = _Run(model, log if log is not None else EventLog())
    try:
        run.begin(settings or {})
        action = run.decide(policy)
        for step in range(1, max_steps + 1):
            run.result.steps = step
            instruction = instruction_for(model, action, step, run.belief)
            operation = run.perform(step, instruction, source, robot)
            observation, z = run.observe(step, source, operation, instruction)
            if isinstance(observation, Apart):  # a step undone: the belief moves to the earlier state
                run.undo(step, action, operation, observation)
            else:
                run.update(step, action, observation, z)
            done = run.progress.finished or (run.progress.may_be_finished and run.finished() >= finished_belief)
            if done:  # every operation joins two subassemblies: N - 1 were done, blank ones included
                run.progress.operations = run.needed
            action = run.decide(policy)
            run.report(step, observation, "done" if done else model.actions[action], status)
            if done:
                return run.stop("assembled", f"the product is assembled after {step} steps "
                                f"({run.operations} operations)")
        return run.stop("step limit", f"stopped after {max_steps} steps, {run.operations} of {run.needed} "
                        "operations done")
    except _Stop as stop:
        return run.stop(stop.reason, stop.message)
    except PlannerError as exc:
        return run.stop("error", str(exc))
    except KeyboardInterrupt:  # the log ends with it, then the interrupt goes on (the command exits 128 + N)
        run.stop("interrupted", f"interrupted at step {run.result.steps}")
        raise


class _Stop(Exception):
    """The loop has to stop for ``reason`` (a :class:`SessionResult` reason); raised by a step of :class:`_Run`."""

    def __init__(self, reason: str, message: str):
        super().__init__(message)
        self.reason, self.message = reason, message


class _Run:
    """One session's state (belief, result so far, log) and the parts of a step, each logging its events."""

    def __init__(self, model: IntentionModel | FactoredIntentionModel, log: EventLog):
        self.model = model
        self.log = log
        self.needed = len(model.plan.product.parts) - 1  # operations that assemble the product
        self.index = {o: k for k, o in enumerate(model.plan.observations)}
        self.resets: list[UnexplainedObservation] = []  # those of the current step, logged as warning events
        self.progress = AssemblyProgress(model.plan)
        self.blank = model.plan.observations.index(BLANK)
        self.updater = updater_for(model, on_reset=self.resets.append)
        self.over = belief_over(model)
        self.factored = self.over == BELIEF_OVER["factored"]
        self.final = final_of(model)
        self.belief = self.updater.initialize()
        self.result = SessionResult("running", "", 0, 0, self.belief, [self.belief])  # stop() says how it ended

    @property
    def operations(self) -> int:
        return self.progress.operations

    def decide(self, policy) -> int:
        """The policy's action for the current belief, timed (the log's ``decision_ms``)."""
        started = time.perf_counter()
        action = int(policy.action(self.belief))
        self.result.decision_seconds.append(time.perf_counter() - started)
        return action

    def finished(self) -> float:
        """The belief that the product is finished."""
        return belief_at(self.belief, self.final)

    def begin(self, settings: dict) -> None:
        model = self.model
        intentions = count_intentions(model.plan.states) if self.factored else model.pomdp.n_states
        designed = model.plan.designed or model.plan.product  # before folding: replaying folds the same fasteners
        deviations = getattr(model, "deviations", None)  # the model's own: replay rebuilds the same tables
        settings = {**settings, "deviations": None if deviations is None else deviations.as_dict(),
                    "observe": getattr(model, "observe", STATE)}
        self.log.write("start", version=LOG_VERSION, product=product_to_dict(designed), settings=settings,
                       n_intentions=intentions, belief_over=self.over,
                       actions=list(model.actions), observations=list(model.observations),
                       top=top_intentions(self.belief))

    def stop(self, reason: str, message: str) -> SessionResult:
        result = self.result
        result.reason, result.message, result.belief = reason, message, self.belief
        result.operations = self.operations
        self.log.write("end", step=result.steps, reason=reason, message=message, operations=result.operations,
                       top=top_intentions(self.belief))
        return result

    def perform(self, step: int, instruction: Instruction, source: ObservationSource,
                robot: Robot) -> int | tuple[int, ...] | None:
        """Tell the source, then have the robot perform ``instruction``; a failure stops the loop. Returns the
        AND/OR operation the robot confirmed (None for wait; a join's operations for an action named by a join).
        A join's action event also records the join, the operation reported (at the belief's most probable state
        where it applies: replay recomputes it) and whether the motion is the same at every state."""
        joined = {} if instruction.join is None else {
            "join": list(instruction.join), "operation": instruction.operation, "same_motion": instruction.same_motion}
        self.log.write("action", step=step, action=instruction.action, name=instruction.name,
                       instruction=instruction.text, decision_ms=round(1000 * self.result.decision_seconds[-1], 3),
                       **joined)
        source.robot_acting(instruction)
        report = robot.perform(instruction)
        self.log.write("robot", step=step, ok=report.ok, message=report.message)
        if not report.ok:
            raise _Stop("robot failed", f"step {step}: the robot could not {instruction.text}: "
                        f"{report.message or 'no reason given'}; the belief is the one before this step")
        return None if instruction.is_wait else instruction.performs

    def observe(self, step: int, source: ObservationSource, operation,
                instruction: Instruction) -> tuple[Observation, int]:
        """The operator's observation for ``step`` and the index the belief is updated with, the step applied
        to the assembly state with the robot's ``operation``. An observation no operation explains there is
        logged (``ignored``), with a warning naming what the operator could do, and counts as blank; the source
        ending stops the loop."""
        before, possible = self.progress.describe(), self.progress.possible(operation)
        offer = getattr(source, "offer", None)  # a source a person types into (the keyboard) shows the choices
        if offer is not None:
            offer(possible)
        observation = source.observe()
        if observation is None:
            raise _Stop("source ended", f"the observations ended at step {step}, with {self.operations} of "
                        f"{self.needed} operations done")
        if isinstance(observation, Apart):
            return observation, None
        z = self.index.get(observation)
        outcome = self.progress.step(operation, z)
        self.log.write("observation", step=step, observation=str(observation), index=z,
                       ignored=not outcome.explained)
        if outcome.robot is False:
            self.log.write("warning", step=step, message=(
                f"the robot's operation {self._robot_name(instruction)} is not possible in the assembly state "
                f"({before}); it does not count"))
        if not outcome.explained:
            why = ("no operation of the product shows these picks" if z is None else
                   "no operation explains it in the assembly state")
            could = ", ".join(possible) if possible else "nothing (only operations that show as blank)"
            self.log.write("warning", step=step, message=(
                f"{observation} ignored: {why} ({before}); the operator could pick: {could}. The step counts "
                "as blank: check the tray and that only one operation's items were taken"))
            return observation, self.blank
        return observation, z

    def _robot_name(self, instruction: Instruction) -> str:
        if instruction.join is not None:
            return "join {} to {}".format(*instruction.join)
        return self.model.plan.andor.describe(instruction.operation)

    def update(self, step: int, action: int, observation: Observation, z: int) -> None:
        """The Bayes filter's update; a reset (an observation of probability 0) is logged as a warning event."""
        self.resets.clear()
        self.belief = self.updater.update(self.belief, action, z)
        for event in self.resets:
            self.log.write("warning", step=step, message=f"{observation}: {event}")
        result = self.result
        result.actions.append(action)
        result.observations.append(z)
        result.beliefs.append(self.belief)
        result.operations = self.operations

    def undo(self, step: int, action: int, operation: int | None, apart: Apart) -> None:
        """A step undone (:mod:`planner.runtime.undo`): the robot's operation, then the piece come apart; the
        belief moves to the completions of the states left (an ``apart`` event), or the session stops when no
        plan can finish the product from them (an ``unrecoverable`` event, one line for the person)."""
        plan, progress = self.model.plan, self.progress
        if operation is not None:
            progress.robot(operation)
        before = progress.describe()
        moves, why, applies = [], [], False
        for s in sorted(progress.states):
            t, reason = apart_state(plan, s, apart.parts)
            applies |= t != -1
            if t is not None and t >= 0 and not in_model(self.model, t):
                t, reason = None, f"no sequence from the base part {self.model.base_part} goes through it"
            if t is not None and t >= 0:
                moves.append((s, t))
            else:
                why.append(reason)
        if not applies:
            self.log.write("warning", step=step, message=(
                f"{apart} ignored: {why[0]} ({before}); name the parts of the piece that came off (apart PART...). "
                "The step counts as blank"))
            return self.update(step, action, BLANK, self.blank)
        if not moves:
            message = (f"step {step}: {apart}: the product cannot be finished from here by any plan ({why[0]}; "
                       f"it was {before}); take it apart to an assembly state of the plan and start a new session")
            self.log.write("unrecoverable", step=step, parts=list(apart.parts), message=message)
            raise _Stop("unrecoverable", message)
        self.log.write("apart", step=step, parts=list(apart.parts), moves=[list(m) for m in moves])
        self.belief = belief_after_apart(self.model, predicted(self.model, self.updater, self.belief, action), moves)
        progress.set_states({t for _, t in moves})
        self.resets.clear()
        result = self.result
        result.actions.append(action)
        result.observations.append(self.blank)
        result.beliefs.append(self.belief)
        result.operations = self.operations

    def report(self, step: int, observation: Observation, next_name: str,
               status: Callable[[str], None] | None) -> None:
        belief = self.belief
        self.log.write("belief", step=step, top=top_intentions(belief),
                       p_finished=round(self.finished(), 6), operations=self.operations,
                       reset=self.resets[-1].reset_to if self.resets else None)
        if status is not None:
            status(status_line(step, belief, str(observation), next_name))
