"""Damaged FreeCAD documents, found before FreeCAD opens them.

A ``.FCStd`` file is a zip archive: ``Document.xml`` declares the objects and their properties, and each shape
is a member of its own (``<Part file="PartShape3.brp"/>``). FreeCAD opens a damaged archive without a word:
the objects whose shape member is missing (a truncated file) or unreadable, and those after an XML error in
``Document.xml``, come back with empty shapes, and an export would silently leave them out. Here the archive
is read in plain Python (no FreeCAD): every member is decompressed and its CRC checked, ``Document.xml`` is
parsed, and each object whose data or files are missing or unreadable is named.

Cost: one pass over the archive (decompressing every member once) and one parse of ``Document.xml``.
"""
from __future__ import annotations

import bisect
import re
import struct
import zipfile
import zlib
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

from lxml import etree

from planner.errors import PlannerError

__all__ = ["DamagedDocumentError", "Damage", "document_damage", "check_document", "SKIP_OPTION", "SKIP_BY_EXPORT"]

_LOCAL = struct.Struct("<4sHHHHHIIIHH")  # a zip member's local header
_DECLARED = re.compile(rb'<Object\s[^>]*?name="([^"]+)"[^>]*>')
_TYPE = re.compile(rb'\stype="([^"]+)"')
# objects that hold shapes or designer intent: the ones an export reads (constraints and the like are not named)
_EXPORTED = re.compile(r"^(Part::|PartDesign::|App::Link|Aplan::)")
_DATA = re.compile(rb'<Object\s+name="([^"]+)"[^>]*>')
_LABEL = re.compile(rb'<Property\s+name="Label"[^>]*>\s*<String\s+value="([^"]*)"')
_FILE = re.compile(rb'<([A-Za-z]+)\s[^>]*?\bfile="([^"]+)"')
# an App::Link to an object of another document: ``file`` names that document (relative to this one's folder,
# as FreeCAD resolves it), not a member of this archive
_XLINK = b"XLink"


# what the zip and zlib modules raise on damaged data (a flipped bit can make a member look encrypted: RuntimeError)
_UNREADABLE = (zipfile.BadZipFile, zlib.error, EOFError, ValueError, NotImplementedError, RuntimeError,
               struct.error, KeyError, UnicodeDecodeError)


class DamagedDocumentError(PlannerError):
    """A FreeCAD document is damaged: objects (or the whole document) cannot be read."""


@dataclass(frozen=True)
class Damage:
    """An object of a document that cannot be read: its internal ``name``, its ``label`` and why."""

    name: str
    label: str
    problem: str

    def __str__(self) -> str:
        shown = self.label if self.label == self.name else f"{self.label} ({self.name})"
        return f"{shown}: {self.problem}"


def _members(data: bytes) -> tuple[dict[str, bool], bool]:
    """Each member's name -> whether it reads back intact (decompressed, CRC right), and whether the archive's
    directory is missing (truncated: members found by scanning the local headers, as FreeCAD does)."""
    try:
        archive = zipfile.ZipFile(BytesIO(data))
    except _UNREADABLE:
        return _scan(data), True
    intact = {}
    for info in archive.infolist():
        try:
            archive.read(info)
            intact[info.filename] = True
        except _UNREADABLE:
            intact[info.filename] = False
    return intact, False


def _scan(data: bytes) -> dict[str, bool]:
    """Members by their local headers (no central directory): name -> intact."""
    intact: dict[str, bool] = {}
    at = 0
    while at + _LOCAL.size <= len(data) and data[at:at + 4] == b"PK\x03\x04":
        _, _, flags, method, _, _, crc, size, _, name_length, extra = _LOCAL.unpack_from(data, at)
        start = at + _LOCAL.size + name_length + extra
        name = data[at + _LOCAL.size:at + _LOCAL.size + name_length].decode("utf-8", "replace")
        if flags & 8:  # sizes after the data (a data descriptor): decompress to find the end
            body, end, ok = _inflate(data, start, method)
            ok = ok and end + 12 <= len(data)
            if ok:
                fields = data[end:end + 16]
                if fields[:4] == b"PK\x07\x08":
                    fields = fields[4:]
                ok = zlib.crc32(body) == struct.unpack_from("<I", fields)[0]
                end += 16 if data[end:end + 4] == b"PK\x07\x08" else 12
        else:
            end = start + size
            ok = end <= len(data)
            if ok:
                try:
                    body = data[start:end] if method == 0 else zlib.decompress(data[start:end], -15)
                    ok = zlib.crc32(body) == crc
                except zlib.error:
                    ok = False
        intact[name] = ok
        if not ok:
            break  # the rest of the archive is gone
        at = end
    return intact


def _inflate(data: bytes, start: int, method: int) -> tuple[bytes, int, bool]:
    if method != 8:
        return b"", start, False
    inflater = zlib.decompressobj(-15)
    try:
        body = inflater.decompress(data[start:])
    except zlib.error:
        return b"", start, False
    return body, len(data) - len(inflater.unused_data), inflater.eof


def document_damage(path: str | Path, _seen: set[Path] | None = None) -> list[Damage]:
    """The damaged objects of the ``.FCStd`` document ``path`` (empty when it reads back whole): objects whose
    data in ``Document.xml`` lies at or after an XML error, or whose files (shapes) are missing from the archive
    or unreadable, and links (``App::Link``, Assembly4, A2plus) to another document that is missing beside it
    or is itself damaged. Raises :class:`DamagedDocumentError` when ``Document.xml`` itself cannot be read.

    A link's ``<XLink file="NAME.FCStd">`` names a document, not an archive member: FreeCAD looks for it
    relative to the linking document's folder (an absolute path as it is). Each linked document is checked
    once. Cost: one pass over each archive reached."""
    path = Path(path)
    seen = _seen if _seen is not None else set()
    seen.add(path.resolve())
    data = path.read_bytes()
    intact, truncated = _members(data)
    if not intact.get("Document.xml"):
        found = "is not a zip archive" if not intact else "has no readable Document.xml"
        raise DamagedDocumentError(f"{path}: the file {found}: it is not a FreeCAD document, or it is damaged "
                                   "beyond repair; open a backup (FreeCAD keeps NAME.FCBak) or export it again")
    try:
        with zipfile.ZipFile(BytesIO(data)) if not truncated else _Scanned(data) as archive:
            text = archive.read("Document.xml")
    except _UNREADABLE:
        raise DamagedDocumentError(f"{path}: its Document.xml cannot be read: the document is damaged beyond "
                                   "repair; open a backup (FreeCAD keeps NAME.FCBak) or export it again") from None
    error_at, error = len(text), ""
    try:
        etree.fromstring(text, etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=False))
    except etree.XMLSyntaxError as exc:
        line = exc.position[0] if exc.position else 1
        error_at = sum(len(row) + 1 for row in text.split(b"\n")[:max(0, line - 1)])
        error = f"the XML error at line {line} of Document.xml ({exc.msg.split(', line')[0]})"
    blocks = {m.group(1).decode("utf-8", "replace"): m.start() for m in _DATA.finditer(text)}
    starts = sorted(blocks.values()) + [len(text)]
    damage: list[Damage] = []
    for match in _DECLARED.finditer(text):
        name = match.group(1).decode("utf-8", "replace")
        if name in blocks and match.start() >= blocks[name]:
            continue  # the object's data block itself, not its declaration
        declared = _TYPE.search(match.group(0))
        kind = declared.group(1).decode("utf-8", "replace") if declared else ""
        if name in {d.name for d in damage} or not _EXPORTED.match(kind):
            continue
        start = blocks.get(name)
        end = starts[bisect.bisect_right(starts, start)] if start is not None else len(text)
        block = text[start:end] if start is not None else b""
        label_found = _LABEL.search(block)
        label = label_found.group(1).decode("utf-8", "replace") if label_found else name
        if start is None or end > error_at and error:
            why = "its data is missing from Document.xml" if not error else f"its data comes after {error}"
            error = error and "that error"  # said once
            damage.append(Damage(name, label, why))
            continue
        for file_match in _FILE.finditer(block):
            member = file_match.group(2).decode("utf-8", "replace")
            if file_match.group(1) == _XLINK:
                problem = _linked_document_problem(path, member, seen)
                if problem:
                    damage.append(Damage(name, label, problem))
                    break
                continue
            if member not in intact:
                why = "the archive is truncated or its directory damaged" if truncated else "the archive lacks it"
                damage.append(Damage(name, label, f"its file {member} is missing ({why})"))
                break
            if not intact[member]:
                damage.append(Damage(name, label, f"its file {member} is unreadable (bad data or checksum)"))
                break
    return damage


def _linked_document_problem(path: Path, name: str, seen: set[Path]) -> str | None:
    """Why the document ``name`` that an object of ``path`` links to cannot be read (None when it can, or
    was checked already): missing beside ``path``, or damaged."""
    if not name:
        return None  # an empty XLink: the link is to an object of this document
    linked = Path(name) if Path(name).is_absolute() else path.parent / name
    if not linked.is_file():
        return f"it links to {name}, which is not in {linked.parent} (copy it beside {path.name})"
    if linked.resolve() in seen:
        return None
    try:
        inner = document_damage(linked, seen)
    except DamagedDocumentError as exc:
        return f"it links to {name}, which cannot be read ({exc})"
    if inner:
        return f"it links to {name}, which is damaged: {'; '.join(str(d) for d in inner)}"
    return None


class _Scanned:
    """The intact members of an archive without a directory, read from their local headers."""

    def __init__(self, data: bytes):
        self._data = data

    def __enter__(self) -> _Scanned:
        return self

    def __exit__(self, *exc) -> None:
        return None

    def read(self, wanted: str) -> bytes:
        at = 0
        data = self._data
        while data[at:at + 4] == b"PK\x03\x04":
            _, _, flags, method, _, _, _, size, _, name_length, extra = _LOCAL.unpack_from(data, at)
            start = at + _LOCAL.size + name_length + extra
            name = data[at + _LOCAL.size:at + _LOCAL.size + name_length].decode("utf-8", "replace")
            if flags & 8:
                body, end, _ = _inflate(data, start, method)
                end += 16 if data[end:end + 4] == b"PK\x07\x08" else 12
            else:
                end = start + size
                body = data[start:end] if method == 0 else zlib.decompress(data[start:end], -15)
            if name == wanted:
                return body
            at = end
        raise KeyError(wanted)


#: What the error recommends when the caller takes ``--skip-damaged`` (``aplan export-freecad``), and when it
#: does not (a command reading the model itself: ``session``, ``stats``, ``simulate``, ...).
SKIP_OPTION = "--skip-damaged exports the rest, leaving these out"
SKIP_BY_EXPORT = ("`aplan export-freecad MODEL -o BUNDLE --skip-damaged` exports the rest, leaving these out; "
                  "then give BUNDLE instead of MODEL")


def check_document(path: str | Path, skip_damaged: bool = False, fix: str = SKIP_OPTION) -> list[str]:
    """Raise :class:`DamagedDocumentError` naming each damaged object of the ``.FCStd`` document ``path``
    (:func:`document_damage`), or, with ``skip_damaged``, return one warning naming each object that will be
    left out. ``fix``: how the error says to export the rest (:data:`SKIP_OPTION` where ``--skip-damaged``
    is accepted, :data:`SKIP_BY_EXPORT` elsewhere). STEP files and other types are not checked (an empty
    list)."""
    path = Path(path)
    if path.suffix.lower() != ".fcstd":
        return []
    damage = document_damage(path)
    if not damage:
        return []
    listed = "; ".join(str(d) for d in damage)
    if not skip_damaged:
        raise DamagedDocumentError(
            f"{path}: the document is damaged, {len(damage)} object(s) cannot be read: {listed}. Open a backup "
            f"(FreeCAD keeps NAME.FCBak) or repair and save it in FreeCAD; {fix}")
    return [f"{path}: the document is damaged; left out {len(damage)} object(s) that cannot be read: {listed}"]
