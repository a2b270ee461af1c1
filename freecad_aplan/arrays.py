"""Where a document's objects are and what an array holds: the placement of the containers above an object
(:func:`parent_placement`), the elements of an ``App::Link`` array (:func:`link_elements`) and of a Draft array
(:func:`array_element_solids`), each a part of its own (:func:`freecad_aplan.document.read_components`)."""
from __future__ import annotations

import FreeCAD
import Part

__all__ = ["parent_placement", "link_elements", "array_element_solids", "outward"]


def outward(solid: "Part.Solid") -> "Part.Solid":
    """``solid`` with its faces turned outward: a solid whose orientation is reversed (seen in STEP files: one
    of the 57 solids of the truck's) has a negative volume, which the product file refuses and which would turn its
    mesh inside out; the same solid reversed has the same faces and a positive volume."""
    return solid.reversed() if solid.Volume < 0 else solid


def parent_placement(obj) -> "FreeCAD.Placement":
    """The placement of the containers (App::Part, links) above ``obj``. FreeCAD 0.20's ``App::Link`` has no
    ``getGlobalPlacement``: for it, the global placement of the container whose group holds it."""
    try:
        return obj.getGlobalPlacement().multiply(obj.Placement.inverse())
    except AttributeError:
        for parent in obj.InList:
            if parent.hasExtension("App::GeoFeatureGroupExtension") and obj in parent.Group:
                return parent_placement(parent).multiply(parent.Placement)
        return FreeCAD.Placement()
    except Exception:
        return FreeCAD.Placement()


def link_elements(obj) -> list[tuple[str, str | None, "Part.Shape"]]:
    """The elements of a link array (an ``App::Link`` with ``ElementCount`` > 0) as (label, internal name,
    solids in global coordinates: the array's containers, the array's and the element's placements), those
    without solids left out; [] for any other object. An array whose elements are not shown as objects
    (``ShowElement`` off) names them ``LABEL_iK`` as FreeCAD would, without an internal name. Cost: one shape
    copy per element."""
    count = getattr(obj, "ElementCount", 0) if obj.isDerivedFrom("App::Link") else 0
    if not count:
        return []
    parent = parent_placement(obj)
    shown = list(obj.ElementList)
    found = []
    for k in range(count):
        shape = Part.getShape(obj, f"{k}.", needSubElement=True, transform=True)
        if shape is None or shape.isNull() or not shape.Solids:
            continue
        solids = [outward(s.copy()) for s in shape.Solids]
        compound = (solids[0] if len(solids) == 1 else Part.makeCompound(solids)).copy()
        if not parent.isIdentity():
            compound.Placement = parent.multiply(compound.Placement)
        element = shown[k] if k < len(shown) else None
        found.append((element.Label if element else f"{obj.Label}_i{k}", element.Name if element else None,
                      compound))
    return found


#: Draft's array features (their proxies' classes): ortho, polar, circular, path and point arrays.
_DRAFT_ARRAYS = ("Array", "PathArray", "PathTwistedArray", "PointArray")


def array_element_solids(obj, shape) -> list[list]:
    """The solids of each element of a Draft array (``Draft.make_*_array``, linked or not), in order: its shape
    holds the base's solids once per element; [] for any other object, or an array whose solid count is no
    multiple of its base's. Cost: one pass over the solids."""
    if type(getattr(obj, "Proxy", None)).__name__ not in _DRAFT_ARRAYS:
        return []
    base = getattr(obj, "Base", None)
    per = len(base.Shape.Solids) if base is not None and hasattr(base, "Shape") else 1
    solids = shape.Solids
    if per < 1 or len(solids) % per or len(solids) <= per:
        return []
    return [solids[k:k + per] for k in range(0, len(solids), per)]
