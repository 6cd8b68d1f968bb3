"""The quarter profile's mesh: three structured blocks (pad, wall, tip wedge), the printed root
fillet when a study asks for it, and local refinement at the singular corners.

:class:`MeshOptions` holds what a mesh is built from; the production mesh is its defaults.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.cell import HexCell

if TYPE_CHECKING:
    from skfem import MeshTri

# Default mesh: elements across the wall thickness and along the wall (the pad gets the same
# number across and a graded number along), then DEFAULT_LEVELS rounds of local refinement
# around the three singular corners (the cavity's tip vertex, a near-crack of angle
# 360 - 2 theta, dominates; then the bonded-free corner at the wall root's outside and the
# inner root corner). Uniform refinement converges only like h^1 there. Chosen from the
# convergence study in benchmarks/bench_ladder.py.
DEFAULT_N_THICK = 3
DEFAULT_N_LENGTH = 12
DEFAULT_LEVELS = 4
REFINE_RADIUS_IN_T = 0.5  # first refinement radius around a corner, in wall thicknesses
CORNERS = ("tip", "outer_root", "inner_root")  # the singular corners the default mesh refines at
PAD_LENGTH_IN_T = 4.0  # length of pad kept next to the wall root, in wall thicknesses
WEDGE_ASPECT = 1.5  # tip wedge: column width over local element height
WEDGE_APEX_FRACTION = 0.1  # tip wedge: the last column spans the last 10 % of its length


@dataclass(frozen=True)
class MeshOptions:
    """How the quarter profile is meshed (the defaults are the production mesh).

    ``n_thick`` elements across the wall, ``n_length`` along it; ``levels`` rounds of local
    refinement within ``radius_in_t`` t / 2^i of the named ``corners`` (:func:`refined_quarter_mesh`);
    ``root_fillet_mm`` the outer root's printed fillet (:class:`RootFillet`; 0 the sharp corner, a
    study knob: studies/fillet_study.py).
    """

    n_thick: int = DEFAULT_N_THICK
    n_length: int = DEFAULT_N_LENGTH
    levels: int = DEFAULT_LEVELS
    corners: tuple[str, ...] = CORNERS
    radius_in_t: float = REFINE_RADIUS_IN_T
    root_fillet_mm: float = 0.0


PRODUCTION_MESH = MeshOptions()  # the mesh whose linear k is the law's (the path runs on it with levels = 0)


def _graded(n: int, both_ends: bool) -> np.ndarray:
    """n+1 points on [0, 1], finer at 1 (and at 0 too when ``both_ends``)."""
    s = np.linspace(0.0, 1.0, n + 1)
    if both_ends:
        return 0.5 - 0.5 * np.cos(np.pi * s)
    return np.sin(0.5 * np.pi * s)


def _map_quad(corners, xi, eta):
    """Bilinear map of the (xi, eta) grid onto the quad corners (00, 10, 11, 01)."""
    c00, c10, c11, c01 = (np.asarray(c, dtype=float) for c in corners)
    X, E = np.meshgrid(xi, eta, indexing="ij")
    pts = (
        ((1 - X) * (1 - E))[..., None] * c00
        + (X * (1 - E))[..., None] * c10
        + (X * E)[..., None] * c11
        + ((1 - X) * E)[..., None] * c01
    )
    return pts  # (len(xi), len(eta), 2)


def _wedge_columns(n_thick: int, wedge_over_t: float) -> np.ndarray:
    """Column positions xi in [0, 1] along the tip wedge (xi = 0 at its thick end, 1 at the
    apex): each column about WEDGE_ASPECT times as wide as the local element height, the
    widths shrinking with the wedge's thickness (1 - xi); the last column ends at the apex."""
    q = min(0.5, WEDGE_ASPECT / (n_thick * max(wedge_over_t, 1e-12)))
    one_minus = [1.0]
    while one_minus[-1] > WEDGE_APEX_FRACTION:
        one_minus.append(one_minus[-1] * (1.0 - q))
    return 1.0 - np.array(one_minus[:-1] + [0.0])


@dataclass(frozen=True)
class RootFillet:
    """The printed fillet at the outer wall root A = (p, 0) (``root_fillet_mm`` r > 0).

    The extruded bead fills the air wedge of angle theta between the outer face and the plate
    below it: the region bounded by the plate from A to T1 = (p + r cot(theta/2), 0), the arc of
    radius r about O = T1 + (0, r), tangent to the plate at T1 and to the face at
    T2 = A + r cot(theta/2) (cos theta, sin theta), and the face back to A.
    """

    r_mm: float
    theta_rad: float
    A: np.ndarray
    T1: np.ndarray
    T2: np.ndarray
    O: np.ndarray

    @property
    def tangent_mm(self) -> float:
        """|A T1| = |A T2| = r cot(theta / 2)."""
        return self.r_mm / math.tan(0.5 * self.theta_rad)

    def arc(self, fractions: np.ndarray) -> np.ndarray:
        """Points (n, 2) of the arc at ``fractions`` of its sweep from T2 (0) to T1 (1)."""
        phi = 0.5 * math.pi + self.theta_rad + np.asarray(fractions) * (math.pi - self.theta_rad)
        return self.O[None, :] + self.r_mm * np.stack([np.cos(phi), np.sin(phi)], axis=1)


def root_fillet(cell: HexCell, r_mm: float) -> RootFillet:
    """The fillet of radius ``r_mm`` at the outer wall root; ValueError when T2 passes B'."""
    outer, inner = cell.outer_profile_xz(), cell.inner_profile_xz()
    A, B, C = np.asarray(outer[0], float), np.asarray(outer[1], float), np.asarray(inner[1], float)
    u = (B - A) / np.hypot(*(B - A))
    theta = math.atan2(u[1], u[0])
    L = r_mm / math.tan(0.5 * theta)
    if not 0.0 < L < float((C - A) @ u):
        raise ValueError(f"root fillet r = {r_mm} mm does not fit the outer face of {cell}")
    T2 = A + L * u
    O = T2 + r_mm * np.array([u[1], -u[0]])
    return RootFillet(r_mm, theta, A, np.array([O[0], 0.0]), T2, O)


def _fillet_columns(xi_wall: np.ndarray, fillet: RootFillet, face_mm: float, size_mm: float) -> tuple[np.ndarray, int]:
    """The wall block's columns along the outer face with the fillet's edge A-T2 in n_f uniform
    steps of at most ``size_mm`` (at least 3), the default columns beyond it (those at least half a
    step past T2). Returns (xi, n_f): column n_f is T2."""
    L = fillet.tangent_mm
    n_f = max(3, int(math.ceil(L / size_mm)))
    xi_f = np.linspace(0.0, L / face_mm, n_f + 1)
    keep = xi_wall > xi_f[-1] + 0.5 * (xi_f[1] - xi_f[0])
    return np.concatenate([xi_f, xi_wall[keep]]), n_f


def _fillet_block(face: np.ndarray, fillet: RootFillet) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate the fillet: its edge on the face is ``face`` (n_f + 1, 2), the wall block's own
    nodes from A to T2; the plate edge A-T1 mirrors them about the bisector; the arc gets steps of
    at most the face's; interior points on the chords across the bisector. Delaunay triangulation
    of that set covers the triangle A T1 T2; the triangles with all three corners on the arc (the
    air inside the arc) are dropped. Checked: every face and plate step is an edge, the area is
    the polygon's. Returns (points (n, 2), triangles (3, m))."""
    from scipy.spatial import Delaunay  # deferred: only the root-fillet study triangulates a free block

    A, L, r, th = fillet.A, fillet.tangent_mm, fillet.r_mm, fillet.theta_rad
    n_f = face.shape[0] - 1
    h = L / n_f
    s = np.linspace(0.0, L, n_f + 1)
    base = np.stack([A[0] + s, np.zeros_like(s)], axis=1)
    base[-1] = fillet.T1
    n_arc = max(6, int(math.ceil(2.0 * r * (math.pi - th) / h)))
    arc = fillet.arc(np.linspace(0.0, 1.0, n_arc + 1))[1:-1]
    inner = []
    for i in range(1, n_f + 1):
        n_c = int(round(float(np.hypot(*(face[i] - base[i]))) / h))
        for f in np.arange(1, n_c) / max(n_c, 1):
            q = (1 - f) * face[i] + f * base[i]
            if np.hypot(*(q - fillet.O)) > r + 0.4 * h:
                inner.append(q)
    pts = np.concatenate([face, base[1:], arc, np.reshape(inner, (-1, 2))])
    on_arc = np.zeros(len(pts), bool)
    on_arc[[n_f, 2 * n_f]] = True  # T2, T1
    on_arc[2 * n_f + 1 : 2 * n_f + 1 + len(arc)] = True
    tri = Delaunay(pts).simplices
    area = _triangle_areas(pts, tri)
    tri = tri[~on_arc[tri].all(axis=1) & (area > 1e-12 * L * L)]
    _check_fillet_block(pts, tri, n_f, fillet, np.concatenate([[fillet.T2], arc, [fillet.T1]]))
    return pts, np.ascontiguousarray(tri.T)


def _triangle_areas(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Areas of the triangles ``tri`` (m, 3) of the points ``pts`` (n, 2)."""
    p0, p1, p2 = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    return 0.5 * np.abs((p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p1[:, 1] - p0[:, 1]) * (p2[:, 0] - p0[:, 0]))


def _polygon_area(xy: np.ndarray) -> float:
    x, z = xy[:, 0], xy[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1))))


def _check_fillet_block(pts, tri, n_f: int, fillet: RootFillet, arc: np.ndarray) -> None:
    """Raise ValueError unless the fillet's triangles tile its polygon and keep the face's and
    the plate's steps as edges (so that the block is conforming with the wall and the pad)."""
    area = _triangle_areas(pts, tri)
    polygon = _polygon_area(np.concatenate([[fillet.A], arc[::-1]]))  # A, T1, arc ..., T2
    edges = {tuple(sorted(e)) for t in tri for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    face_steps = [(i, i + 1) for i in range(n_f)]
    base_ids = [0] + list(range(n_f + 1, 2 * n_f + 1))
    base_steps = [tuple(sorted(e)) for e in zip(base_ids[:-1], base_ids[1:])]
    missing = [e for e in face_steps + base_steps if e not in edges]
    if missing or abs(area.sum() - polygon) > 1e-9 * polygon:
        raise ValueError(f"root fillet mesh: {len(missing)} missing edges, area {area.sum():.6g} of {polygon:.6g}")


def quarter_profile_mesh(
    cell: HexCell, n_thick: int = DEFAULT_N_THICK, n_length: int = DEFAULT_N_LENGTH, root_fillet_mm: float = 0.0
) -> tuple[np.ndarray, np.ndarray, float]:
    """Triangle mesh of the quarter profile (bottom pad's right part + lower right wall).

    Built from the cell's own polygons in three structured blocks:

    * pad quad: from the cut x_cut to the wall root, bottom z = 0 to top z = t;
    * wall quad: outer root A = (p, 0), B' (the point of the outer face opposite the cavity's
      tip vertex C: B'C is normal to the wall and t long), C, inner root D (the inner pad
      corner) -- a well-shaped quad of thickness t at every theta;
    * tip wedge B' B C, B = (W/2, h/2) the outer tip: the solid between the outer face and the
      mirror plane beyond the cavity's tip, t / tan(theta) long (11 t at theta = 5 deg). It is
      meshed with columns graded towards its apex, so that shallow walls keep elements about
      as wide as they are high there. (Mapping the whole wall as one quad A B C D stretched
      the n_thick elements across the tip face B C, t / sin(theta) long, and at theta = 5 deg
      left the small-strain k 35 % off its converged value.)

    ``root_fillet_mm`` r > 0 (a study knob, studies/fillet_study.py) adds the printed fillet
    that fills the air wedge between the outer face and the plate at A (:func:`root_fillet`): the
    wall block gets uniform columns along the face from A to the tangent point T2 (the fillet's
    edge reuses them) and the fillet is triangulated on its own (:func:`_fillet_block`).

    Returns (points (2, N), triangles (3, M), x_cut_mm).
    """
    outer = cell.outer_profile_xz()
    inner = cell.inner_profile_xz()
    A, B = np.asarray(outer[0], float), np.asarray(outer[1], float)  # (p, 0), (W/2, h/2)
    D, C = np.asarray(inner[0], float), np.asarray(inner[1], float)  # (a, t), (c, h/2)
    t = cell.t_mm
    u_wall = (B - A) / np.hypot(*(B - A))
    Bp = A + float((C - A) @ u_wall) * u_wall  # B'
    x_cut = max(0.0, D[0] - PAD_LENGTH_IN_T * t)
    n_pad = max(2, int(math.ceil(n_length * 0.5)))
    across = np.linspace(0, 1, n_thick + 1)
    xi_wall = _graded(n_length, True)
    fillet = root_fillet(cell, root_fillet_mm) if root_fillet_mm > 0 else None
    if fillet is not None:
        xi_wall, n_f = _fillet_columns(xi_wall, fillet, float(np.hypot(*(Bp - A))), t / n_thick)
    wall = _map_quad((A, Bp, C, D), xi_wall, across)
    pad = _map_quad(((x_cut, 0.0), A, D, (x_cut, t)), _graded(n_pad, False), across)
    xi = _wedge_columns(n_thick, float(np.hypot(*(B - Bp))) / t)
    X, E = np.meshgrid(xi, across, indexing="ij")
    wedge = (
        Bp[None, None, :]
        + X[..., None] * (B - Bp)[None, None, :]
        + (E * (1.0 - X))[..., None] * (C - Bp)[None, None, :]
    )
    extra = None if fillet is None else _fillet_block(wall[: n_f + 1, 0], fillet)
    pts, tri = _stitch_blocks((pad, wall, wedge), max(cell.h_mm, 1.0), extra)
    return pts.T.copy(), tri, x_cut


def _stitch_blocks(grids, length_scale_mm: float, extra=None) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate structured point grids (ni, nj, 2) and merge the nodes they share.

    ``extra``: an already triangulated block (points (n, 2), triangles (3, m)) merged after the
    grids (the root fillet's).

    Each grid quad becomes two triangles; nodes closer than 1e-9 ``length_scale_mm`` are one
    node (the blocks' common lines, the wedge's apex); triangles that collapse onto a merged
    node are dropped and every triangle is made counter-clockwise. Returns (points (N, 2),
    triangles (3, M)).
    """
    blocks, tris, offset = [], [], 0
    for grid in grids:
        ni, nj = grid.shape[:2]
        idx = offset + np.arange(ni * nj).reshape(ni, nj)
        a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
        c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        tris.append(np.stack([a, b, c]))
        tris.append(np.stack([a, c, d]))
        blocks.append(grid.reshape(-1, 2))
        offset += ni * nj
    if extra is not None:
        blocks.append(extra[0])
        tris.append(extra[1] + offset)
    pts = np.concatenate(blocks)
    tri = np.concatenate(tris, axis=1)
    # merge the nodes shared by the blocks (the wall-root line, the line B'C, the apex B)
    key = np.round(pts / length_scale_mm * 1e9).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    pts = pts[first]
    tri = inverse.ravel()[tri]
    # the wedge's last column collapses onto the apex: drop its degenerate triangles
    tri = np.ascontiguousarray(tri[:, (tri[0] != tri[1]) & (tri[1] != tri[2]) & (tri[0] != tri[2])])
    # counter-clockwise orientation
    p0, p1, p2 = pts[tri[0]], pts[tri[1]], pts[tri[2]]
    area2 = (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p1[:, 1] - p0[:, 1]) * (p2[:, 0] - p0[:, 0])
    flip = area2 < 0
    tri[1, flip], tri[2, flip] = tri[2, flip], tri[1, flip].copy()
    return pts, tri


def refined_quarter_mesh(cell: HexCell, options: MeshOptions = PRODUCTION_MESH) -> tuple[MeshTri, float]:
    """:func:`quarter_profile_mesh` with ``options.levels`` rounds of refinement at the corners.

    Round i refines (red-green) the triangles whose centroid lies within radius_in_t t / 2^i of
    the named ``corners`` (CORNERS: the cavity's tip vertex, the outer wall-root corner, the
    inner wall-root corner; with a root fillet, "outer_root" is A and the fillet's tangent points
    T1 and T2). Returns (skfem MeshTri, x_cut_mm).
    """
    from skfem import MeshTri  # deferred: scikit-fem (0.2 s) loads only when a mesh is built

    pts, tri, x_cut = quarter_profile_mesh(cell, options.n_thick, options.n_length, options.root_fillet_mm)
    mesh = MeshTri(pts, tri)
    outer_root = [cell.outer_profile_xz()[0]]
    if options.root_fillet_mm > 0:
        fillet = root_fillet(cell, options.root_fillet_mm)
        outer_root += [tuple(fillet.T1), tuple(fillet.T2)]
    where = {
        "tip": [cell.inner_profile_xz()[1]],
        "outer_root": outer_root,
        "inner_root": [cell.inner_profile_xz()[0]],
    }
    at = np.array([p for name in options.corners for p in where[name]])  # (n, 2) corner positions, mm
    for i in range(options.levels):
        mid = mesh.p[:, mesh.t].mean(axis=1)
        r = options.radius_in_t * cell.t_mm * 0.5**i
        dist = np.hypot(mid[0][None, :] - at[:, :1], mid[1][None, :] - at[:, 1:])
        marked = np.flatnonzero((dist < r).any(axis=0))
        if marked.size:
            mesh = mesh.refined(marked)
    return mesh, x_cut
