"""Several parts made one component of a product, after its diagrams are known (what ``--group`` does on export,
done on the product: the interlock rules' last resort, :mod:`planner.assembly.interlocks`).

Definition. Merging parts ``M`` into component ``c``: ``c`` replaces every member of ``M`` wherever a part id
appears (contacts, obstruction pairs, technical constraints, operation tags, subassembly members, fastener
hosts, markers); relations inside ``M`` vanish (``c`` touches or blocks itself), duplicates collapse to one.
``c`` has no mesh (it is no single solid of the model) and the members' summed volume and mass.
"""
from __future__ import annotations

from dataclasses import replace

from ..errors import PlannerError
from .model import Markers, Obstruction, OperationTag, Part, Product, TechnicalConstraint

__all__ = ["merge_parts"]


def merge_parts(product: Product, name: str, members: tuple[str, ...], label: str = "") -> Product:
    """``product`` with ``members`` (two or more part ids) merged into the part ``name`` (module docstring),
    placed where the first member was. Raises :class:`PlannerError` when a member is not a part, is a fastener
    (a fastener is installed by an operation, never part of a component), or ``name`` is taken.
    Cost: O(size of the product)."""
    ids = set(product.part_ids)
    unknown = [m for m in members if m not in ids]
    if len(set(members)) < 2 or unknown:
        raise PlannerError(f"cannot make one component of {', '.join(members)}: "
                           + (f"{', '.join(unknown)} not a part" if unknown else "two parts or more are needed"))
    fasteners = [m for m in members if m in product.fastener_parts]
    if fasteners:
        raise PlannerError(f"cannot make one component of {', '.join(members)}: {', '.join(fasteners)} is a "
                           "fastener (installed by an operation, not part of a component)")
    if name in ids - set(members) or name in {g.id for g in product.subassemblies} | {t.id for t in product.tools}:
        raise PlannerError(f"cannot make one component {name!r}: the name is taken")
    inside = set(members)

    def to(part: str) -> str:
        return name if part in inside else part

    by_id = {p.id: p for p in product.parts}
    volumes = [by_id[m].volume for m in members]
    masses = [by_id[m].mass for m in members]
    merged = Part(name, label or " + ".join(by_id[m].label or m for m in members), None, None,
                  sum(volumes) if None not in volumes else None, sum(masses) if None not in masses else None)
    parts = tuple(merged if p.id == members[0] else p for p in product.parts if p.id not in inside - {members[0]})
    contacts = _pairs(product.contacts, to)
    obstructions = tuple(Obstruction(o.direction, _pairs(o.blocks, to, ordered=True)) for o in product.obstructions)
    constraints = []
    for c in product.technical_constraints:
        mapped, requires = frozenset(map(to, c.parts)), to(c.requires)
        if requires not in mapped:  # one the component settles itself is dropped
            constraints.append(TechnicalConstraint(mapped, requires, c.active, c.reason))
    operations = tuple(OperationTag((frozenset(map(to, t.inputs[0])), frozenset(map(to, t.inputs[1]))),
                                    t.unfavorable, t.robot, t.tool)
                       for t in product.operations
                       if not frozenset(map(to, t.inputs[0])) & frozenset(map(to, t.inputs[1])))
    subassemblies = tuple(replace(g, parts=tuple(dict.fromkeys(map(to, g.parts)))) for g in product.subassemblies)
    fastener_groups = tuple(replace(g, hosts=frozenset(map(to, g.hosts))) for g in product.fasteners)
    markers = product.markers
    if markers is not None:
        kept: dict[str, int] = {}
        for item, marker in markers.ids:
            kept.setdefault(to(item), marker)  # the first member's marker stands for the component
        markers = Markers(tuple(kept.items()), markers.dictionary)
    return replace(product, parts=parts, contacts=contacts, obstructions=obstructions,
                   technical_constraints=tuple(constraints), operations=operations, subassemblies=subassemblies,
                   fasteners=fastener_groups, markers=markers)


def _pairs(pairs, to, ordered: bool = False) -> tuple[tuple[str, str], ...]:
    seen: dict = {}
    for a, b in pairs:
        x, y = to(a), to(b)
        if x != y:
            seen.setdefault((x, y) if ordered else frozenset((x, y)), (x, y))
    return tuple(seen.values())
