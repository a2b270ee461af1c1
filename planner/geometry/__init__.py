"""Geometry: the connection diagram and the obstruction diagrams along +/-X, Y, Z from part meshes (the mesh
engine, :mod:`.mesh_engine`, with its :mod:`.tolerances`), product bundles (a product file with one mesh
per part) that carry them (:mod:`.bundle`), and the gaps between parts (:mod:`.gaps`) with what an analysis
does with them: ``--contact auto``, the gap record, the warning when too much touches (:mod:`.clearances`)."""
from .bundle import (
           ENGINES,
           PRODUCT_FILE,
           analyze_product,
           apply_report,
           bundle_product_path,
           is_analysed,
           load_part_meshes,
)
from .gaps import Gap, GapReport, contact_tolerance_for, mesh_gaps
from .mesh_engine import AXES, GeometryError, GeometryReport, PartMesh, analyze_meshes
from .tolerances import AUTO, Tolerances

__all__ = ["ENGINES", "PRODUCT_FILE", "analyze_product", "apply_report", "bundle_product_path", "is_analysed",
           "load_part_meshes", "AXES", "GeometryError", "GeometryReport", "PartMesh", "Tolerances", "analyze_meshes",
           "AUTO", "Gap", "GapReport", "contact_tolerance_for", "mesh_gaps"]
