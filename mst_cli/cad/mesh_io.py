"""Triangle meshes: tessellation of a B-rep solid (OCP, build123d) and welding (trimesh), for the
CAD path; the closed-mesh test and binary STL (numpy only, so that writing a mesh built by
:mod:`mst_cli.cad.mesh_body` imports no mesh library).

Output is deterministic: the same solid and tolerance give the same vertices (welded in
first-seen order) and triangles, so byte-identical STL files. The 3MF and STEP writers, which
need more care for that, are in :mod:`mst_cli.cad.deterministic`; their names are re-exported
here for the callers that write all the mesh files from one module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mst_cli.cad.deterministic import (
    PRUSA_CUSTOM_GCODE_MEMBER,
    PRUSA_PAUSE_PRINT_TYPE,
    STEP_TIMESTAMP,
    prusa_pause_xml,
    three_mf_bytes,
    write_step,
)

if TYPE_CHECKING:
    from build123d import Solid

__all__ = ["PRUSA_CUSTOM_GCODE_MEMBER", "PRUSA_PAUSE_PRINT_TYPE", "STEP_TIMESTAMP", "is_closed_oriented",
           "merge_vertices", "prusa_pause_xml", "stl_bytes", "tessellate", "three_mf_bytes", "write_step"]

STL_HEADER = "mst sensor body, mm"
# largest angle (rad) one mesh segment of a curved surface spans, in both meshers
ANGULAR_TOLERANCE_RAD = 0.1


def tessellate(solid: Solid, tolerance_mm: float,
               angular_tolerance_rad: float = ANGULAR_TOLERANCE_RAD) -> tuple[np.ndarray, np.ndarray]:
    """Indexed triangle mesh of ``solid`` with outward normals.

    OCCT's incremental mesher discretises every edge once and shares it between the two
    faces it bounds, so the faces' meshes meet vertex to vertex; welding equal coordinates
    gives a closed mesh. ``tolerance_mm`` is the largest chord deviation from the surface.

    Returns
    -------
    vertices : (n, 3) float64 array, mm
    triangles : (m, 3) int64 array of vertex indices, counter-clockwise seen from outside
    """
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    # Mesh here rather than in build123d's Shape.mesh, which asks for a *relative* deflection:
    # --stl-tolerance and the pocket's volume tolerance in export.json are absolute (mm).
    # Shape.tessellate then finds a fine enough triangulation and only reads it back.
    BRepMesh_IncrementalMesh(solid.wrapped, tolerance_mm, False, angular_tolerance_rad, False)
    points, corners = solid.tessellate(tolerance_mm, angular_tolerance_rad)
    vertices = np.array([tuple(p) for p in points], dtype=float).reshape(-1, 3)
    triangles = np.array(corners, dtype=np.int64).reshape(-1, 3)
    _keep_corner_order(solid, triangles)
    return merge_vertices(vertices, triangles)


def _keep_corner_order(solid, triangles: np.ndarray) -> None:
    """Start each triangle of a reversed face at the corner mst has always written first.

    build123d lists a reversed face's triangle (n1, n3, n2), mst wrote (n3, n2, n1): the same
    oriented triangle, but STL and 3MF store the corner order, so exports of a design would
    change bytes without changing shape. Rolled in place, face by face as build123d lists them.
    """
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    faces = [f.wrapped for f in solid.faces()]
    counts = [BRep_Tool.Triangulation_s(f, TopLoc_Location()).NbTriangles() for f in faces]
    reversed_ = np.repeat([f.Orientation() == TopAbs_REVERSED for f in faces], counts)
    triangles[reversed_] = np.roll(triangles[reversed_], -1, axis=1)


def _trimesh(vertices: np.ndarray, triangles: np.ndarray):
    import trimesh
    # process=False: trimesh must not reorder, weld or drop anything behind our back
    return trimesh.Trimesh(vertices=vertices, faces=triangles, process=False)


def merge_vertices(vertices: np.ndarray, triangles: np.ndarray, digits: int = 9) -> tuple[np.ndarray, np.ndarray]:
    """Weld vertices whose coordinates agree to ``digits`` decimals (mm) (trimesh, which keeps
    the first-seen order, so the result is deterministic); drop triangles that collapse."""
    mesh = _trimesh(vertices, triangles)
    mesh.merge_vertices(digits_vertex=digits)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    # a triangle whose corners welded together has no area: by index, not by a size tolerance
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return np.asarray(mesh.vertices, dtype=float), faces[keep]


def directed_edges(triangles: np.ndarray) -> np.ndarray:
    """(3m, 2) directed edges (a, b) of the triangles, each triangle's three in order."""
    t = np.asarray(triangles, dtype=np.int64)
    return np.stack([t, np.roll(t, -1, axis=1)], axis=-1).reshape(-1, 2)


def edge_counts(triangles: np.ndarray) -> tuple[bool, bool]:
    """(watertight, winding consistent): every undirected edge used by exactly two triangles;
    and no directed edge used twice (two neighbours run a shared edge in opposite directions)."""
    e = directed_edges(triangles)
    if len(e) == 0:
        return False, False
    _, undirected = np.unique(np.sort(e, axis=1), axis=0, return_counts=True)
    _, directed = np.unique(e, axis=0, return_counts=True)
    return bool(np.all(undirected == 2)), bool(np.all(directed == 1))


def is_closed_oriented(vertices: np.ndarray, triangles: np.ndarray) -> bool:
    """True when the mesh is closed (every edge shared by two triangles) and consistently wound,
    checked before anything is written (numpy: the export path imports no mesh library)."""
    return all(edge_counts(triangles))


def face_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit normal of every triangle (right-hand rule; zero for a degenerate triangle)."""
    tri = np.asarray(vertices, dtype=float)[np.asarray(triangles, dtype=np.int64)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1)
    return np.divide(n, length[:, None], out=np.zeros_like(n), where=length[:, None] > 0)


def stl_bytes(vertices: np.ndarray, triangles: np.ndarray, header: str = STL_HEADER) -> bytes:
    """Binary STL: 80-byte header, triangle count, then normal + 3 vertices per triangle
    (float32, little-endian) and a zero attribute, in the order of ``triangles``."""
    t = np.asarray(triangles, dtype=np.int64)
    record = np.zeros(len(t), dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    record["normal"] = face_normals(vertices, t)
    record["corners"] = np.asarray(vertices, dtype=float)[t]
    return (header.encode("ascii")[:80].ljust(80, b" ") + np.uint32(len(t)).astype("<u4").tobytes()
            + record.tobytes())

