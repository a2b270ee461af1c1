"""A helical spring test document, built in FreeCAD (imported by FreeCADCmd scripts of the tests and the
bench): a base plate, a rod standing on it, a compression spring around the rod (Part::Helix swept with a
circle, Part::Sweep) resting on the plate, and a washer around the rod resting on the spring.

The spring's mesh cannot be within 1 % of its B-rep in the tessellation's work bound (its first mesh is
about 2.6 % short; ``finer`` would need about 190,000 facets; Mefisto, when it ran, was 15 % short), so its
export gives it a fallback rule (:mod:`freecad_aplan.tessellation`): ``hull``, its ring being 2.2 times its
volume at the default pitch 2 and 4.4 at pitch 4 (taken then because its exact shape is over the OCCT
engine's bound, :mod:`freecad_aplan.occt.complexity`)."""
ROD_RADIUS, COIL_RADIUS, WIRE, PITCH, HEIGHT = 8.5, 10.0, 0.6, 2.0, 40.0


def build_spring_document(path: str, pitch: float = PITCH, height: float = HEIGHT) -> dict:
    """Build and save the document at ``path``; returns its object names by role. The parts are placed so
    that the spring touches the plate and the washer (distances measured, not assumed). ``pitch`` and
    ``height`` are the helix's (``height / pitch`` turns; the default: 20 turns of pitch 2)."""
    import FreeCAD
    import Part

    V = FreeCAD.Vector
    doc = FreeCAD.newDocument("spring_rod")
    helix = doc.addObject("Part::Helix", "Helix")
    helix.Pitch, helix.Height, helix.Radius = pitch, height, COIL_RADIUS
    profile = doc.addObject("Part::Circle", "Profile")
    profile.Radius = WIRE
    profile.Placement = FreeCAD.Placement(V(COIL_RADIUS, 0, 0), FreeCAD.Rotation(V(1, 0, 0), 90))
    spring = doc.addObject("Part::Sweep", "Spring")
    spring.Sections, spring.Spine, spring.Solid, spring.Frenet = [profile], helix, True, True
    helix.Visibility = profile.Visibility = False
    doc.recompute()
    shape = spring.Shape
    low = shape.BoundBox.ZMin
    plate = doc.addObject("Part::Box", "Plate")
    plate.Length = plate.Width = 30
    plate.Height = 4
    plate.Placement = FreeCAD.Placement(V(-15, -15, low - 4), FreeCAD.Rotation())
    doc.recompute()
    gap = shape.distToShape(plate.Shape)[0]  # up onto the spring's lowest point (its box is loose)
    plate.Placement = FreeCAD.Placement(V(-15, -15, low - 4 + gap), FreeCAD.Rotation())
    doc.recompute()
    top = float(plate.Placement.Base.z) + 4
    rod = doc.addObject("Part::Cylinder", "Rod")
    rod.Radius, rod.Height = ROD_RADIUS, height + 12
    rod.Placement.Base = V(0, 0, top)
    outer = Part.makeCylinder(COIL_RADIUS + 3, 2, V(0, 0, shape.BoundBox.ZMax))
    inner = Part.makeCylinder(ROD_RADIUS + 0.2, 2, V(0, 0, shape.BoundBox.ZMax))
    washer = doc.addObject("Part::Feature", "Washer")
    washer.Shape = outer.cut(inner)
    doc.recompute()
    gap = shape.distToShape(washer.Shape)[0]
    washer.Placement = FreeCAD.Placement(V(0, 0, -gap), FreeCAD.Rotation())  # down onto its highest point
    doc.recompute()
    doc.saveAs(path)
    assert shape.distToShape(plate.Shape)[0] < 1e-6 and shape.distToShape(washer.Shape)[0] < 1e-6
    names = {"plate": plate.Name, "rod": rod.Name, "spring": spring.Name, "washer": washer.Name}
    FreeCAD.closeDocument(doc.Name)
    return names
