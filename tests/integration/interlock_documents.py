"""The FreeCADCmd script that builds the interlock test documents (tests/integration/test_interlock_documents.py,
bench/bench_interlocks.py): ``TMP = FOLDER`` prepended, it saves ``DOCUMENT.FCStd`` there for each of
:data:`DOCUMENTS` and prints ``APLAN-RESULT`` with the closed-form checks (OCCT's overlap volume of the press
fit, FreeCAD's rotation of the spline's axis)."""

DOCUMENTS = ("press_fit", "splined_hub", "captured", "caged_ball")

SCRIPT = r"""
import json, os
import FreeCAD, Part
V = FreeCAD.Vector
out = {}

def save(name, shapes):
    doc = FreeCAD.newDocument(name)
    for label, shape in shapes:
        obj = doc.addObject("Part::Feature", label)
        obj.Label = label
        obj.Shape = shape
    doc.recompute()
    doc.saveAs(os.path.join(TMP, name + ".FCStd"))
    FreeCAD.closeDocument(doc.Name)

block = Part.makeBox(40, 40, 20).cut(Part.makeCylinder(5, 15, V(20, 20, 5)))
pin = Part.makeCylinder(5.1, 25, V(20, 20, 5))
out["press_fit_overlap"] = block.common(pin).Volume
save("press_fit", [("Block", block), ("Pin", pin)])

shaft = Part.makeCylinder(8, 60, V(0, 0, -30))
hub = Part.makeCylinder(20, 20, V(0, 0, -10)).cut(Part.makeCylinder(8, 20, V(0, 0, -10)))
for k in range(6):
    turn = FreeCAD.Placement(V(0, 0, 0), FreeCAD.Rotation(V(0, 0, 1), 60 * k))
    tooth = Part.makeBox(3, 4, 60, V(7, -2, -30)); tooth.Placement = turn.multiply(tooth.Placement)
    way = Part.makeBox(3, 3.6, 20, V(7, -1.8, -10)); way.Placement = turn.multiply(way.Placement)
    shaft = shaft.fuse(tooth)
    hub = hub.cut(way)
tilt = FreeCAD.Placement(V(0, 0, 0), FreeCAD.Rotation(20, 30, 0))
shaft, hub = shaft.removeSplitter(), hub.removeSplitter()
shaft.Placement = tilt; hub.Placement = tilt
axis = tilt.Rotation.multVec(V(0, 0, 1))
out["spline_axis"] = [axis.x, axis.y, axis.z]
save("splined_hub", [("Shaft", shaft), ("Hub", hub)])

housing = Part.makeBox(60, 60, 20).cut(Part.makeBox(40, 40, 10, V(10, 10, 10)))
cover = Part.makeBox(60, 60, 5, V(0, 0, 20)).cut(Part.makeCylinder(4, 5, V(30, 30, 20)))
bolts = []
for k, (x, y) in enumerate([(5, 5), (55, 5), (5, 55), (55, 55)]):
    housing = housing.cut(Part.makeCylinder(2.5, 10, V(x, y, 10)))
    cover = cover.cut(Part.makeCylinder(2.5, 5, V(x, y, 20)))
    bolt = Part.makeCylinder(2.5, 15, V(x, y, 10)).fuse(Part.makeCylinder(4.5, 3, V(x, y, 25))).removeSplitter()
    bolts.append((f"Bolt{k + 1:03d}", bolt))
knob = Part.makeCylinder(10, 4, V(30, 30, 16)).fuse(Part.makeCylinder(4, 5, V(30, 30, 20))).fuse(
    Part.makeCylinder(8, 3, V(30, 30, 25))).removeSplitter()
save("captured", [("Housing", housing), ("Cover", cover), ("Knob", knob)] + bolts)

save("caged_ball", [("Cage", Part.makeSphere(10).cut(Part.makeSphere(6))), ("Ball", Part.makeSphere(6))])
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""
