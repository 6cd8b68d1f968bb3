"""Triangle meshes: tessellation of a B-rep solid (OCP, build123d) and welding (trimesh), for the
CAD path; the closed-mesh test and binary STL (numpy only, so that writing a mesh built by
:mod:`mst_cli.cad.mesh_body` imports no mesh library).

Output is deterministic: the same solid and tolerance give the same vertices (welded in
first-seen order) and triangles, so byte-identical STL files. The 3MF and STEP writers, which
need more care for that, are in :mod:`mst_cli.cad.deterministic`; their names are re-exported
here for the callers that write all the mesh files from one module.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.cad.deterministic import (
    PRUSA_CUSTOM_GCODE_MEMBER,
    PRUSA_PAUSE_PRINT_TYPE,
    STEP_TIMESTAMP,
    prusa_pause_xml,
    step_bytes,
    three_mf_bytes,
    write_step,
)

if TYPE_CHECKING:
    from build123d import Solid

__all__ = [
    "PRUSA_CUSTOM_GCODE_MEMBER",
    "PRUSA_PAUSE_PRINT_TYPE",
    "STEP_TIMESTAMP",
    "is_closed_oriented",
    "merge_vertices",
    "prusa_pause_xml",
    "step_bytes",
    "stl_bytes",
    "tessellate",
    "three_mf_bytes",
    "write_step",
]

STL_HEADER = "mst sensor body, mm"
# largest angle (rad) one mesh segment of a curved surface spans, in both meshers
ANGULAR_TOLERANCE_RAD = 0.1


def tessellate(
    solid: Solid, tolerance_mm: float, angular_tolerance_rad: float = ANGULAR_TOLERANCE_RAD
) -> tuple[np.ndarray, np.ndarray]:
    """Indexed triangle mesh of ``solid`` with outward normals.

    OCCT's incremental mesher discretises every edge once and shares it between the two
    faces it bounds, so the faces' meshes meet vertex to vertex; welding equal coordinates
    gives a closed mesh. ``tolerance_mm`` is the largest chord deviation from the surface.

    Returns
    -------
    vertices : (n, 3) float64 array, mm
    triangles : (m, 3) int64 array of vertex indices, counter-clockwise seen from outside
    """
    from OCP.BRepMesh import BRepMesh_IncrementalMesh  # deferred: the CAD kernel (--step only)

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
    # deferred: the CAD kernel (--step only)
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    faces = [f.wrapped for f in solid.faces()]
    counts = [BRep_Tool.Triangulation_s(f, TopLoc_Location()).NbTriangles() for f in faces]
    reversed_ = np.repeat([f.Orientation() == TopAbs_REVERSED for f in faces], counts)
    triangles[reversed_] = np.roll(triangles[reversed_], -1, axis=1)


def _trimesh(vertices: np.ndarray, triangles: np.ndarray):
    import trimesh  # deferred: heavy (pulls scipy.spatial)

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
    return header.encode("ascii")[:80].ljust(80, b" ") + np.uint32(len(t)).astype("<u4").tobytes() + record.tobytes()


# --------------------------------------------------------------------------- reading (mst check)
# trimesh welds the vertices of a loaded STL to this many decimals (its tol.merge = 1e-8)
WELD_DIGITS = 8


@dataclass(frozen=True, eq=False)
class Mesh:
    """An indexed triangle mesh and what ``mst check`` measures on it, in numpy only (trimesh
    imports scipy.spatial, a third of a second, for none of it). Attribute names as trimesh's."""

    vertices: np.ndarray  # (n, 3) float64, mm
    faces: np.ndarray  # (m, 3) int64

    @classmethod
    def of(cls, mesh: Any) -> Mesh:
        """A Mesh of anything with ``vertices`` and ``faces`` (a trimesh.Trimesh, say)."""
        return cls(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64))

    def moved(self, vertices: np.ndarray) -> Mesh:
        return Mesh(np.asarray(vertices, dtype=float), self.faces)

    @property
    def triangles(self) -> np.ndarray:
        return self.vertices[self.faces]

    @property
    def bounds(self) -> np.ndarray:
        return np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def volume(self) -> float:
        """Signed volume (divergence theorem): positive for a closed mesh with outward normals."""
        tri = self.triangles
        return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)

    @property
    def face_normals(self) -> np.ndarray:
        return face_normals(self.vertices, self.faces)

    @property
    def area_faces(self) -> np.ndarray:
        tri = self.triangles
        return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)

    @property
    def triangles_center(self) -> np.ndarray:
        return self.triangles.mean(axis=1)

    @property
    def is_watertight(self) -> bool:
        return edge_counts(self.faces)[0]

    @property
    def is_winding_consistent(self) -> bool:
        return edge_counts(self.faces)[1]

    @property
    def is_volume(self) -> bool:
        """Watertight, consistently wound, finite and of positive volume (trimesh's test)."""
        return (
            self.is_watertight
            and self.is_winding_consistent
            and bool(np.isfinite(self.vertices).all())
            and self.volume > 0.0
        )


def weld(vertices: np.ndarray, triangles: np.ndarray, digits: int = WELD_DIGITS) -> Mesh:
    """One vertex per coordinate rounded to ``digits`` decimals (kept in first-seen order)."""
    key = np.round(np.asarray(vertices, dtype=float) * 10.0**digits).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    rank = np.argsort(np.argsort(first))
    return Mesh(
        np.asarray(vertices, dtype=float)[np.sort(first)],
        rank[inverse.reshape(-1)][np.asarray(triangles, dtype=np.int64)],
    )


def binary_stl_triangles(data: bytes) -> np.ndarray | None:
    """(m, 3, 3) corners of a binary STL, or None when ``data`` is not one (its size must be
    84 + 50 x the triangle count in its header)."""
    if len(data) < 84:
        return None
    count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
    if len(data) != 84 + 50 * count or count == 0:
        return None
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(data, dtype=record, offset=84)["corners"].astype(float)
