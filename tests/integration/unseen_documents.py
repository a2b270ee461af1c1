"""The FreeCADCmd script that builds assemblies in the styles public models come in (tests/integration/
test_unseen_documents.py, bench/bench_unseen_cad.py): ``TMP = FOLDER`` prepended, it saves ``NAME.FCStd`` there
for each of :data:`DOCUMENTS` (and ``coupling_hidden.FCStd``, the coupling with its link array's elements not
shown as objects, ``coupling.step``, the coupling exported to STEP, and ``one_body.step``, the coupling as one
body of ten solids), and prints
``APLAN-RESULT`` with the parts' labels per document (and the coupling read with the link array's elements
grouped, one nut excluded). ``REPO`` (the repository) is prepended too.

- ``hinge``: two leaves as PartDesign Bodies (additive and subtractive primitives), knuckles interleaved along
  Z with exactly touching end faces, 0.05 mm radial clearance to the other leaf, and a headed pin through them;
- ``coupling``: two round flanges (touching at z = 10) in App::Part containers with nested placements, four
  bolts as an App::Link array of one bolt (shank radius equal to the hole's: touching cylinders), and four nuts
  in a container turned by 90 degrees about Z (their shapes turned back, so they sit on the bolts);
- ``vise``: Part primitives and booleans: a base with a fixed jaw, a sliding jaw on it, a screw through a
  threaded hole of the fixed jaw (the same radius) into the sliding jaw, and a handle bar through the
  screw's head (0.05 mm clearance);
- ``bolt_circle``: the coupling's flanges at radius 160 with a circle of 40 bolts and 40 nuts, each a Draft
  polar array of one plain feature (82 parts: one per array element);
- ``gearbox``: Part booleans, a closed two-shaft gearbox of 14 parts (:data:`GEARBOX`) whose gears float
  once their shafts are out (a support contact each, :mod:`planner.assembly.support_contacts`);
- ``machine``: the gearbox on a base plate with a row of 20 brackets (:data:`MACHINE`, 35 parts): too large
  for the support-contact rule to judge flat, so its gearbox's workstation judges it
  (:mod:`planner.assembly.level_supports`).

The obstruction ground truth of each follows from the construction: :data:`GROUND_TRUTH` (by label).
"""

import math

DOCUMENTS = ("hinge", "coupling", "vise", "bolt_circle", "gearbox", "machine")

#: The gearbox (mm): a housing x 0..100, y 0..60, z 0..60 with a cavity x 10..90, y 10..50 open at the top (z from
#: 10), bores of radius 5 along Y at (x, z) = (32, 30) and (68, 30) through its walls, four blind holes of radius 2
#: at the corners (z 45..60); a cover z 60..65 with four holes, screws (shank radius 2, z 45..65, head radius 4 at
#: z 65..68); per bore a shaft (radius 5, y -15..75), a gear on it inside (radius 18, y 25..35: the two meet at
#: x = 50) and a bearing on each side outside (a ring of radii 5 and 10, y -10..0 and 60..70). The parts come
#: apart one by one, but a gear whose shaft is out touches only the other gear: it rests in the housing.
GEARBOX = "gearbox"
#: The machine: the gearbox standing on a base plate x -300..400, y -50..110, z -10..0, with a row of 20 brackets
#: (10 x 10 x 20 mm at y -40..-30, 18 mm apart, ten on each side of the gearbox) standing on it. The plate and any
#: set of the 20 brackets are connected: at least 2^20 connected part sets, past the support-contact rule's
#: CHECK_LIMIT, so the rule judges the gearbox's workstation, not the flat product (planner.assembly.level_supports).
MACHINE = "machine"
_PLATE = ((-300, -50, -10), (400, 110, 0))
_BRACKETS = [-290 + 28 * k for k in range(10)] + [110 + 28 * k for k in range(10)]


def _machine_truth() -> dict[str, set[tuple[str, str]]]:
    """The machine's diagrams (:data:`MACHINE`): the gearbox's, the plate under everything (moving +Z it hits
    every part), and along X each bracket hits those ahead of it in the row (their shadows across X are the
    same); the brackets' shadows meet no part of the gearbox's, nor the plate's in an area."""
    truth = {axis: set(pairs) for axis, pairs in _gearbox_truth().items()}
    names = [f"Bracket{k + 1}" for k in range(len(_BRACKETS))]
    others = sorted({p for pairs in truth.values() for pair in pairs for p in pair}) + names
    truth["+Z"] |= {("Plate", p) for p in others}
    truth["+X"] |= {(a, b) for i, a in enumerate(names) for b in names[i + 1:]}
    return truth


def _gearbox_truth() -> dict[str, set[tuple[str, str]]]:
    """The gearbox's diagrams from its construction (:data:`GEARBOX`; x moving along +d collides with y when
    their shadows across d overlap in an area and y lies ahead; faces or lines that only touch are no overlap).

    Along Z: the housing's floor lies under everything inside it, the cover over it; a screw's head rests on
    the cover and its shank's tip on the housing; a shaft is held both ways by the housing's bore walls, its
    bearings and its gear around it. Along X: the housing's side walls hold the screws, shafts and gears both
    ways (and the cover its screws); what lies at x = 32 meets what lies at x = 68 (shafts, gears, bearings),
    the screws at x = 5 those at x = 95. Along Y: the shafts slide through their bores, gears and bearings; the
    housing's end walls hold the gears both ways and stand between the bearings (the outer ones, y -10..0, hit
    them moving +Y; the inner, y 60..70, are hit), and a bearing meets the gear and the bearing beyond it; the
    screws at y = 5 meet those at y = 55."""
    screws = [f"Screw{k}" for k in range(1, 5)]
    both = lambda pairs: {p for a, b in pairs for p in ((a, b), (b, a))}  # noqa: E731
    z = {("Housing", "Cover")} | {(h, s) for s in screws for h in ("Housing", "Cover")}
    x = both([(s, h) for s in screws for h in ("Housing", "Cover")]) | {("Screw1", "Screw2"), ("Screw3", "Screw4")}
    y = both([(s, h) for s in screws for h in ("Housing", "Cover")]) | {("Screw1", "Screw3"), ("Screw2", "Screw4")}
    for k in "AB":
        shaft, gear, outer, inner = f"Shaft{k}", f"Gear{k}", f"Bearing{k}1", f"Bearing{k}2"
        z |= both([(shaft, "Housing"), (shaft, gear), (shaft, outer), (shaft, inner)])
        z |= {("Housing", gear), (shaft, "Cover"), (gear, "Cover")}
        x |= both([(shaft, "Housing"), (gear, "Housing"), (shaft, gear), (shaft, outer), (shaft, inner)])
        y |= both([(gear, "Housing")]) | {(outer, "Housing"), ("Housing", inner), (outer, gear), (gear, inner),
                                          (outer, inner)}
    x |= {("ShaftA", "ShaftB"), ("GearA", "GearB"), ("ShaftA", "GearB"), ("GearA", "ShaftB"),
          ("BearingA1", "BearingB1"), ("BearingA2", "BearingB2")}
    x |= {(bearing, "ShaftB") for bearing in ("BearingA1", "BearingA2")}
    x |= {("ShaftA", bearing) for bearing in ("BearingB1", "BearingB2")}
    return {"+X": x, "+Y": y, "+Z": z}

#: Bolt centres of the coupling: the four corners (+-A, +-A) of a square (A = 20).
_A = 20
_BOLTS = [(-_A, -_A), (_A, -_A), (-_A, _A), (_A, _A)]


#: Bolt circle of the ``bolt_circle`` document: N bolts at radius R, the first at angle 0 (Draft's polar array).
_CIRCLE_N, _CIRCLE_R = 40, 150.0
_CIRCLE = [(_CIRCLE_R * math.cos(2 * math.pi * k / _CIRCLE_N), _CIRCLE_R * math.sin(2 * math.pi * k / _CIRCLE_N))
           for k in range(_CIRCLE_N)]


def _coupling_truth(centres, bolts: list[str], nuts: list[str]) -> dict[str, set[tuple[str, str]]]:
    """A flange coupling's diagrams (x moving along +d collides with y), from its construction: flanges FA
    (z 0..10) and FB (z 10..20) with holes of radius 3 at ``centres``, bolts (head radius 5 at z -4..0 under FA,
    shank radius 3 up to z 24) and nuts (radius 5 with a hole of 3, z 20..24 on FB), ``bolts[k]`` and
    ``nuts[k]`` at ``centres[k]``.

    Along Z a bolt's head pushes both flanges and its nut, the flanges the nuts, FA the FB. Across (X, Y) a
    shank is held by both flanges and its nut. Moved along +X, a cylinder of radius r1 at (x1, y1) meets one of
    radius r2 further along X when their shadows on the YZ plane overlap: |y1 - y2| < r1 + r2 and their z
    ranges overlap (head with head, shank with shank and nut, nut with nut); the same across Y. A gap within
    0.01 of a threshold is refused (the truth would then hang on rounding)."""
    z = {("FA", "FB")}
    for bolt, nut in zip(bolts, nuts):
        z |= {("FA", nut), ("FB", nut), (bolt, "FA"), (bolt, "FB"), (bolt, nut)}
    truth = {"+Z": z}
    for axis, along, across in (("+X", 0, 1), ("+Y", 1, 0)):
        pairs = set()
        for k, (bolt, nut) in enumerate(zip(bolts, nuts)):
            pairs |= {(bolt, "FA"), (bolt, "FB"), ("FA", bolt), ("FB", bolt), (bolt, nut), (nut, bolt)}
            for j, (other, other_nut) in enumerate(zip(bolts, nuts)):
                if centres[j][along] <= centres[k][along] + 1e-9:
                    continue
                gap = abs(centres[j][across] - centres[k][across])
                assert all(abs(gap - limit) > 0.01 for limit in (8, 10)), (bolt, other, gap)
                if gap < 10:    # heads with heads (bolts), nuts with nuts
                    pairs |= {(bolt, other), (nut, other_nut)}
                if gap < 8:     # a shank with the other's nut, a nut with the other's shank
                    pairs |= {(bolt, other_nut), (nut, other)}
        truth[axis] = pairs
    return truth


#: x moving along +d without limit collides with y: the hinge's relations from its construction. Leaf A
#: (plate x -30..0, knuckles z 0..10 and 20..30 of radius 3 about the Z axis), leaf B (plate x 0..30, knuckle
#: z 10..20), the pin (shank radius 1.5, z 0..30, head radius 2.5 on A at z 30..31.5). Along X, A's knuckles
#: meet B's plate and B's knuckle A's plate only moving towards each other; along Y each knuckle is caught by
#: the other plate's lips (the clearance cut of radius 3.05 leaves plate at |y| > 0.94 for x below 3.05, where
#: the knuckle reaches |y| 0.77 at x 2.9); along Z the knuckles alternate, and the head stops the pin going down.
_HINGE = {"+X": {("LeafA", "LeafB"), ("Pin", "LeafA"), ("Pin", "LeafB"), ("LeafA", "Pin"), ("LeafB", "Pin")},
          "+Y": {("LeafA", "LeafB"), ("LeafB", "LeafA"), ("Pin", "LeafA"), ("Pin", "LeafB"), ("LeafA", "Pin"),
                 ("LeafB", "Pin")},
          "+Z": {("LeafA", "LeafB"), ("LeafB", "LeafA"), ("LeafA", "Pin"), ("LeafB", "Pin")}}


def _vise_truth() -> dict[str, set[tuple[str, str]]]:
    """The vise's diagrams from its construction (coordinates in :data:`SCRIPT`): the base (x 0..100, y 0..40,
    z 0..10), the fixed jaw on it (x 0..15, z 10..40), the sliding jaw on it (x 50..65, z 10..40), the screw
    along X at (y 20, z 25) (shank radius 5, x -20..60, into a blind bore of the sliding jaw; head radius 8 at
    x -30..-20), the handle bar along Y through the head (radius 2 in a bore of 2.05, y 0..40).

    The jaws and the screw's shank stand over the base; the screw and the bar are held across their axes by
    what surrounds them."""
    z = {("Base", "FixedJaw"), ("Base", "SlidingJaw"), ("Base", "Screw"), ("Bar", "Screw"), ("Screw", "Bar")}
    for holder in ("FixedJaw", "SlidingJaw"):
        z |= {("Screw", holder), (holder, "Screw")}
    # Along X: the fixed jaw slides along the shank (a through hole) but not past the head; the sliding jaw's
    # blind bore stops the screw; the bar in the head meets both jaws and holds the screw both ways.
    x = {("FixedJaw", "SlidingJaw"), ("Screw", "SlidingJaw"), ("Screw", "FixedJaw"), ("Bar", "FixedJaw"),
         ("Bar", "SlidingJaw"), ("Screw", "Bar"), ("Bar", "Screw")}
    # Along Y: the screw in the jaws' bores both ways; the bar slides along its own axis.
    y = {("Screw", "FixedJaw"), ("FixedJaw", "Screw"), ("Screw", "SlidingJaw"), ("SlidingJaw", "Screw")}
    return {"+X": x, "+Y": y, "+Z": z}


GROUND_TRUTH = {"hinge": _HINGE, "vise": _vise_truth(), "gearbox": _gearbox_truth(), "machine": _machine_truth(),
                "coupling": _coupling_truth(_BOLTS, [f"Bolt_i{k}" for k in range(4)],
                                            [f"Nut{k + 1}" for k in range(4)]),
                "bolt_circle": _coupling_truth(_CIRCLE, [f"Bolts_{k + 1:03d}" for k in range(_CIRCLE_N)],
                                               [f"Nuts_{k + 1:03d}" for k in range(_CIRCLE_N)])}

#: The STEP file names the link array's elements after the object they show (FreeCAD's STEP export).
STEP_NAMES = {f"BoltSource{'' if k == 0 else f'{k:03d}'}": f"Bolt_i{k}" for k in range(4)}
#: The one body's solids, in the order they were put in it: the coupling's parts.
ONE_BODY = {f"Coupling_{k + 1:03d}": name for k, name in enumerate(
    ["FA", "FB"] + [f"Bolt_i{k}" for k in range(4)] + [f"Nut{k + 1}" for k in range(4)])}

SCRIPT = r"""
import json, os
import FreeCAD, Part
V = FreeCAD.Vector
P = FreeCAD.Placement
R = FreeCAD.Rotation
out = {}

def feature(doc, label, shape, container=None):
    obj = doc.addObject("Part::Feature", label)
    obj.Label = label
    obj.Shape = shape
    if container is not None:
        container.addObject(obj)
    return obj

def saved(doc, name):
    doc.recompute()
    doc.saveAs(os.path.join(TMP, name + ".FCStd"))
    out[name] = sorted(o.Label for o in doc.Objects)

# Hinge: PartDesign Bodies.
doc = FreeCAD.newDocument("hinge")
def body(label, plate_x, knuckles, clear):
    b = doc.addObject("PartDesign::Body", label)
    b.Label = label
    plate = doc.addObject("PartDesign::AdditiveBox", label + "Plate")
    plate.Length, plate.Width, plate.Height = 30, 2, 30
    plate.Placement = P(V(plate_x, -1, 0), R())
    b.addObject(plate)
    for k, z in enumerate(knuckles):
        knuckle = doc.addObject("PartDesign::AdditiveCylinder", f"{label}Knuckle{k}")
        knuckle.Radius, knuckle.Height = 3, 10
        knuckle.Placement = P(V(0, 0, z), R())
        b.addObject(knuckle)
    for k, z in enumerate(clear):
        gap = doc.addObject("PartDesign::SubtractiveCylinder", f"{label}Clearance{k}")
        gap.Radius, gap.Height = 3.05, 10
        gap.Placement = P(V(0, 0, z), R())
        b.addObject(gap)
    hole = doc.addObject("PartDesign::SubtractiveCylinder", label + "PinHole")
    hole.Radius, hole.Height = 1.5, 30
    b.addObject(hole)
    return b
body("LeafA", -30, [0, 20], [10])
body("LeafB", 0, [10], [0, 20])
feature(doc, "Pin", Part.makeCylinder(1.5, 30).fuse(Part.makeCylinder(2.5, 1.5, V(0, 0, 30))).removeSplitter())
saved(doc, "hinge")

# Coupling: App::Part containers with nested placements, an App::Link array of bolts.
doc = FreeCAD.newDocument("coupling")
top = doc.addObject("App::Part", "Coupling"); top.Label = "Coupling"
top.Placement = P(V(100, 50, 0), R())
holes = [Part.makeCylinder(3, 30, V(x, y, -5)) for x, y in BOLTS]
def flange(z):
    shape = Part.makeCylinder(40, 10, V(0, 0, z)).cut(Part.makeCylinder(10, 10, V(0, 0, z)))
    for h in holes:
        shape = shape.cut(h)
    return shape
for label, z in (("FA", 0), ("FB", 10)):
    holder = doc.addObject("App::Part", label + "Holder"); holder.Label = label + "Holder"
    holder.Placement = P(V(0, 0, z), R())
    top.addObject(holder)
    feature(doc, label, flange(0), holder)
bolt = Part.makeCylinder(5, 4, V(0, 0, -4)).fuse(Part.makeCylinder(3, 24)).removeSplitter()
bolts = doc.addObject("App::Part", "Bolts"); bolts.Label = "Bolts"
top.addObject(bolts)
source = feature(doc, "BoltSource", bolt)
source.Visibility = False
array = doc.addObject("App::Link", "Bolt"); array.Label = "Bolt"
array.LinkedObject = source
array.ElementCount = 4
doc.recompute()
for element, (x, y) in zip(array.ElementList, BOLTS):  # PlacementList does not reach the elements headless
    element.Placement = P(V(x, y, 0), R())
bolts.addObject(array)
nuts = doc.addObject("App::Part", "Nuts"); nuts.Label = "Nuts"
nuts.Placement = P(V(0, 0, 20), R(V(0, 0, 1), 90))
top.addObject(nuts)
turn_back = R(V(0, 0, 1), -90)
for k, (x, y) in enumerate(BOLTS):
    c = turn_back.multVec(V(x, y, 0))
    feature(doc, f"Nut{k + 1}", Part.makeCylinder(5, 4, c).cut(Part.makeCylinder(3, 4, c)), nuts)
saved(doc, "coupling")
import sys
sys.path.insert(0, REPO)
from freecad_aplan.document import read_components
grouped = read_components(doc, groups={"bolts": ["Bolt_i*"]}, exclude=["Nut4"]).components
out["coupling_grouped"] = {c.id: len(c.shape.Solids) for c in grouped}
# The same with the array's elements not shown as objects (ShowElement off: no App::LinkElement in the tree).
array.ShowElement = False
doc.recompute()
doc.saveAs(os.path.join(TMP, "coupling_hidden.FCStd"))
import Import
Import.export([top], os.path.join(TMP, "coupling.step"))
# The same coupling as one body of ten solids (a STEP file some CAD systems write), in the order of its parts.
one = [flange(0), flange(10)] + [bolt.translated(V(x, y, 0)) for x, y in BOLTS]
one += [Part.makeCylinder(5, 4, V(x, y, 20)).cut(Part.makeCylinder(3, 4, V(x, y, 20))) for x, y in BOLTS]
body = FreeCAD.newDocument("one_body")
merged = feature(body, "Coupling", Part.makeCompound([s.translated(V(100, 50, 0)) for s in one]))
Import.export([merged], os.path.join(TMP, "one_body.step"))

# Vise: Part primitives and booleans.
doc = FreeCAD.newDocument("vise")
def box(name, lo, size):
    b = doc.addObject("Part::Box", name)
    b.Length, b.Width, b.Height = size
    b.Placement = P(V(*lo), R())
    return b
def cylinder(name, radius, height, base, axis):
    c = doc.addObject("Part::Cylinder", name)
    c.Radius, c.Height = radius, height
    c.Placement = P(V(*base), R(V(0, 0, 1), V(*axis)))
    return c
def labelled(obj, label):
    obj.Label = label
    return obj
labelled(box("Base", (0, 0, 0), (100, 40, 10)), "Base")
fixed = doc.addObject("Part::Cut", "FixedJaw"); fixed.Label = "FixedJaw"
fixed.Base = box("FixedBlock", (0, 0, 10), (15, 40, 30))
fixed.Tool = cylinder("Thread", 5, 15, (0, 20, 25), (1, 0, 0))
sliding = doc.addObject("Part::Cut", "SlidingJaw"); sliding.Label = "SlidingJaw"
sliding.Base = box("SlidingBlock", (50, 0, 10), (15, 40, 30))
sliding.Tool = cylinder("Bore", 5, 10, (50, 20, 25), (1, 0, 0))
screw = doc.addObject("Part::MultiFuse", "Screw"); screw.Label = "Screw"
head = doc.addObject("Part::Cut", "Head")
head.Base = cylinder("HeadBlank", 8, 10, (-30, 20, 25), (1, 0, 0))
head.Tool = cylinder("BarBore", 2.05, 40, (-25, 0, 25), (0, 1, 0))
screw.Shapes = [cylinder("Shank", 5, 80, (-20, 20, 25), (1, 0, 0)), head]
labelled(cylinder("Bar", 2, 40, (-25, 0, 25), (0, 1, 0)), "Bar")
saved(doc, "vise")

# Gearbox: a closed housing of Part booleans, its cover screwed on (see GEARBOX).
SHAFTS = ((32, "A"), (68, "B"))
CORNERS = ((5, 5), (95, 5), (5, 55), (95, 55))
def along_y(radius, y0, length, x, z=30):
    return Part.makeCylinder(radius, length, V(x, y0, z), V(0, 1, 0))
def gearbox(doc):
    housing = Part.makeBox(100, 60, 60).cut(Part.makeBox(80, 40, 50, V(10, 10, 10)))
    for x, _ in SHAFTS:
        housing = housing.cut(along_y(5, 0, 60, x))
    for x, y in CORNERS:
        housing = housing.cut(Part.makeCylinder(2, 15, V(x, y, 45)))
    feature(doc, "Housing", housing)
    cover = Part.makeBox(100, 60, 5, V(0, 0, 60))
    for x, y in CORNERS:
        cover = cover.cut(Part.makeCylinder(2, 5, V(x, y, 60)))
    feature(doc, "Cover", cover)
    for k, (x, y) in enumerate(CORNERS):
        feature(doc, f"Screw{k + 1}", Part.makeCylinder(2, 20, V(x, y, 45)).fuse(
            Part.makeCylinder(4, 3, V(x, y, 65))).removeSplitter())
    for x, name in SHAFTS:
        feature(doc, "Shaft" + name, along_y(5, -15, 90, x))
        feature(doc, "Gear" + name, along_y(18, 25, 10, x).cut(along_y(5, 25, 10, x)))
        for k, y0 in ((1, -10), (2, 60)):
            feature(doc, f"Bearing{name}{k}", along_y(10, y0, 10, x).cut(along_y(5, y0, 10, x)))
doc = FreeCAD.newDocument("gearbox")
gearbox(doc)
saved(doc, "gearbox")

# Machine: the gearbox standing on a base plate with a row of brackets (see MACHINE).
doc = FreeCAD.newDocument("machine")
gearbox(doc)
feature(doc, "Plate", Part.makeBox(PLATE[1][0] - PLATE[0][0], PLATE[1][1] - PLATE[0][1], PLATE[1][2] - PLATE[0][2],
                                   V(*PLATE[0])))
for k, x in enumerate(BRACKETS):
    feature(doc, f"Bracket{k + 1}", Part.makeBox(10, 10, 20, V(x, -40, 0)))
saved(doc, "machine")

# Bolt circle: Draft polar arrays of a bolt and a nut.
import Draft
doc = FreeCAD.newDocument("bolt_circle")
holes = Part.makeCompound([Part.makeCylinder(3, 30, V(x, y, -5)) for x, y in CIRCLE])
for label, z in (("FA", 0), ("FB", 10)):
    feature(doc, label, Part.makeCylinder(160, 10, V(0, 0, z)).cut(Part.makeCylinder(10, 10, V(0, 0, z))).cut(holes))
x0 = CIRCLE[0][0]
bolt = Part.makeCylinder(5, 4, V(x0, 0, -4)).fuse(Part.makeCylinder(3, 24, V(x0, 0, 0))).removeSplitter()
nut = Part.makeCylinder(5, 4, V(x0, 0, 20)).cut(Part.makeCylinder(3, 4, V(x0, 0, 20)))
for label, shape in (("Bolt", bolt), ("Nut", nut)):
    array = Draft.make_polar_array(feature(doc, label, shape), number=len(CIRCLE), angle=360, center=V(0, 0, 0))
    array.Label = label + "s"
saved(doc, "bolt_circle")
print("APLAN-RESULT " + json.dumps(out), flush=True)
""".replace("BOLTS", repr(_BOLTS)).replace("CIRCLE", repr(_CIRCLE)).replace("PLATE", repr(_PLATE)).replace(
    "BRACKETS", repr(_BRACKETS))
