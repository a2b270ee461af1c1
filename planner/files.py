"""Writing files safely: every output goes through a temporary file in its folder, then is renamed into place,
so a failure (a full disk, an interrupt) never leaves a partial file behind."""
from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

__all__ = ["write_atomic", "open_atomic", "save_figure"]

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
    fd, tmp = _create_temporary(path)
    try:
        with open(fd, "wb") as handle:
            yield handle
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


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
