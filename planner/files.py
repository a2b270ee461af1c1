"""Writing files safely: every output goes through a temporary file in its folder, then is renamed into place,
so a failure (a full disk, an interrupt) never leaves a partial file behind."""
from __future__ import annotations

import os
import secrets
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

__all__ = ["write_atomic", "open_atomic", "save_figure"]


def write_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder, so no partial file is left."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes the file private; give it the usual permissions
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


@contextmanager
def open_atomic(path: str | os.PathLike) -> Iterator[BinaryIO]:
    """A binary file handle on a new temporary file in ``path``'s folder, renamed to ``path`` when the block
    ends without an error, removed otherwise (so no partial file is ever at ``path``).

    The temporary file is created with mode 0o666, so the system applies the umask as for any new file (no
    ``os.umask`` call, whose change would be process-wide).
    """
    path = Path(path)
    folder = path.parent
    for _ in range(100):
        tmp = folder / f".{path.name}.{secrets.token_hex(4)}.tmp"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
            break
        except FileExistsError:  # another writer's temporary file: draw another name
            continue
    else:
        raise FileExistsError(f"{folder}: no free temporary file name for {path.name}")
    try:
        with os.fdopen(fd, "wb") as handle:
            yield handle
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def save_figure(figure, path: str | os.PathLike, **options) -> str:
    """Save the matplotlib ``figure`` to ``path`` atomically (:func:`open_atomic`), in the format its suffix
    names (``.png``, ``.svg``, ``.pdf``, ...); ``options`` go to ``figure.savefig``. Returns ``str(path)``."""
    path = Path(path)
    with open_atomic(path) as handle:
        figure.savefig(handle, format=path.suffix[1:].lower() or None, **options)
    return str(path)
