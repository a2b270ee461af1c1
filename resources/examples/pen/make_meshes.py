"""The meshes of the embedded pen example, built from solids of revolution (run it to rewrite ``meshes/``).

Bourjault's ballpoint pen has six parts, all solids of revolution about the X axis. Each part here is a
*half-section outline*: a closed polygon of points ``(x, r)`` (axial position, radius, in mm) traversed
counter-clockwise in the (x, r) half-plane, revolved about the X axis with ``SEGMENTS`` facets around. A
point with ``r = 0`` lies on the axis and becomes one vertex (a cone tip or the centre of an end disc).

The dimensions are those of the real (simplified) pen model, rounded to 0.1 mm; the outlines are written
here, not read from its CAD files. They keep the pen's relations:

- the five liaisons touch along exactly coincident surfaces, with identical tessellations (the same
  angles for every ring): the ink fills the cartridge's bore (r 6); the head's spigot (r 6) enters the
  cartridge and its step at x 21.7 meets the cartridge's end; the head's neck (r 12) enters the body's bore
  and its shoulder at x 16.7 meets the body's end; the cap's bore (r 15) slides on the body; the button's
  plug (r 12) enters the body's bore and its collar meets the body's rear end;
- all other pairs keep clear gaps of 1 mm or more (the head's shoulder, r 14, is 1 mm inside the cap's bore;
  the ink ends 2.5 mm short of the head's spigot; the cartridge, r 9, is 3 mm inside the body's bore, r 12).

``planner.geometry.analyze_meshes`` on these meshes gives the pen's connection diagram and its +X, +Y, +Z
obstruction diagrams (those of ``pen.json``, equal to the ground truth shipped with the pen model).

Output: ``meshes/<part id>.stl``, binary STL in mm, float32 vertices. The bytes are the same on every run
and do not depend on trimesh's or manifold3d's version (the mesh and the file are written here with numpy).

Usage: ``python make_meshes.py [--out DIR]``.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

__all__ = ["SEGMENTS", "PROFILES", "revolve", "pen_meshes", "mesh_volume", "write_stl", "write_meshes", "main"]

HERE = Path(__file__).resolve().parent

SEGMENTS = 48  # facets around the axis; a multiple of 4, so that the +Y and +Z views are the same

# Half-section outlines (x, r) in mm, counter-clockwise in the (x, r) half-plane.
PROFILES: dict[str, tuple[tuple[float, float], ...]] = {
    # A rod inside the cartridge's bore, 2.5 mm behind the head's spigot and 2.5 mm inside the rear end.
    "ink": ((29.2, 0.0), (109.2, 0.0), (109.2, 6.0), (29.2, 6.0)),
    # A tube, bore r 6, outer r 9, open at both ends.
    "cartridge": ((21.7, 6.0), (111.7, 6.0), (111.7, 9.0), (21.7, 9.0)),
    # A cone (tip at x 0, r 14 at x 16.7), a neck r 12 into the body, a spigot r 6 into the cartridge.
    "head": ((0.0, 0.0), (26.7, 0.0), (26.7, 6.0), (21.7, 6.0), (21.7, 12.0), (16.7, 12.0), (16.7, 14.0)),
    # A tube, bore r 12, outer r 15, open at both ends.
    "body": ((16.7, 12.0), (186.7, 12.0), (186.7, 15.0), (16.7, 15.0)),
    # A cup closed at -X: outer r 18, bore r 15 from x -23.3 to its mouth at x 46.7 (over the body).
    "cap": ((-33.3, 0.0), (-23.3, 0.0), (-23.3, 15.0), (46.7, 15.0), (46.7, 18.0), (-33.3, 18.0)),
    # A plug r 12 into the body's bore and a collar r 15 behind the body.
    "button": ((182.7, 0.0), (194.7, 0.0), (194.7, 15.0), (186.7, 15.0), (186.7, 12.0), (182.7, 12.0)),
}


def _ring(segments: int) -> np.ndarray:
    """(segments, 2) float64 unit directions (cos, sin) at angles 2 pi k / segments, exactly symmetric
    under quarter turns (the first quadrant is computed, the others are its exact rotations)."""
    if segments < 4 or segments % 4:
        raise ValueError(f"segments must be a positive multiple of 4, got {segments}")
    angle = 2 * np.pi * np.arange(segments // 4) / segments
    c, s = np.cos(angle), np.sin(angle)
    c[0], s[0] = 1.0, 0.0
    return np.concatenate([np.stack(q, axis=1) for q in ((c, s), (-s, c), (-c, -s), (s, -c))])


def revolve(profile, segments: int = SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """The closed triangle mesh of a half-section outline revolved about the X axis.

    ``profile``: (p, 2) points ``(x, r)``, ``r >= 0``, counter-clockwise in the (x, r) half-plane, not
    closed (the last point joins the first); points with ``r = 0`` are on the axis. Returns ``vertices``
    (v, 3) float64 and ``faces`` (f, 3) int64, outward oriented. An edge between two ring points becomes
    ``2 segments`` triangles, an edge between a ring point and an axis point a fan of ``segments``.
    """
    profile = np.asarray(profile, dtype=np.float64)
    if profile.ndim != 2 or profile.shape[1] != 2 or len(profile) < 3 or np.any(profile[:, 1] < 0):
        raise ValueError(f"profile must be (p >= 3, 2) points (x, r >= 0), got {profile.tolist()}")
    ring = _ring(segments)
    vertices, rings = [], []  # rings[i]: the vertex index of profile point i at each angle
    count = 0
    for x, r in profile:
        if r == 0:
            vertices.append([[x, 0.0, 0.0]])
            rings.append(np.full(segments, count))
            count += 1
        else:
            vertices.append(np.column_stack([np.full(segments, x), r * ring]))
            rings.append(count + np.arange(segments))
            count += segments
    faces = []
    for i in range(len(profile)):
        a, b = rings[i], rings[(i + 1) % len(profile)]
        a1, b1 = np.roll(a, -1), np.roll(b, -1)
        # Quad (a, b, b1, a1) along the edge, split on its diagonal a-b1; a quad with an axis point
        # degenerates into one triangle, an edge along the axis into none.
        for tri in (np.stack([a, b, b1], axis=1), np.stack([a, b1, a1], axis=1)):
            keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
            faces.append(tri[keep])
    return np.concatenate(vertices), np.concatenate(faces).astype(np.int64)


def mesh_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by a closed, outward-oriented mesh (sum of signed tetrahedra)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def pen_meshes(segments: int = SEGMENTS) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Part id -> (vertices (v, 3) float64, faces (f, 3) int64), in mm, vertices rounded to float32 (the
    values the STL files hold, so volumes computed here equal those of the files)."""
    out = {}
    for part, profile in PROFILES.items():
        vertices, faces = revolve(profile, segments)
        out[part] = (vertices.astype(np.float32).astype(np.float64), faces)
    return out


_STL = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


def write_stl(path: Path, vertices: np.ndarray, faces: np.ndarray, name: str = "") -> None:
    """Write a binary STL: an 80-byte header (``name``), the triangle count, then per triangle its unit
    normal, its three vertices (float32) and a zero attribute."""
    triangles = vertices[faces]
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    records = np.zeros(len(faces), dtype=_STL)
    records["normal"] = normal
    records["vertices"] = triangles
    header = f"APLAN pen example: {name}, revolved by make_meshes.py".encode("ascii")[:80].ljust(80, b" ")
    with open(path, "wb") as stream:
        stream.write(header)
        stream.write(np.uint32(len(faces)).astype("<u4").tobytes())
        stream.write(records.tobytes())


def write_meshes(directory: Path = HERE / "meshes", segments: int = SEGMENTS) -> dict[str, Path]:
    """Write ``<directory>/<part id>.stl`` for every part; returns part id -> path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = {}
    for part, (vertices, faces) in pen_meshes(segments).items():
        paths[part] = directory / f"{part}.stl"
        write_stl(paths[part], vertices, faces, part)
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Write the pen example's part meshes (binary STL, mm).")
    parser.add_argument("--out", type=Path, default=HERE / "meshes", help="output folder (default: %(default)s)")
    args = parser.parse_args(argv)
    paths = write_meshes(args.out)
    meshes = pen_meshes()
    for part, path in paths.items():
        vertices, faces = meshes[part]
        print(f"{path}: {len(faces)} triangles, volume {mesh_volume(vertices, faces):.3f} mm^3")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
