"""Fastener groups the planner proposes for the designer to accept.

Definition
----------
A part is a *candidate* fastener when

- *name*: its id or label holds one of :data:`FASTENER_WORDS` as a word (``wood_screw_001``, ``HexBolt``,
  ``M6 nut``; case-insensitive, a CamelCase word counts as one), or
- *geometry*: its volume is at most the product's median part volume, and at least two of the parts it
  touches are each :data:`HOST_VOLUME_RATIO` times its volume or more (a small part that joins two others).

A part is never a candidate when

- *rolling element*: its id or label holds one of :data:`ROLLING_WORDS` (``ball``, ``roller``, ``needle``), or
- *own joint*: it is a candidate by geometry only, and a subassembly of the designer's (the document's
  structure: an ``App::Part`` container such as a bearing of rings and balls) holds it together with every
  part it touches: the authors modelled that joint as one component, whose balls or rollers are parts.

Those are listed in :attr:`FastenerProposals.left_out` with the reason. A proposal that folds a member of a
designer's subassembly says so in its ``reason`` (the member and the subassembly).

Candidates that touch one another form one fastener (a bolt, its nut and washer); its hosts are the
non-candidate parts it touches. A host ``X`` of a fastener is its *shaft* (a long bolt held by a washer or nut
stack, passing through a bore with clearance) when

- *stack*: ``X`` touches the fastener and exactly one other part ``H`` (what the shaft is screwed into), and
- *bore*: another host ``G`` of the fastener (what the stack clamps) surrounds ``X``: ``G`` blocks ``X`` both
  ways along at least two direction lines of the obstruction diagrams (``X`` can leave ``G`` along its own
  axis only), and
- *size*: ``H`` and ``G`` are each :data:`HOST_VOLUME_RATIO` times ``X``'s volume or more.

A shaft joins the fastener, whose hosts become ``G`` and ``H`` (the pump's bolts 13_*: a washer 12_* on the
motor 11_001, the bolt through the motor's bore into the body 1_001). A fastener that joins fewer than two
parts is not proposed (it is listed in :attr:`FastenerProposals.left_out` with the reason). Fasteners with the
same hosts make one group (the four screws of one wheel), installed by one operation.

Cost: O(parts log parts + contacts + obstruction pairs).
"""
from __future__ import annotations

import re
import statistics
from dataclasses import dataclass

from .model import FastenerGroup, Part, Product

__all__ = ["FASTENER_WORDS", "ROLLING_WORDS", "HOST_VOLUME_RATIO", "FastenerProposals", "fastener_proposals",
           "propose_fasteners"]

FASTENER_WORDS = ("screw", "bolt", "nut", "washer", "pin", "rivet", "clip")
# Rolling elements of a bearing: small parts between two larger ones that are not fasteners.
ROLLING_WORDS = ("ball", "roller", "needle")

# A fastener is this many times smaller than each of two parts it joins (the truck's screws: 68 and more;
# the pump's bolts: 300 and more; its diaphragm, clamped between two housings, is not a fastener).
HOST_VOLUME_RATIO = 10.0

_WORD = re.compile(r"(?<![a-z])(" + "|".join(FASTENER_WORDS) + r")(e?s)?(?![a-z])")
_ROLLING = re.compile(r"(?<![a-z])(" + "|".join(ROLLING_WORDS) + r")(e?s)?(?![a-z])")


@dataclass(frozen=True)
class FastenerProposals:
    """``groups``: the proposed groups (``source="proposed"``, ``reason`` says why); ``left_out``: candidates
    not proposed, each with the reason."""

    groups: tuple[FastenerGroup, ...]
    left_out: tuple[tuple[str, str], ...]


def _name_word(part: Part, words: re.Pattern = _WORD) -> str | None:
    """The fastener word (or another of ``words``) in the part's id or label, if any."""
    for text in (part.id, part.label):
        spaced = re.sub(r"([a-z])([A-Z])", r"\1 \2", text or "").lower()
        spaced = re.sub(r"[0-9_]+", " ", spaced)  # Ball001, ball_3: the word, then a number
        found = words.search(spaced)
        if found:
            return found.group(1)
    return None


def _designer_structure(product: Product) -> tuple[dict[str, str], dict[str, set[str]]]:
    """Part -> the designer's subassembly that lists it directly, and subassembly -> the parts it holds at any
    depth. Cost: O(subassembly members x depth)."""
    designer = [s for s in product.subassemblies if s.source == "designer"]
    listed = {s.id: s.parts for s in designer}
    parent = {m: s.id for s in designer for m in s.parts}

    def held(sid: str, seen: frozenset = frozenset()) -> set[str]:
        out: set[str] = set()
        for m in listed[sid]:
            out |= held(m, seen | {sid}) if m in listed and m not in seen else {m}
        return out

    return {p: parent[p] for p in product.part_ids if p in parent}, {s: held(s) for s in listed}


def fastener_proposals(product: Product) -> FastenerProposals:
    """The groups of :func:`propose_fasteners` and the candidates left out (see the module's definition).
    Parts already in a fastener group of ``product`` are neither candidates nor hosts."""
    tagged = product.fastener_parts
    touching: dict[str, set[str]] = {p.id: set() for p in product.parts}
    for a, b in product.contacts:
        touching[a].add(b)
        touching[b].add(a)
    volumes = {p.id: p.volume for p in product.parts if p.volume is not None}
    median = statistics.median(volumes.values()) if volumes else None
    in_subassembly, holds = _designer_structure(product)
    why: dict[str, str] = {}
    not_fasteners: list[tuple[str, str]] = []
    for part in product.parts:
        if part.id in tagged:
            continue
        rolling = _name_word(part, _ROLLING)
        if rolling:
            not_fasteners.append((part.id, f"name ({rolling!r}): a rolling element, not a fastener"))
            continue
        word = _name_word(part)
        if word:
            why[part.id] = f"name ({word!r})"
            continue
        volume = volumes.get(part.id)
        if volume is None or median is None or volume > median:
            continue
        big = sorted(n for n in touching[part.id] if n not in tagged
                     and volumes.get(n, 0.0) >= HOST_VOLUME_RATIO * max(volume, 1e-12))
        if len(big) >= 2:
            own = in_subassembly.get(part.id)
            if own is not None and touching[part.id] <= holds[own]:
                not_fasteners.append((part.id, f"geometry (joins {', '.join(big)}), but the designer's subassembly "
                                               f"{own!r} holds it with every part it touches (a bearing's balls, "
                                               "say): left as a part"))
                continue
            ratio = min(volumes[n] for n in big) / max(volume, 1e-12)
            why[part.id] = f"geometry (volume {volume:.4g}, at most the median {median:.4g}; joins {', '.join(big)}, " \
                           f"each {ratio:.0f} times larger or more)"
    for part_id in why:
        if part_id in in_subassembly:
            why[part_id] += f"; folding takes it out of the designer's subassembly {in_subassembly[part_id]!r}"
    enclosing = _enclosing(product)
    fasteners, left_out = [], []
    for members in _touching_groups(sorted(why, key=product.part_ids.index), touching):
        hosts = frozenset(n for m in members for n in touching[m] if n not in why and n not in tagged)
        for shaft, held_by, bore in _shafts(members, hosts, touching, volumes, enclosing, tagged | set(why)):
            why[shaft] = f"geometry (a shaft through the bore of {bore}, held by {', '.join(members)}; " \
                         f"screwed into {held_by})"
            members = sorted([*members, shaft], key=product.part_ids.index)
            hosts = hosts - {shaft} | {held_by}
        if len(hosts) < 2:
            joined = f"only {min(hosts)}" if hosts else "nothing"
            left_out.extend((m, f"{why[m]}, but it joins {joined}: left as a part (check its contacts)")
                            for m in members)
        else:
            fasteners.append((members, hosts))
    return FastenerProposals(_grouped(fasteners, why), tuple(not_fasteners + left_out))


def _enclosing(product: Product) -> dict[str, set[str]]:
    """Part -> the parts that surround it: that block it both ways along two or more direction lines of the
    obstruction diagrams (a bore around a shaft). Cost: O(obstruction pairs)."""
    moves: dict[tuple[str, str], set[tuple[float, ...]]] = {}
    for obstruction in product.obstructions:
        forward = tuple(round(c, 6) for c in obstruction.direction.vector)
        backward = tuple(-c for c in forward)
        for x, y in obstruction.blocks:  # x moving along the direction hits y; y moving back hits x
            moves.setdefault((x, y), set()).add(forward)
            moves.setdefault((y, x), set()).add(backward)
    out: dict[str, set[str]] = {}
    for (x, y), blocked in moves.items():
        lines = {d for d in blocked if tuple(-c for c in d) in blocked and d > tuple(-c for c in d)}
        if len(lines) >= 2:
            out.setdefault(x, set()).add(y)
    return out


def _shafts(members: list[str], hosts: frozenset[str], touching: dict[str, set[str]], volumes: dict[str, float],
            enclosing: dict[str, set[str]], excluded: set[str]) -> list[tuple[str, str, str]]:
    """The hosts of the fastener ``members`` that are shafts (see the module's definition), each as
    (shaft, the part it is screwed into, the host whose bore it passes through)."""
    found = []
    for shaft in sorted(hosts):
        others = touching[shaft] - set(members)
        volume = volumes.get(shaft)
        if len(others) != 1 or volume is None or others & excluded:
            continue
        (held_by,) = others
        big = HOST_VOLUME_RATIO * max(volume, 1e-12)
        bores = sorted(g for g in hosts - {shaft, held_by} if g in enclosing.get(shaft, ()) and volumes.get(g, 0.0) >= big)
        if bores and volumes.get(held_by, 0.0) >= big:
            found.append((shaft, held_by, bores[0]))
    return found


def propose_fasteners(product: Product) -> list[FastenerGroup]:
    """Fastener groups proposed from names and geometry (``source="proposed"``; ``reason`` says why)."""
    return list(fastener_proposals(product).groups)


def _touching_groups(candidates: list[str], touching: dict[str, set[str]]) -> list[list[str]]:
    """The candidates split into sets that touch one another (a bolt with its nut), in candidate order."""
    chosen = set(candidates)
    seen: set[str] = set()
    out = []
    for start in candidates:
        if start in seen:
            continue
        members, stack = [], [start]
        seen.add(start)
        while stack:
            part = stack.pop()
            members.append(part)
            for other in sorted(touching[part] & chosen - seen):
                seen.add(other)
                stack.append(other)
        out.append(sorted(members, key=candidates.index))
    return out


def _grouped(fasteners: list[tuple[list[str], frozenset[str]]], why: dict[str, str]) -> tuple[FastenerGroup, ...]:
    """One group per host set, named after the hosts, in the order of its first fastener."""
    by_hosts: dict[frozenset[str], list[str]] = {}
    for members, hosts in fasteners:
        by_hosts.setdefault(hosts, []).extend(members)
    groups = []
    for hosts, parts in by_hosts.items():
        alike = f" (and {len(parts) - 1} more)" if len(parts) > 1 else ""
        groups.append(FastenerGroup(id="fasteners_" + "+".join(sorted(hosts)), parts=tuple(parts), hosts=hosts,
                                    source="proposed", reason=f"{parts[0]}: {why[parts[0]]}{alike}"))
    return tuple(groups)
