"""A person at the console: :class:`ConsoleRobot` (someone standing in for the robot, as in the paper's
experiment) and :class:`KeyboardSource` (the operator's picks typed in).

Both talk to the person through ``read`` and ``write`` callables: prompts and instructions go to standard
error, so standard output stays for results. This is user interaction, not logging.
"""
from __future__ import annotations

import sys
from typing import Callable, Sequence

from ..assembly.tags import Observation
from ..product import Product
from .interfaces import Instruction, RobotReport
from .undo import Apart

__all__ = ["read_line", "ConsoleRobot", "KeyboardSource", "PROMPT", "COULD_PICK"]


def read_line(prompt: str) -> str:
    """Like :func:`input`, but the prompt goes to standard error (standard output stays for results)."""
    sys.stderr.write(prompt)
    sys.stderr.flush()
    line = sys.stdin.readline()
    if not line:
        raise EOFError
    return line.rstrip("\n")


def _to_stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class ConsoleRobot:
    """A person stands in for the robot: the instruction is printed and the person confirms with Enter
    (or types ``f`` and a reason, then Enter, when it could not be done). Waiting needs no confirmation
    unless ``confirm_wait``. End of input counts as a failure (nobody confirmed)."""

    def __init__(self, read: Callable[[str], str] = read_line, write: Callable[[str], None] | None = None,
                 confirm_wait: bool = False):
        self._read = read
        self._write = write or _to_stderr
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


#: How the keyboard's prompt starts, and the line before it listing what the operator could pick now (a front
#: end that shows the prompt, the workbench's session panel, finds them by these).
PROMPT = "operator picked (parts and tool; Enter: nothing; apart PART...: came off; q: stop): "
COULD_PICK = "  the operator could pick now: "


class KeyboardSource:
    """The operator's picks typed in, one line per step: part and tool ids separated by spaces or commas
    (``ink cartridge hammer``), an empty line for nothing, ``q`` to stop, ``apart PART...`` when those parts
    came off the piece that held them (a step undone: :class:`~planner.runtime.undo.Apart`). A line naming
    something that is not a part or tool, or two tools, is refused and asked again.

    Before each prompt the person sees what the operator could pick now (:meth:`offer`: the observations of the
    operations possible in the assembly state, ``cartridge+ink+[hammer]``) and, with ``show_robot`` (a robot
    that performs by itself, ``--robot auto``), what the robot does at this step: the person at the keyboard
    needs both to type what the operator did next to it.

    ``joins`` (the observations of ``--observe join``, :func:`~planner.assembly.tags.join_observation_table`):
    the person also tells which pieces were joined. The choices are then numbered (``1. {cartridge ink}+head``),
    and the person types the number of what the operator did, or its text as shown; picks that name no piece
    are taken as they are when some operation of loose parts alone shows them."""

    def __init__(self, product: Product, read: Callable[[str], str] = read_line,
                 write: Callable[[str], None] | None = None, show_robot: bool = False,
                 joins: Sequence[Observation] | None = None):
        self.parts = set(product.part_ids)
        self.tools = {t.id for t in product.tools}
        self._read = read
        self._write = write or _to_stderr
        self.show_robot = show_robot
        self.joins = None if joins is None else {str(o): o for o in joins}
        self._offered: list[str] = []

    def offer(self, picks: list[str]) -> None:
        """Show ``picks`` (observations as text, e.g. ``body+button+[hammer]``) as what the operator could pick
        (numbered, with ``joins``)."""
        self._offered = list(picks)
        shown = [f"{k}. {p}" for k, p in enumerate(picks, 1)] if self.joins is not None else picks
        self._write(COULD_PICK + (", ".join(shown) if shown else "nothing that shows (Enter)"))

    def _join(self, line: str) -> Observation | None:
        """With ``joins``: the observation a line names (a number of the choices offered, or a choice's text);
        None when it names none of them."""
        text = line.strip()
        if text.isdigit() and 1 <= int(text) <= len(self._offered):
            text = self._offered[int(text) - 1]
        return self.joins.get(text)

    def observe(self) -> Observation | Apart | None:
        while True:
            try:
                line = self._read(PROMPT)
            except EOFError:
                return None
            names = line.replace(",", " ").split()
            if names in (["q"], ["quit"]):
                return None
            if self.joins is not None and names and names[0] != "apart":
                joined = self._join(line)
                if joined is not None:
                    return joined
                if any(c in line for c in "{}") or line.strip().isdigit():
                    self._write(f"  not one of the choices: {line.strip()} (" + (
                        f"type its number, 1 to {len(self._offered)}, or its text as shown)" if self._offered else
                        "nothing shows now: press Enter)"))
                    continue
            if names[:1] == ["apart"]:
                unknown = [n for n in names[1:] if n not in self.parts]
                if names[1:] and not unknown:
                    return Apart(tuple(sorted(set(names[1:]))))
                self._write(f"  apart needs the parts that came off, one piece (parts: {', '.join(sorted(self.parts))})"
                            + (f"; not a part: {', '.join(unknown)}" if unknown else ""))
                continue
            unknown = [n for n in names if n not in self.parts | self.tools]
            tools = [n for n in names if n in self.tools]
            if unknown:
                self._write(f"  not a part or tool: {', '.join(unknown)} (parts: {', '.join(sorted(self.parts))}; "
                            f"tools: {', '.join(sorted(self.tools)) or 'none'})")
            elif len(tools) > 1:
                self._write(f"  one tool per operation, got {', '.join(tools)}")
            else:
                picked = Observation(tuple(sorted(set(n for n in names if n in self.parts))),
                                     tools[0] if tools else None)
                if self.joins is not None and picked.parts and str(picked) not in self.joins:
                    self._write("  which pieces did these join? type the number of what the operator did (the "
                                "choices above name the pieces)")
                    continue
                return picked

    def robot_acting(self, instruction: Instruction) -> None:
        """With ``show_robot``, say what the robot does at this step (the person types only the operator's picks)."""
        if self.show_robot:
            self._write(f"robot, step {instruction.step}: {instruction.text}")
