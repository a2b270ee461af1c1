"""Interrupts in one place: SIGINT (Ctrl-C), SIGTERM and SIGHUP end a command cleanly.

- :func:`signals_as_interrupts`: SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted` (a
  ``KeyboardInterrupt``), so every ``finally`` and every ``except BaseException`` that cleans up and re-raises
  runs on the way out: temporary files and folders are removed (:mod:`planner.files`), child processes are
  killed (:func:`child_options` and the callers' ``kill`` on the way out), partial outputs never appear.
  Each signal is also recorded until the command's top level takes it (:func:`delivered`): code that catches
  ``BaseException`` and carries on cannot lose it, since :func:`raise_if_swallowed` raises it again before
  an output is committed and the command still ends with ``128 + N``.
- :func:`held_interrupts`: around third-party code that swallows ``BaseException`` (trimesh guards its
  optional imports so), the signals are held and delivered as soon as the block ends.
- :func:`deferred_interrupts`: in an anytime computation (the solver), SIGINT and SIGTERM only set a flag
  that the computation checks between steps, so it can stop with a consistent result and keep it; a second
  signal interrupts at once.
- :func:`exit_status`: ``128 + signal``, the shell's convention (130 for Ctrl-C, 143 for SIGTERM).

Handlers can only be installed in the main thread; elsewhere (a GUI's worker thread) these do nothing.
"""
from __future__ import annotations

import signal
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["Interrupted", "child_options", "start_child", "deferred_interrupts", "delivered", "exit_status", "held_interrupts",
           "raise_if_swallowed", "signal_number", "signals_as_interrupts", "swallowed"]

_TERMINATING = tuple(s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s)
#: The signals :func:`signals_as_interrupts` raised and no top level has taken yet (:func:`delivered`).
_RAISED: list[int] = []


class Interrupted(KeyboardInterrupt):
    """A terminating signal (``signum``) raised like Ctrl-C's ``KeyboardInterrupt``."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def signal_number(exc: BaseException) -> int:
    """The signal behind an interrupt: ``exc.signum`` for :class:`Interrupted`, else SIGINT."""
    return int(getattr(exc, "signum", signal.SIGINT))


def exit_status(signum: int) -> int:
    """The exit status of a command ended by signal ``signum``: ``128 + signum``."""
    return 128 + int(signum)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def signals_as_interrupts() -> Iterator[None]:
    """Within the block, SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted`, each recorded until
    :func:`delivered`; the previous handlers come back after."""
    if not _main_thread():
        yield
        return

    def interrupt(signum, frame) -> None:
        _RAISED.append(signum)
        raise Interrupted(signum)

    _RAISED.clear()
    previous = {s: signal.signal(s, interrupt) for s in (signal.SIGINT, *_TERMINATING)}
    try:
        yield
    finally:
        _RAISED.clear()  # what the block did not take is not for the code after it
        for s, handler in previous.items():
            signal.signal(s, handler)


def delivered() -> None:
    """The top level has taken the interrupt (it ends the command with ``128 + N``): forget the signals."""
    _RAISED.clear()


def swallowed() -> int:
    """The first signal raised as an interrupt and not yet :func:`delivered` (0: none): past a point where an
    interrupt would have ended the command, one that is still recorded was caught and ignored on the way."""
    return _RAISED[0] if _RAISED else 0


def raise_if_swallowed() -> None:
    """Raise :class:`Interrupted` again for a signal some code caught and ignored (:func:`swallowed`): called
    before an output is committed, so an ignored interrupt never ends in a finished output."""
    if _RAISED:
        raise Interrupted(_RAISED[0])


@contextmanager
def held_interrupts() -> Iterator[None]:
    """Within the block, SIGINT, SIGTERM and SIGHUP are held; the first one is delivered to the previous
    handler (raised again) as soon as the block ends, even when it ends with an error. For third-party code
    that catches ``BaseException`` and carries on (trimesh's optional imports), which would lose the
    interrupt. Outside the main thread it does nothing."""
    if not _main_thread():
        yield
        return
    held: list[int] = []
    # A handler set outside Python (None) cannot be put back from Python: such a signal is left alone.
    chosen = [s for s in (signal.SIGINT, *_TERMINATING) if signal.getsignal(s) is not None]
    previous = {s: signal.signal(s, lambda signum, frame: held.append(signum)) for s in chosen}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        if held:
            signal.raise_signal(held[0])  # the previous handler runs now: it raises, or ends the process


_deferring: list[Callable[[], int]] = []  # the pending() of the deferred_interrupts blocks open, innermost last


@contextmanager
def deferred_interrupts() -> Iterator[Callable[[], int]]:
    """Within the block, the first SIGINT or SIGTERM sets a flag instead of interrupting, and puts the
    previous handlers back (so a second one interrupts at once). Yields ``pending()``: the signal received,
    0 while none was. Outside the main thread, ``pending()`` stays 0 and nothing is deferred. Nested in
    another such block, it yields the outer block's ``pending()`` (one flag for the whole computation: the
    solver's set-up and its main loop in :func:`planner.api.solve`)."""
    if _deferring:  # nested (the solver inside api.solve): the outer block's flag, its handlers stay
        yield _deferring[-1]
        return
    received: list[int] = []
    if not _main_thread():
        yield lambda: 0
        return
    chosen = (signal.SIGINT, *_TERMINATING[:1])
    previous = {s: signal.getsignal(s) or signal.SIG_DFL for s in chosen}  # None: set outside Python

    def defer(signum, frame) -> None:
        received.append(signum)
        for s, handler in previous.items():
            signal.signal(s, handler)

    for s in chosen:
        signal.signal(s, defer)
    pending = lambda: received[0] if received else 0  # noqa: E731
    _deferring.append(pending)
    try:
        yield pending
    finally:
        _deferring.pop()
        for s, handler in previous.items():
            signal.signal(s, handler)


def child_options(unblock: tuple[int, ...] = ()) -> dict:
    """Keyword arguments for :class:`subprocess.Popen` so the child dies with this process, even when it is
    killed outright (SIGKILL): on Linux the child asks the kernel for SIGKILL when its parent exits
    (``PR_SET_PDEATHSIG``). Elsewhere nothing; the callers kill their children on an interrupt anyway.
    ``unblock``: signals the parent holds while it starts the child (:func:`start_child`), released in the
    child before it runs its program (a signal mask survives exec)."""
    if not sys.platform.startswith("linux"):
        return {}
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
    except OSError:
        return {}

    def die_with_parent() -> None:  # runs in the child, between fork and exec
        libc.prctl(1, int(signal.SIGKILL))  # 1: PR_SET_PDEATHSIG
        if unblock:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, unblock)

    return {"preexec_fn": die_with_parent}


def start_child(command: list[str], **options) -> subprocess.Popen:
    """``subprocess.Popen(command, **options)`` with :func:`child_options`, started so that an interrupt never
    leaves it running: SIGINT, SIGTERM and SIGHUP are held while it starts (an interrupt between the fork and
    the return of ``Popen`` would leave a child that no caller knows of to kill: the kernel's SIGKILL at this
    process's exit comes later, while it still runs), then released, and a signal that came meanwhile kills and
    reaps the child before it is raised. The signals are held for this thread only: in a process whose other
    threads do not hold them, one sent to the process can still come through another thread meanwhile. Cost: two ``pthread_sigmask`` calls."""
    held = (signal.SIGINT, *_TERMINATING)
    holding = _main_thread() and hasattr(signal, "pthread_sigmask")
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held) if holding else None
    process = None
    try:
        process = subprocess.Popen(command, **options, **child_options(held if holding else ()))
    finally:
        if holding:
            try:
                signal.pthread_sigmask(signal.SIG_SETMASK, previous)  # a signal held meanwhile is raised here
            except BaseException:
                if process is not None:
                    process.kill()
                    process.wait()
                raise
    return process
