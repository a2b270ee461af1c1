"""The collaboration runtime: observations -> belief -> action -> robot, until the product is assembled.

One decision step (as in :func:`planner.simulate.simulate_episode` and the paper's Sec. IV loop):

1. the policy picks the action for the current belief (an operation for the robot, or ``wait``);
2. the observation source is told what the robot is about to do (its marker events are not the
   operator's), then the robot performs it and reports success or failure;
3. the source delivers the operator's observation for the step (what the operator was seen picking, or
   blank);
4. the Bayes filter updates the belief with (action, observation).

*Assembled*: every operation joins two subassemblies, so a product of N parts is assembled after N - 1
operations; the loop counts the robot's confirmed operations and the operator's non-blank observations (an
operation that joins two subassemblies without a tool looks like blank, so the loop also stops when the
belief on the finished product reaches ``finished_belief``).

Interfaces (:class:`typing.Protocol`, so a ROS or vendor adapter plugs in without subclassing):
:class:`ObservationSource` (``observe``, ``robot_acting``) and :class:`Robot` (``perform``). Provided:
:class:`ConsoleRobot` (prints the instruction for a person standing in for the robot and waits for the
Enter key, as in the paper's experiment), :class:`ScriptedRobot`, :class:`ScriptedOperator`,
:class:`KeyboardSource` (the operator's picks typed in) and :class:`planner.vision.VisionSource` (camera).

Every event goes to an :class:`EventLog` (JSON lines, one ``write`` + flush + fsync per line, so a crash
loses at most the line being written); :func:`replay` recomputes the beliefs from a log.
A robot failure, an observation no operation explains, or a source error ends the loop cleanly: the belief
stays the last consistent one, the log holds every event up to the stop, and the result says why.
"""
from __future__ import annotations

import json
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Protocol, Sequence, runtime_checkable

import numpy as np

from ..assembly.plan import Plan
from ..assembly.tags import BLANK, Observation
from ..decision.belief import DiscreteUpdater
from ..decision.intention_model import IntentionModel, intention_model
from ..errors import PlannerError
from ..product.model import Product, product_from_dict, product_to_dict

__all__ = [
    "SessionError", "Instruction", "RobotReport", "ObservationSource", "Robot", "ConsoleRobot", "ScriptedRobot",
    "ScriptedOperator", "KeyboardSource", "EventLog", "SessionResult", "run_session", "instruction_for",
    "status_line", "read_line", "Replay", "replay", "LOG_VERSION",
]

LOG_VERSION = 1


class SessionError(PlannerError):
    """A session cannot start or go on: a log that cannot be written or read, a model that does not fit."""


@dataclass(frozen=True)
class Instruction:
    """What the robot is asked to do at one step: an operation (join ``inputs`` with ``tool``) or wait.

    ``picks``: the inputs that are single parts, which the robot takes from the tray.
    """

    step: int
    action: int
    name: str
    operation: int | None = None
    inputs: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    tool: str | None = None

    @property
    def is_wait(self) -> bool:
        return self.operation is None

    @property
    def picks(self) -> tuple[str, ...]:
        return tuple(sorted(side[0] for side in self.inputs or () if len(side) == 1))

    @property
    def text(self) -> str:
        if self.is_wait:
            return "wait (do nothing this step)"
        first, second = ("{" + ", ".join(side) + "}" for side in self.inputs)
        return f"join {first} with {second}" + (f" using the {self.tool}" if self.tool else "")


@dataclass(frozen=True)
class RobotReport:
    ok: bool
    message: str = ""


@runtime_checkable
class ObservationSource(Protocol):
    """Where the operator's observations come from (a camera, a keyboard, a script, a ROS topic)."""

    def observe(self) -> Observation | None:
        """The operator's operation in this step (BLANK when none); None when the source has ended."""

    def robot_acting(self, instruction: Instruction) -> None:
        """Called before the robot performs ``instruction``, so the robot's own picks are not the operator's."""


@runtime_checkable
class Robot(Protocol):
    """Performs instructions; reports whether it succeeded (``RobotReport(False, why)`` otherwise)."""

    def perform(self, instruction: Instruction) -> RobotReport:
        ...


def read_line(prompt: str) -> str:
    """Like :func:`input`, but the prompt goes to standard error (standard output stays for results)."""
    sys.stderr.write(prompt)
    sys.stderr.flush()
    line = sys.stdin.readline()
    if not line:
        raise EOFError
    return line.rstrip("\n")


def instruction_for(model: IntentionModel, action: int, step: int) -> Instruction:
    """The instruction of ``action`` in ``model`` at ``step``."""
    name = model.actions[action]
    operation = model.operation(action)
    if operation is None:
        return Instruction(step, action, name)
    plan = model.plan
    first, second = (tuple(sorted(side)) for side in plan.andor.inputs(operation))
    return Instruction(step, action, name, operation, (first, second), plan.tags.tool[operation])


class ConsoleRobot:
    """A person stands in for the robot: the instruction is printed and the person confirms with Enter
    (or types ``f`` and a reason, then Enter, when it could not be done). Waiting needs no confirmation
    unless ``confirm_wait``. End of input counts as a failure (nobody confirmed)."""

    def __init__(self, read: Callable[[str], str] = read_line, write=None, confirm_wait: bool = False):
        self._read = read
        self._write = write or (lambda text: print(text, file=sys.stderr, flush=True))
        self.confirm_wait = confirm_wait

    def perform(self, instruction: Instruction) -> RobotReport:
        self._write(f"\nROBOT, step {instruction.step}: {instruction.text}")
        if instruction.is_wait and not self.confirm_wait:
            return RobotReport(True)
        try:
            answer = self._read("  press Enter when done (f REASON + Enter if it failed): ").strip()
        except EOFError:
            return RobotReport(False, "no confirmation (end of input)")
        if answer.lower().startswith("f"):
            return RobotReport(False, answer[1:].strip() or "reported failure")
        return RobotReport(True)


class ScriptedRobot:
    """Performs every instruction at once, failing at the steps in ``fail_at``; ``on_perform`` (e.g. a
    simulated cell taking the robot's parts from a synthetic tray) is called for each performed one."""

    def __init__(self, fail_at: Iterable[int] = (), on_perform: Callable[[Instruction], None] | None = None):
        self.fail_at = set(fail_at)
        self.on_perform = on_perform
        self.performed: list[Instruction] = []

    def perform(self, instruction: Instruction) -> RobotReport:
        if instruction.step in self.fail_at:
            return RobotReport(False, f"scripted failure at step {instruction.step}")
        self.performed.append(instruction)
        if self.on_perform is not None:
            self.on_perform(instruction)
        return RobotReport(True)


class ScriptedOperator:
    """An operator following one assembly sequence (``operations``, AND/OR operation indices in order).

    Each step it performs its next operation when ``acts(step)`` says so (default: always, the operator
    taking turns with the robot as in the paper's runs) and nothing else; an operation the robot performs
    is struck from its list. As an :class:`ObservationSource` it reports the observation of what it did.
    ``off_script`` lists the robot's operations that were not in the sequence.
    """

    def __init__(self, plan: Plan, operations: Sequence[int], acts: Callable[[int], bool] | None = None):
        self.plan = plan
        self.remaining = [int(o) for o in operations]
        self.acts = acts or (lambda step: True)
        self.step = 0
        self.done: list[int] = []
        self.off_script: list[int] = []

    @classmethod
    def following(cls, model: IntentionModel, intention: int, acts=None) -> "ScriptedOperator":
        """The operator whose intention is ``intention`` of the decision model ``model``."""
        return cls(model.plan, model.sequence_operations(intention), acts)

    def next_operation(self) -> int | None:
        """Advance one step: the operation the operator performs in it, or None."""
        self.step += 1
        if not self.remaining or not self.acts(self.step):
            return None
        operation = self.remaining.pop(0)
        self.done.append(operation)
        return operation

    def observation_of(self, operation: int | None) -> Observation:
        return BLANK if operation is None else self.plan.observations[int(self.plan.operation_observation[operation])]

    def observe(self) -> Observation | None:
        return self.observation_of(self.next_operation())

    def robot_acting(self, instruction: Instruction) -> None:
        if instruction.operation is None:
            return
        if instruction.operation in self.remaining:
            self.remaining.remove(instruction.operation)
        else:
            self.off_script.append(instruction.operation)


class KeyboardSource:
    """The operator's picks typed in, one line per step: part and tool ids separated by spaces or commas
    (``ink cartridge hammer``), an empty line for nothing, ``q`` to stop. A line naming something that is
    not a part or tool, or two tools, is refused and asked again."""

    def __init__(self, product: Product, read: Callable[[str], str] = read_line, write=None):
        self.parts = set(product.part_ids)
        self.tools = {t.id for t in product.tools}
        self._read = read
        self._write = write or (lambda text: print(text, file=sys.stderr, flush=True))

    def observe(self) -> Observation | None:
        while True:
            try:
                line = self._read("operator picked (parts and tool; Enter: nothing; q: stop): ")
            except EOFError:
                return None
            names = line.replace(",", " ").split()
            if names in (["q"], ["quit"]):
                return None
            unknown = [n for n in names if n not in self.parts | self.tools]
            tools = [n for n in names if n in self.tools]
            if unknown:
                self._write(f"  not a part or tool: {', '.join(unknown)} (parts: {', '.join(sorted(self.parts))}; "
                            f"tools: {', '.join(sorted(self.tools)) or 'none'})")
            elif len(tools) > 1:
                self._write(f"  one tool per operation, got {', '.join(tools)}")
            else:
                return Observation(tuple(sorted(set(n for n in names if n in self.parts))), tools[0] if tools else None)

    def robot_acting(self, instruction: Instruction) -> None:
        """Nothing to do: the person types only the operator's picks."""


class EventLog:
    """Session events as JSON lines. Each event is one line written with one ``write``, then flushed and
    fsynced. ``path`` None keeps the events in memory only (``events`` always holds them); ``on_event`` sees
    every event as it is written."""

    def __init__(self, path: str | os.PathLike | None = None, on_event: Callable[[dict], None] | None = None):
        self.path = Path(path) if path is not None else None
        self.events: list[dict] = []
        self.on_event = on_event
        self._handle = None
        if self.path is not None:
            try:
                self._handle = open(self.path, "x", encoding="utf-8")
            except FileExistsError:
                raise SessionError(f"{self.path}: the log exists already; choose another file name "
                                   "(a log is never overwritten)") from None
            except OSError as exc:
                raise SessionError(f"{self.path}: cannot create the log: {exc}") from None

    def write(self, event: str, **fields) -> dict:
        record = {"event": event, "time": round(time.time(), 3), **fields}
        self.events.append(record)
        if self._handle is not None:
            try:
                self._handle.write(json.dumps(record) + "\n")
                self._handle.flush()
                os.fsync(self._handle.fileno())
            except OSError as exc:
                raise SessionError(f"{self.path}: cannot write the log: {exc}") from None
        if self.on_event is not None:
            self.on_event(record)
        return record

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None


@dataclass
class SessionResult:
    """How a session ended. ``reason``: ``assembled``, ``source ended``, ``robot failed``, ``unexplained
    observation``, ``error``, ``interrupted`` or ``step limit``; ``message`` says more."""

    reason: str
    message: str
    steps: int
    operations: int
    belief: np.ndarray
    beliefs: list[np.ndarray] = field(default_factory=list)
    actions: list[int] = field(default_factory=list)
    observations: list[int] = field(default_factory=list)

    @property
    def assembled(self) -> bool:
        return self.reason == "assembled"


def _top(belief: np.ndarray, k: int = 5) -> list[list]:
    order = np.argsort(-belief, kind="stable")[:k]
    return [[int(i), round(float(belief[i]), 6)] for i in order if belief[i] > 0]


def status_line(step: int, belief: np.ndarray, observation: str, next_action: str, k: int = 3) -> str:
    """``step 3 | belief i12 0.71 i15 0.20 i3 0.05 | seen ink+[hammer] | next a4:...``"""
    top = " ".join(f"i{i} {p:.2f}" for i, p in _top(belief, k))
    return f"step {step} | belief {top} | seen {observation} | next {next_action}"


def run_session(model: IntentionModel, policy, source: ObservationSource, robot: Robot,
                log: EventLog | None = None, status: Callable[[str], None] | None = None, max_steps: int = 500,
                finished_belief: float = 0.99, settings: dict | None = None) -> SessionResult:
    """Run the decision loop (module docstring) until the product is assembled or the loop has to stop.

    ``model``: the decision model of the product (:func:`planner.decision.intention_model`); ``policy`` has
    ``action(belief)``;
    ``settings`` (e.g. the policy file, rewards, discount) go into the log's start event. Never raises for a
    robot failure, an unexplained observation or a source error: the result says what happened.
    """
    plan = model.plan
    log = log if log is not None else EventLog()
    final = model.final_state
    needed = len(plan.product.parts) - 1
    index = {o: k for k, o in enumerate(plan.observations)}
    updater = DiscreteUpdater(model.pomdp)
    belief = updater.initialize()
    result = SessionResult("step limit", f"stopped after {max_steps} steps", 0, 0, belief, [belief])
    log.write("start", version=LOG_VERSION, product=product_to_dict(plan.product), settings=settings or {},
              n_intentions=model.pomdp.n_states, actions=list(model.actions), observations=list(model.observations),
              top=_top(belief))

    def stop(reason: str, message: str) -> SessionResult:
        result.reason, result.message, result.belief = reason, message, belief
        log.write("end", step=result.steps, reason=reason, message=message, operations=result.operations,
                  top=_top(belief))
        return result

    try:
        action = policy.action(belief)
        for step in range(1, max_steps + 1):
            result.steps = step
            instruction = instruction_for(model, action, step)
            log.write("action", step=step, action=action, name=instruction.name, instruction=instruction.text)
            source.robot_acting(instruction)
            report = robot.perform(instruction)
            log.write("robot", step=step, ok=report.ok, message=report.message)
            if not report.ok:
                return stop("robot failed", f"step {step}: the robot could not {instruction.text}: "
                            f"{report.message or 'no reason given'}; the belief is the one before this step")
            if not instruction.is_wait:
                result.operations += 1
            observation = source.observe()
            if observation is None:
                return stop("source ended", f"the observations ended at step {step}, with "
                            f"{result.operations} of {needed} operations done")
            z = index.get(observation)
            log.write("observation", step=step, observation=str(observation), index=z)
            if z is None:
                return stop("unexplained observation",
                            f"step {step}: the operator was seen picking {observation}, which no operation of "
                            f"{plan.product.name or 'the product'} explains (an operation takes one part + tool, "
                            "two parts + tool, or the tool only); check the tray and that only one operation's "
                            "items were taken; the belief is the one before this step")
            resets = len(updater.events)
            belief = updater.update(belief, action, z)
            for event in updater.events[resets:]:
                log.write("warning", step=step, message=f"{observation}: {event}")
            result.actions.append(action)
            result.observations.append(z)
            result.beliefs.append(belief)
            if observation != BLANK:
                result.operations += 1
            done = result.operations >= needed or belief[final] >= finished_belief
            action = policy.action(belief)
            next_name = "done" if done else model.actions[action]
            log.write("belief", step=step, top=_top(belief), p_finished=round(float(belief[final]), 6),
                      operations=result.operations,
                      reset=updater.events[-1].reset_to if len(updater.events) > resets else None)
            if status is not None:
                status(status_line(step, belief, str(observation), next_name))
            if done:
                return stop("assembled", f"the product is assembled after {step} steps "
                            f"({result.operations} operations)")
        return stop("step limit", f"stopped after {max_steps} steps, {result.operations} of {needed} operations done")
    except PlannerError as exc:
        return stop("error", str(exc))
    except KeyboardInterrupt:
        return stop("interrupted", f"interrupted at step {result.steps}")


# ---------------------------------------------------------------------------------------------- replay


@dataclass
class Replay:
    """A session log replayed: the product, the beliefs recomputed from its actions and observations (the
    initial one first), and the steps whose logged belief differs from the recomputed one."""

    product: Product
    model: IntentionModel
    actions: list[int]
    observations: list[int]
    beliefs: list[np.ndarray]
    end: dict | None
    mismatches: list[int]
    events: list[dict]


def _read_log(path: Path) -> list[dict]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise SessionError(f"{path}: cannot read the log: {exc}") from None
    events = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            event = json.loads(line)
        except json.JSONDecodeError as exc:
            if number == len(lines):  # the line being written when the session died
                break
            raise SessionError(f"{path}: line {number}: not JSON ({exc.msg}); the log is damaged") from None
        if not isinstance(event, dict) or "event" not in event:
            raise SessionError(f"{path}: line {number}: not a session event")
        events.append(event)
    if not events or events[0]["event"] != "start":
        raise SessionError(f"{path}: not a session log (it must start with a 'start' event)")
    if events[0].get("version") != LOG_VERSION:
        raise SessionError(f"{path}: log version {events[0].get('version')!r}; this planner reads version "
                           f"{LOG_VERSION}")
    return events


def replay(path: str | os.PathLike, tolerance: float = 1e-6) -> Replay:
    """Recompute the beliefs of the session logged at ``path`` (the product is stored in the log).

    Beliefs depend on the model's transitions and observations only, not on rewards or the policy.
    Raises :class:`SessionError` for a file that is not a session log.
    """
    from ..assembly.plan import make_plan

    path = Path(path)
    events = _read_log(path)
    start = events[0]
    product = product_from_dict(start["product"], f"{path} (start event)")
    model = intention_model(make_plan(product))
    if list(model.observations) != start.get("observations") or list(model.actions) != start.get("actions"):
        raise SessionError(f"{path}: the product in the log no longer gives the logged actions and observations "
                           "(the log was written by another planner version)")
    updater = DiscreteUpdater(model.pomdp)
    belief = updater.initialize()
    beliefs, actions, observations, mismatches = [belief], [], [], []
    pending: dict[int, int] = {}
    end = None
    for number, event in enumerate(events[1:], start=2):
        kind = event["event"]
        try:
            if kind == "action":
                pending[event["step"]] = int(event["action"])
            elif kind == "observation" and event.get("index") is not None:
                step = event["step"]
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)  # a reset, logged by the session already
                    belief = updater.update(belief, pending[step], int(event["index"]))
                actions.append(pending[step])
                observations.append(int(event["index"]))
                beliefs.append(belief)
            elif kind == "belief":
                if any(abs(belief[int(i)] - float(p)) > tolerance for i, p in event["top"]):
                    mismatches.append(event["step"])
            elif kind == "end":
                end = event
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise SessionError(f"{path}: event {number} ({kind!r}): malformed or out of order ({exc!r}); "
                               "the log is damaged") from None
    return Replay(product, model, actions, observations, beliefs, end, mismatches, events)
