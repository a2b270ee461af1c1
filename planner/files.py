"""Writing files safely: every output goes through a temporary file in its folder, then is renamed into place,
so a failure (a full disk, an interrupt) never leaves a partial file behind; the operating system's refusals
(no such folder, no permission, a full disk) become :class:`OutputError`s that say what to do.

Fault injection (tests): with ``APLAN_FAULT_DISK_FULL=N`` in the environment, every file written here (and
every session log: :func:`with_faults`) fails with ``ENOSPC`` once ``N`` bytes are written, as on a full disk
(a small full tmpfs needs root): the write that passes ``N`` writes what fits, then fails.
"""
from __future__ import annotations

import errno
import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from .errors import PlannerError
from .interrupts import raise_if_swallowed

__all__ = [
    "FAULT_DISK_FULL",
    "OutputError",
    "building_folder",
    "check_output",
    "make_folder_beside",
    "open_atomic",
    "replace_folder",
    "save_figure",
    "with_faults",
    "write_atomic",
]

FAULT_DISK_FULL = "APLAN_FAULT_DISK_FULL"


class OutputError(PlannerError):
    """An output cannot be written: its folder is missing or read-only, or the disk is full."""


def _explain(path: Path, exc: OSError) -> OutputError:
    """The :class:`OutputError` for the operating system's refusal ``exc`` to write ``path``."""
    fixes = {errno.ENOENT: f"create the folder {str(path.parent)!r} first, or choose another output",
             errno.ENOTDIR: f"{str(path.parent)!r} is not a folder: choose another output",
             errno.EACCES: f"the folder {str(path.parent)!r} is not writable: choose another output or change "
                           "its permissions",
             errno.EROFS: "the file system is read-only: choose another output",
             errno.ENOSPC: "the disk is full: free some space or write to another disk",
             errno.EDQUOT: "the disk quota is exhausted: free some space or write elsewhere"}
    fixes[errno.EPERM] = fixes[errno.EACCES]
    fix = fixes.get(exc.errno, "choose another output")
    return OutputError(f"{path}: cannot write it ({exc.strerror or exc}); {fix}. Nothing was written")


def check_output(path: str | os.PathLike) -> None:
    """Raise :class:`OutputError` unless ``path``'s folder exists, is a folder and is writable: checked before
    any work starts, so a long computation never ends in an output it cannot write."""
    path = Path(path)
    folder = path.parent
    if not folder.exists():
        raise _explain(path, FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT)))
    if not folder.is_dir():
        raise _explain(path, NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR)))
    if not os.access(folder, os.W_OK | os.X_OK):
        raise _explain(path, PermissionError(errno.EACCES, os.strerror(errno.EACCES)))
    if path.is_dir():
        raise OutputError(f"{path}: a folder, but the output is a file: choose a file name")

_ATTEMPTS = 100  # random names tried before giving up (a clash is already unlikely at the first)


def _create_temporary(path: Path) -> tuple[int, Path]:
    """A new, empty file beside ``path``, opened for writing: (descriptor, path).

    It is created with mode ``0o666`` and the kernel applies the process' umask, as for any new file. (Asking
    for the umask means setting it, which would race with other threads creating files; ``mkstemp`` makes
    the file private, so the mode would have to be fixed afterwards.) ``O_EXCL`` refuses a name that exists.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
    for _ in range(_ATTEMPTS):
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:  # another writer's temporary file: draw another name
            continue
    raise FileExistsError(f"{path.parent}: cannot create a temporary file for {path.name} ({_ATTEMPTS} names taken)")


@contextmanager
def open_atomic(path: str | os.PathLike) -> Iterator[BinaryIO]:
    """A binary file handle on a new temporary file in ``path``'s folder, renamed to ``path`` when the block
    ends without an error, removed otherwise (so no partial file is ever at ``path``). The file gets the
    permissions of any new file: ``0o666`` less the umask."""
    path = Path(path)
    try:
        fd, tmp = _create_temporary(path)
    except OSError as exc:
        raise _explain(path, exc) from None
    try:
        with open(fd, "wb") as handle:
            yield with_faults(handle)
        raise_if_swallowed()  # an interrupt some code caught and ignored: no output after it
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise _explain(path, exc) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def with_faults(handle: BinaryIO) -> BinaryIO:
    """``handle`` as it is, or, with ``APLAN_FAULT_DISK_FULL=N`` set, a handle that fails with ``ENOSPC`` once
    ``N`` bytes are written through it (the module docstring's fault injection)."""
    room = os.environ.get(FAULT_DISK_FULL)
    return _FullDisk(handle, int(room)) if room else handle


class _FullDisk:
    """A binary handle that fails with ``ENOSPC`` once ``room`` bytes are written (fault injection): the write
    that passes it writes the bytes that fit first, as a real full disk leaves a partial write."""

    def __init__(self, handle: BinaryIO, room: int):
        self._handle, self._room = handle, room

    def write(self, data) -> int:
        view = memoryview(data).cast("B")
        if view.nbytes > self._room:
            self._handle.write(view[:self._room])
            self._handle.flush()
            self._room = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._room -= view.nbytes
        return self._handle.write(data)

    def __getattr__(self, name: str):
        return getattr(self._handle, name)


def write_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`open_atomic`)."""
    with open_atomic(path) as handle:
        handle.write(str.encode(text, "utf-8"))  # a TypeError for anything but text, after the file is made


def save_figure(figure, path: str | os.PathLike, **options) -> str:
    """Save the matplotlib ``figure`` to ``path`` atomically (:func:`open_atomic`), in the format its suffix
    names (``.png``, ``.svg``, ``.pdf``, ...); ``options`` go to ``figure.savefig``. Returns ``str(path)``."""
    path = Path(path)
    with open_atomic(path) as handle:
        figure.savefig(handle, format=path.suffix[1:].lower() or None, **options)
    return str(path)


def make_folder_beside(path: str | os.PathLike, suffix: str = ".partial") -> Path:
    """A new, empty, hidden folder beside ``path`` (``.NAME.RANDOM.partial``) to build it in, then rename into
    place. Made with mode ``0o777`` less the umask, as any new folder (``mkdtemp``'s are private, ``0o700``, and
    a renamed bundle would stay so)."""
    path = Path(path)
    for _ in range(_ATTEMPTS):
        folder = path.parent / f".{path.name}.{secrets.token_hex(6)}{suffix}"
        try:
            folder.mkdir(0o777)
            return folder
        except FileExistsError:
            continue
        except OSError as exc:
            raise _explain(path, exc) from None
    raise FileExistsError(f"{path.parent}: cannot create a folder for {path.name} ({_ATTEMPTS} names taken)")


def replace_folder(work: str | os.PathLike, target: str | os.PathLike) -> None:
    """Put the finished folder ``work`` (made by :func:`make_folder_beside`) in place of ``target``: the one
    atomic folder swap. A target that exists is renamed aside first (``.NAME.old``), then ``work`` renamed into
    place and the old one removed, so at every moment ``target`` is either the old folder or the new one (never
    missing half its files, never a mix). An interrupt some code swallowed stops the swap before it starts
    (:func:`~planner.interrupts.raise_if_swallowed`). Cost: two renames and removing the old folder."""
    work, target = Path(work), Path(target)
    raise_if_swallowed()
    if not target.exists():
        os.rename(work, target)
        return
    old = target.with_name(f".{target.name}.{secrets.token_hex(6)}.old")
    os.rename(target, old)
    try:
        os.rename(work, target)
    except BaseException:
        os.rename(old, target)  # the old folder back: the target is never left missing
        raise
    shutil.rmtree(old, ignore_errors=True)


@contextmanager
def building_folder(target: str | os.PathLike) -> Iterator[Path]:
    """Build the folder ``target`` in a new hidden folder beside it (:func:`make_folder_beside`), yielded; when the
    block ends without an error it replaces ``target`` (:func:`replace_folder`), else it is removed and ``target``
    is left as it was. Every folder the planner and the workbench write (bundles) goes through here."""
    work = make_folder_beside(target)
    try:
        yield work
        replace_folder(work, target)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
