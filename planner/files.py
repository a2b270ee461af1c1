"""Writing files safely: every output goes through a temporary file in its folder, then is renamed into place,
so a failure (a full disk, an interrupt) never leaves a partial file behind."""
from __future__ import annotations

import os
import secrets
from pathlib import Path

__all__ = ["write_atomic"]

_ATTEMPTS = 100  # random names tried before giving up (a clash is already unlikely at the first)


def write_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` through a temporary file in the same folder, renamed into place,
    so no partial file is left. The file gets the permissions of any new file: ``0o666`` less the umask."""
    path = Path(path)
    fd, tmp = _create_temporary(path)
    try:
        with open(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _create_temporary(path: Path) -> tuple[int, Path]:
    """A new, empty file beside ``path``, opened for writing: (descriptor, path).

    It is created with mode ``0o666`` and the kernel applies the process' umask, as for any new file. (Asking
    for the umask means setting it, which would race with other threads creating files; ``mkstemp`` makes
    the file private, so the mode would have to be fixed afterwards.) ``O_EXCL`` refuses a name that exists.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(_ATTEMPTS):
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"{path.parent}: cannot create a temporary file for {path.name} ({_ATTEMPTS} names taken)")
