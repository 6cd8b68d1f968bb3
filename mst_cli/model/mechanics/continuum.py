"""Rung L2 ``continuum``: nonlinear plane-strain finite elements of the real hex profile.

The reference model of the ladder (docs/design.md section 4). The layer's profile (x across the
width, z up; one continuous web through the depth D along y) is meshed from the
:class:`~mst_cli.model.cell.HexCell` polygons, with quadratic triangles (P2: linear
triangles lock in bending at nu = 0.45), and loaded by displacement control with a compressible
Neo-Hookean material through closure, up to the lock.

Symmetry and boundary conditions (a quarter of the profile: x >= 0, z <= h/2)
---------------------------------------------------------------------------
The profile is mirror-symmetric about x = 0 and, for equal and opposite plate motions, about
the mid-plane z = h/2; a rigid translation does not change the stresses, so bottom plate fixed
and top plate lowered by d is the symmetric problem shifted by d/2. The quarter model is the
bottom pad's right part plus the lower right wall:

* bottom face z = 0 (bonded to the rigid plate below): u = 0;
* pad cut at x = x_cut (x = 0 is the mirror plane; far from the wall the bonded pad is
  unstressed, so the pad is truncated a few t from the wall root): u_x = 0;
* wall tip face z = h/2 (the mirror plane, moving down by d/2 with the chevron's tip):
  u_z = -d/2, free to slide in x (no shear traction on a mirror plane).

The tip reaction f (N per mm of depth) is the force carried by one chevron whose compression is
d. The web's two chevrons act in parallel over its width b = D:  F = 2 b f.

Plane strain (the web is D = 20 mm wide, its walls 0.4-3 mm thick: away from the faces
y = +-D/2 nothing can stretch along y), lambda_3 = 1: the compressible Neo-Hookean energy
W = mu/2 (I_1 - 3) - mu ln J + lambda/2 (ln J)^2 (e.g. Bonet & Wood, "Nonlinear Continuum
Mechanics for Finite Element Analysis", 2nd ed., section 6.4.3) of the in-plane F, with the
3D Lame constants of the material's small-strain E and nu. Its small-strain limit is
plane-strain linear elasticity (uniaxial modulus E' = E / (1 - nu^2); tests/test_continuum.py
checks the tangent, a patch test and a Timoshenko cantilever).

Contact (:meth:`_Problem._contact_sets`): frictionless, by an active set inside Newton, of the
inner pad and wall faces against the moving mirror plane z = h/2 - d/2 and of the wall's outer
face against the plate z = 0. The pads touch at the contact allowance (the roughness of two
printed faces); faces that close at an angle, from the cavity's tip vertex and the outer wall
root, touch at zero gap. The lock (:func:`follow_to_lock`) is the first compression at which
the tangent stiffness reaches LOCK_STIFFNESS_FACTOR x k: a wall pinched between the plate and
its mirror, or the pads meeting (docs/design.md section 4). With rigid pads that is at most
d = h - 2t - allowance; the pads are elastic, so they meet up to a few per cent later.

This module loads only when L2 is asked for (``mechanics`` defers it), so scipy is imported at its
top; scikit-fem, the slowest import, loads only when a mesh is built.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg.lapack import dgbsv, dpbsv
from scipy.sparse import coo_matrix, csc_matrix, csr_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.sparse.linalg import splu

from mst_cli.model.cell import HexCell
from mst_cli.model.mechanics.frame import TabulatedLockingLayer, locked_tabulated_law
from mst_cli.model.mechanics.law_cache import law_cache
from mst_cli.model.mechanics.path import LAW_CHORD_TOL_REL, PathError, PathTolerances, StepControl, follow_to_event
from mst_cli.parallel import one_blas_thread

if TYPE_CHECKING:
    from skfem import MeshTri

    from mst_cli.model.material import Material

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
# Contact is searched up to this multiple of the rigid-pad stroke h - 2t - allowance (the
# elastic pads under stiff walls meet up to ~5 % late; beyond this the solve is an error).
D_MAX_OVER_NOMINAL = 1.5
# The lock (docs/design.md section 4): the first compression at which the layer's tangent
# stiffness reaches this multiple of its small-load stiffness k. Where a wall is pinched
# between the plate and its mirror, or the pads meet, the tangent jumps 20-80 fold within a
# few micrometres, so the lock force hardly depends on the factor; the gradual stiffening of
# faces zipping shut before that (up to ~2.5 k) stays part of the pre-lock curve.
LOCK_STIFFNESS_FACTOR = 5.0
# Newton's active set: after this many changes of the set within one solve, a contact point
# released once and back in contact stays held (:meth:`_Problem._newton`)
SET_CHANGES_BEFORE_HOLDING = 4
# the tangent jumps at the lock, so the event is bisected, to 1e-5 of the stroke
LOCK_TOLERANCES = PathTolerances(event_gap_rel=0.0, event_width_rel=1e-5, max_event_iterations=40, bisect=True)


class ContinuumError(RuntimeError):
    """The FE solve did not converge (reported, never returned as a silent number)."""


# --------------------------------------------------------------------------- mesh
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


def refined_quarter_mesh(
    cell: HexCell,
    n_thick: int = DEFAULT_N_THICK,
    n_length: int = DEFAULT_N_LENGTH,
    levels: int = DEFAULT_LEVELS,
    corners: tuple[str, ...] = CORNERS,
    radius_in_t: float = REFINE_RADIUS_IN_T,
    root_fillet_mm: float = 0.0,
) -> tuple[MeshTri, float]:
    """:func:`quarter_profile_mesh` with ``levels`` rounds of refinement at the corners.

    Round i refines (red-green) the triangles whose centroid lies within radius_in_t t / 2^i of
    the named ``corners`` (CORNERS: the cavity's tip vertex, the outer wall-root corner, the
    inner wall-root corner; with a root fillet, "outer_root" is A and the fillet's tangent points
    T1 and T2). Returns (skfem MeshTri, x_cut_mm).
    """
    from skfem import MeshTri  # deferred: scikit-fem (0.2 s) loads only when a mesh is built

    pts, tri, x_cut = quarter_profile_mesh(cell, n_thick, n_length, root_fillet_mm)
    mesh = MeshTri(pts, tri)
    outer_root = [cell.outer_profile_xz()[0]]
    if root_fillet_mm > 0:
        fillet = root_fillet(cell, root_fillet_mm)
        outer_root += [tuple(fillet.T1), tuple(fillet.T2)]
    where = {
        "tip": [cell.inner_profile_xz()[1]],
        "outer_root": outer_root,
        "inner_root": [cell.inner_profile_xz()[0]],
    }
    at = np.array([p for name in corners for p in where[name]])  # (n, 2) corner positions, mm
    for i in range(levels):
        mid = mesh.p[:, mesh.t].mean(axis=1)
        r = radius_in_t * cell.t_mm * 0.5**i
        dist = np.hypot(mid[0][None, :] - at[:, :1], mid[1][None, :] - at[:, 1:])
        marked = np.flatnonzero((dist < r).any(axis=0))
        if marked.size:
            mesh = mesh.refined(marked)
    return mesh, x_cut


# --------------------------------------------------------------------------- material
def _lame_3d(E_MPa, nu):
    mu = E_MPa / (2.0 * (1.0 + nu))
    lam = E_MPa * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return mu, lam


def _kinematics(Fm, mu, lam):
    """Plane-strain Neo-Hookean at the in-plane F (2, 2, ...), lambda_3 = 1: the first Piola
    stress P = mu F + (lam ln J - mu) F^-T and the pieces of its tangent (F^-T, ln J)."""
    J = Fm[0, 0] * Fm[1, 1] - Fm[0, 1] * Fm[1, 0]
    Finv_T = np.array([[Fm[1, 1], -Fm[1, 0]], [-Fm[0, 1], Fm[0, 0]]]) / J
    lnJ = np.log(J)
    P = mu * Fm + (lam * lnJ - mu) * Finv_T
    return P, Finv_T, lnJ


# --------------------------------------------------------------------------- assembly
class _Assembler:
    """Residual and tangent of the Neo-Hookean forms on one P2 vector basis, vectorised.

    Total Lagrangian: the shape-function gradients, quadrature weights and the sparsity
    pattern belong to the reference mesh and never change, so they are computed once here and
    every Newton step is a few batched array products plus one bincount into a fixed CSR
    pattern (scikit-fem's ``asm`` rebuilt all of this and called the form once per pair of
    local basis functions: 144 Python calls per tangent, most of L2's time).
    """

    def __init__(self, basis):
        dofs = basis.element_dofs  # (n_loc, n_el)
        n_loc, n_el = dofs.shape
        grads = np.array([basis.basis[i][0].grad for i in range(n_loc)])  # (n_loc, 2, 2, n_el, n_q)
        n_q = grads.shape[-1]
        # B[e, q, k, i]: component k = (c, j) of the gradient d u_c / d X_j of local function i
        self.B = np.ascontiguousarray(grads.reshape(n_loc, 4, n_el, n_q).transpose(2, 3, 1, 0))
        Bw = self.B * basis.dx[:, :, None, None]
        # (n_el, n_loc, n_q * 4): weighted B^T, quadrature points and components as one axis
        self.BwT = np.ascontiguousarray(Bw.transpose(0, 3, 1, 2).reshape(n_el, n_loc, 4 * n_q))
        self.dofs = np.ascontiguousarray(dofs.T)  # (n_el, n_loc)
        self.N = basis.N
        # CSR pattern of K (scipy merges the duplicate entries in C), and where element entry
        # (e, i, j) goes in its data: the rank of its key row * N + col among the pattern's keys

        rows = np.broadcast_to(self.dofs[:, :, None], (n_el, n_loc, n_loc)).ravel()
        cols = np.broadcast_to(self.dofs[:, None, :], (n_el, n_loc, n_loc)).ravel()
        pattern = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(self.N, self.N)).tocsr()
        pattern.sort_indices()
        self.indices, self.indptr, self.nnz = pattern.indices, pattern.indptr, pattern.nnz
        keys = np.repeat(np.arange(self.N, dtype=np.int64), np.diff(self.indptr)) * self.N + self.indices
        self.scatter = np.searchsorted(keys, rows.astype(np.int64) * self.N + cols)

    def residual(self, u, mu, lam):
        """r = int P : grad v; also returns what the tangent at u needs (F^-T, ln J)."""
        grad_u = np.einsum("eqki,ei->keq", self.B, u[self.dofs])  # (4, n_el, n_q)
        Fm = grad_u.reshape(2, 2, *grad_u.shape[1:]) + np.eye(2)[:, :, None, None]
        if np.any(Fm[0, 0] * Fm[1, 1] - Fm[0, 1] * Fm[1, 0] <= 0):
            raise FloatingPointError("inverted element")
        P, FiT, lnJ = _kinematics(Fm, mu, lam)
        if not np.all(np.isfinite(P)):
            raise FloatingPointError("inverted element")
        n_el, n_q = lnJ.shape
        Pk = P.reshape(4, n_el, n_q).transpose(1, 2, 0).reshape(n_el, 4 * n_q)
        r_el = np.einsum("eik,ek->ei", self.BwT, Pk)
        r = np.bincount(self.dofs.ravel(), weights=r_el.ravel(), minlength=self.N)
        return r, (FiT, lnJ)

    def tangent(self, state, mu, lam):
        """K = int grad v : A : grad du, A = dP/dF = mu I - (lam ln J - mu) F^-T (x) F^-T
        (transposed pairing) + lam F^-T (x) F^-T, as CSR on the fixed pattern."""

        FiT, lnJ = state
        Fi = FiT.transpose(2, 3, 0, 1)  # (n_el, n_q, 2, 2)
        n_el, n_q = lnJ.shape
        f = Fi.reshape(n_el, n_q, 4)
        # A[(a, b), (m, n)] = mu d_am d_bn - (lam ln J - mu) FiT_an FiT_mb + lam FiT_ab FiT_mn
        swap = np.einsum("eqan,eqmb->eqabmn", Fi, Fi).reshape(n_el, n_q, 4, 4)
        A = lam * f[..., :, None] * f[..., None, :] - (lam * lnJ - mu)[..., None, None] * swap + mu * np.eye(4)
        AB = (A @ self.B).reshape(n_el, 4 * n_q, -1)  # (n_el, n_q * 4, n_loc)
        K_el = self.BwT @ AB  # (n_el, n_loc, n_loc)
        data = np.bincount(self.scatter, weights=K_el.ravel(), minlength=self.nnz)
        return csr_matrix((data, self.indices, self.indptr), shape=(self.N, self.N))


class _PlatePenalty:
    """An assembler with the outer wall face's contact with the plate as a penalty.

    The plate pushes a point of the outer face that has gone below it (u_z < -z) back with a
    force kappa (overlap), kappa = ``per_mm`` mu L (L the point's share of the face's length,
    mm): a pressure mu ``per_mm`` per mm of overlap. Unlike the active set, the contact force
    is continuous in u, so Newton does not churn where many small elements touch one after the
    other (the root-graded meshes of docs/design.md section 4, "Steep walls"); the answer is
    the active set's as ``per_mm`` grows (tests/test_continuum.py). Only where the plate stays
    put (the centred problem).
    """

    def __init__(self, base: _Assembler, dofs: np.ndarray, obstacle_mm: np.ndarray, kappa: np.ndarray):
        self.base, self.dofs, self.obstacle_mm, self.kappa = base, dofs, obstacle_mm, kappa
        self.N, self.nnz, self.indices, self.indptr = base.N, base.nnz, base.indices, base.indptr
        # where each dof's diagonal entry sits in the CSR pattern
        starts = base.indptr[dofs]
        self.diag_pos = np.array(
            [a + np.searchsorted(base.indices[a : base.indptr[i + 1]], i) for a, i in zip(starts, dofs)]
        )

    def overlap_mm(self, u: np.ndarray) -> np.ndarray:
        return np.maximum(self.obstacle_mm - u[self.dofs], 0.0)

    def residual(self, u, mu, lam):
        r, state = self.base.residual(u, mu, lam)
        pen = self.overlap_mm(u)
        r[self.dofs] -= self.kappa * pen  # the plate pushes up
        return r, (state, pen > 0.0)

    def tangent(self, state, mu, lam):
        inner, touching = state
        K = self.base.tangent(inner, mu, lam)
        K.data[self.diag_pos[touching]] += self.kappa[touching]
        return K


_ASSEMBLERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _assembler(basis) -> _Assembler | _PlatePenalty:
    """The assembler of a basis, built on first use (kept as long as the basis lives)."""
    asm = _ASSEMBLERS.get(basis)
    if asm is None:
        asm = _ASSEMBLERS[basis] = _Assembler(basis)
    return asm


# --------------------------------------------------------------------------- solver
@dataclass(frozen=True)
class ContinuumResult:
    """Force-displacement of one layer from the FE solve, up to its lock."""

    displacement_mm: np.ndarray  # layer compression d at every converged step
    force_N: np.ndarray  # layer force F at those steps
    k_linear_N_per_mm: float  # small-strain (linear) stiffness, by-product
    d_contact_mm: float  # the lock: where the tangent reaches LOCK_STIFFNESS_FACTOR x k (last sample)
    contact_at: str  # what closed there: "pad" (the pads meet) or "wall" (a wall pinched)
    newton_iterations: int
    n_dofs: int
    reaction_balance: float  # |force across the mirror plane - support reaction| / force
    mesh_scale: float  # k on the refined mesh / k on the path's mesh
    lock_stiffness_ratio: float = math.nan  # tangent / k just past the lock (>= LOCK_STIFFNESS_FACTOR)
    contact_points: np.ndarray | None = None  # surface points in contact at each sample
    min_stretch_at_lock: float = math.nan  # smallest principal stretch on the path's mesh at the lock


class _FreeBlock:
    """The block of a tangent on a set of free dofs, ordered so that it is banded.

    ``free``: the dofs, in reverse Cuthill-McKee order (on the path's mesh a half-bandwidth of
    about 43 for 570-940 unknowns); ``csc(K)``: the block as a sparse matrix (the fine mesh's
    one solve); :meth:`solve`: LAPACK's banded Cholesky (dpbsv), or its banded LU with partial
    pivoting (dgbsv) where the block is not positive definite. The tangent of a hyperelastic
    body is symmetric, and positive definite wherever the displacement-controlled path is
    stable. On a 571-dof path mesh a solve takes 0.5 ms against SuperLU's 1.2 ms with its own
    column ordering, which it redid on every solve though the pattern is fixed (same answers to
    3e-13; benchmarks/l2_cost.py, part 3).
    """

    def __init__(self, asm: _Assembler | _PlatePenalty, free: np.ndarray):
        # number K's entries 1..nnz (exact in floats), cut the block, read the numbers back
        tagged = csr_matrix((np.arange(1.0, asm.nnz + 1.0), asm.indices, asm.indptr), shape=(asm.N, asm.N))
        self.free = free[reverse_cuthill_mckee(tagged[free][:, free].tocsr(), symmetric_mode=True)]
        sub = tagged[self.free][:, self.free].tocsc()
        self.pos, self.indices, self.indptr = sub.data.astype(np.int64) - 1, sub.indices, sub.indptr
        n = self.free.size
        row, col = sub.indices, np.repeat(np.arange(n), np.diff(sub.indptr))
        b = self.half_band = int(np.max(np.abs(row - col))) if n else 0
        self.at_lu = (2 * b + row - col) * n + col  # LAPACK's general band: (i, j) at [2b + i - j, j]
        upper = row <= col
        self.at_chol, self.pos_chol = ((b + row - col) * n + col)[upper], self.pos[upper]  # [b + i - j, j]

    def csc(self, K) -> csc_matrix:
        return csc_matrix((K.data[self.pos], self.indices, self.indptr), shape=(self.free.size, self.free.size))

    def solve(self, K, rhs: np.ndarray) -> np.ndarray:
        """The block of the tangent K solved for ``rhs`` (in the block's order). Raises
        FloatingPointError for a singular block (the path then halves its step)."""
        n, b = self.free.size, self.half_band
        band = np.zeros((b + 1) * n)
        band[self.at_chol] = K.data[self.pos_chol]
        _, x, info = dpbsv(band.reshape(b + 1, n), rhs, overwrite_ab=True)
        if info == 0:
            return x
        band = np.zeros((3 * b + 1) * n)  # not positive definite: LU, with room for the pivots' fill
        band[self.at_lu] = K.data[self.pos]
        _, _, x, info = dgbsv(b, b, band.reshape(3 * b + 1, n), rhs, overwrite_ab=True)
        if info != 0:
            raise FloatingPointError(f"singular tangent (LAPACK dgbsv info {info})")
        return x


class _ActiveSet:
    """The contact set's update at a converged Newton pass (frictionless, unilateral).

    A point past its obstacle joins the set; a held point whose reaction pulls leaves it.
    Grazing points at the edge of a contact zone can pull when held and penetrate when free,
    and the set then cycles for ever (a steep wall's outer face peeling off the plate did, on a
    root-graded mesh): after SET_CHANGES_BEFORE_HOLDING changes within one solve, a point back
    in contact after a release stays held (a small nodal pull at the zone's edge).
    """

    def __init__(self, eligible: np.ndarray, tol_mm: float):
        self.eligible, self.tol_mm = eligible, tol_mm
        self.changes = 0
        self.released = np.zeros(eligible.size, bool)
        self.held = np.zeros(eligible.size, bool)

    def update(self, active: np.ndarray, overlap_mm: np.ndarray, pull: np.ndarray) -> np.ndarray | None:
        """The next set from the signed overlap with each obstacle (> 0: penetrating) and the
        signed reaction (> 0: pulling); None when the set is consistent and stays."""
        penetrating = self.eligible & ~active & (overlap_mm > self.tol_mm)
        if self.changes >= SET_CHANGES_BEFORE_HOLDING:
            self.held |= active & self.released
        pulling = active & (pull > 0.0) & ~self.held
        if not penetrating.any() and not pulling.any():
            return None
        self.changes += 1
        self.released |= pulling
        return (active | penetrating) & ~pulling


class _Problem:
    plate: _PlatePenalty | None = None  # the plate's contact as a penalty, when asked for
    fillet: RootFillet | None = None  # the outer root's printed fillet (quarter_profile_mesh), if any

    def __init__(
        self,
        cell,
        material,
        n_thick,
        n_length,
        levels,
        corners=CORNERS,
        radius_in_t=REFINE_RADIUS_IN_T,
        plate_penalty_per_mm=None,
        root_fillet_mm=0.0,
    ):
        from skfem import Basis, ElementTriP2, ElementVector  # deferred: scikit-fem, as in refined_quarter_mesh

        self.cell = cell
        self.fillet = root_fillet(cell, root_fillet_mm) if root_fillet_mm > 0 else None
        self.mesh, x_cut = refined_quarter_mesh(cell, n_thick, n_length, levels, corners, radius_in_t, root_fillet_mm)
        self.basis = Basis(self.mesh, ElementVector(ElementTriP2()), intorder=4)
        self.mu, self.lam = _lame_3d(material.youngs_modulus_MPa, material.poisson_ratio)
        b = self.basis
        h2 = 0.5 * cell.h_mm
        tol = 1e-9 * max(cell.width_mm, cell.h_mm)
        xy = b.doflocs  # (2, ndofs): location of every dof
        is_x = np.zeros(b.N, bool)
        is_x[b.nodal_dofs[0]] = True
        is_x[b.facet_dofs[0]] = True
        on_bottom = np.abs(xy[1]) < tol
        on_cut = np.abs(xy[0] - x_cut) < tol
        on_tip = np.abs(xy[1] - h2) < tol
        # the masks the tilted problem (continuum_tilt) reuses: x dofs, bonded face, the pad's cut
        self.is_x, self.on_bottom, self.on_cut = is_x, on_bottom, on_cut
        self.fixed_zero = np.flatnonzero(on_bottom | (on_cut & is_x))
        self.tip_z = np.flatnonzero(on_tip & ~is_x & ~on_bottom)
        self.support_z = np.flatnonzero((on_bottom | on_cut) & ~is_x)
        self.dirichlet = np.union1d(self.fixed_zero, self.tip_z)
        self.free = np.setdiff1d(np.arange(b.N), self.dirichlet)
        self._blocks = {}  # free_block's cache: pinned set -> (free, gather, CSC pattern)
        self.x_cut = x_cut
        self._contact_sets(cell, xy, is_x, tol, on_bottom, on_tip)
        self.h2 = h2
        self.depth_factor = 2.0 * cell.b_mm  # F = 2 b f: two chevrons of a web b wide
        self.plate = None if plate_penalty_per_mm is None else self._plate_as_penalty(plate_penalty_per_mm)

    def _plate_as_penalty(self, per_mm):
        """Take the outer face's contact out of the active set and into a penalty (_PlatePenalty)."""
        n = self.n_inner
        dofs, obstacle = self.contact_dofs[n:], self.obstacle_u0[n:]
        self.contact_dofs, self.contact_sign = self.contact_dofs[:n], self.contact_sign[:n]
        self.obstacle_u0, self.obstacle_rate = self.obstacle_u0[:n], self.obstacle_rate[:n]
        # each point's share of the face's length: half the distance between its neighbours
        xy = self.basis.doflocs[:, dofs]
        along = np.hypot(xy[0] - xy[0].min(), xy[1] - xy[1].min())
        order = np.argsort(along)
        sorted_share = np.gradient(along[order])
        sorted_share[[0, -1]] *= 0.5
        share = np.empty(dofs.size)
        share[order] = sorted_share
        plate = _PlatePenalty(_Assembler(self.basis), dofs, obstacle, per_mm * self.mu * share)
        _ASSEMBLERS[self.basis] = plate
        return plate

    def _contact_sets(self, cell, xy, is_x, tol, on_bottom, on_tip):
        """The z-dofs of every surface that can close, each with its side and offset.

        * inner faces (the inner pad face z = t and the inner wall face) against their mirror
          images across the moving mid-plane: z + u_z <= h/2 - d/2 - g_c/2 (sign +1);
        * the outer wall face against the plate below it, z = 0: z + u_z >= g_c (sign -1); with
          a root fillet, the face from T2 up and the fillet's arc (:meth:`_fillet_arc_dofs`).

        g_c is the clear gap at which two printed faces touch: the contact allowance (the
        roughness and elephant's foot of two printed faces, section 4 of docs/design.md), but
        never more than the gap at rest, so that no point starts inside its obstacle (next
        to the cavity's tip vertex and the outer root corner the faces meet at an angle and
        the gap at rest falls to zero): g_c = min(allowance, gap at rest). The obstacle is a
        continuous function of position, so no mesh node decides where contact may start.
        """
        t, h2, a = cell.t_mm, 0.5 * cell.h_mm, cell.contact_allowance_mm
        inner = cell.inner_profile_xz()
        (ax, az), (cx, cz) = inner[0], inner[1]
        outer = cell.outer_profile_xz()
        (px, pz), (bx, bz) = outer[0], outer[1]

        def on_segment(x0, z0, x1, z1):
            ux = np.array([x1 - x0, z1 - z0]) / math.hypot(x1 - x0, z1 - z0)
            rel = xy - np.array([[x0], [z0]])
            along = ux[0] * rel[0] + ux[1] * rel[1]
            across = -ux[1] * rel[0] + ux[0] * rel[1]
            return (np.abs(across) < tol) & (along >= -tol) & (along <= math.hypot(x1 - x0, z1 - z0) + tol)

        z_dof = ~is_x & ~on_tip & ~on_bottom
        on_pad_face = (np.abs(xy[1] - t) < tol) & (xy[0] <= ax + tol)
        self.pad_z = np.flatnonzero(on_pad_face & z_dof)
        wall_in = np.flatnonzero(on_segment(ax, az, cx, cz) & ~on_pad_face & z_dof)
        if self.fillet is not None:  # the face from T2 up, then the fillet's arc
            T2 = self.fillet.T2
            wall_out = np.flatnonzero(on_segment(T2[0], T2[1], bx, bz) & z_dof)
            arc = self._fillet_arc_dofs(self.fillet, xy, tol)
            wall_out = np.concatenate([wall_out, np.setdiff1d(arc, wall_out)])
        else:
            wall_out = np.flatnonzero(on_segment(px, pz, bx, bz) & z_dof)
        self.inner_z = np.concatenate([self.pad_z, wall_in])
        z = xy[1]
        rest_in = 2.0 * (h2 - z[self.inner_z])  # gap to the mirror image at rest
        rest_out = z[wall_out]  # gap to the plate at rest
        # clear gap at touch: the allowance between the pads (parallel faces), none where faces
        # close at an angle (zipping from a vertex)
        touch_in = np.where(np.arange(self.inner_z.size) < self.pad_z.size, a, 0.0)
        self.contact_dofs = np.concatenate([self.inner_z, wall_out])
        self.contact_sign = np.concatenate([np.ones(self.inner_z.size), -np.ones(wall_out.size)])
        self.n_inner = self.inner_z.size
        # obstacle position in u_z at d = 0, and its rate with d (the mirror plane moves by -d/2)
        self.obstacle_u0 = np.concatenate([0.5 * (rest_in - touch_in), -rest_out])
        self.obstacle_rate = np.concatenate([np.full(self.inner_z.size, -0.5), np.zeros(wall_out.size)])

    def _fillet_arc_dofs(self, f: RootFillet, xy, tol) -> np.ndarray:
        """The z-dofs on the root fillet ``f``'s arc: on the mesh's boundary, inside the triangle
        A T1 T2 and off the plate (the fillet's face edge A-T2 is inside the solid)."""
        b, mesh = self.basis, self.mesh
        facets = mesh.boundary_facets()
        dofs = np.unique(np.concatenate([b.nodal_dofs[1][mesh.facets[:, facets]].ravel(), b.facet_dofs[1][facets]]))
        rel = xy[:, dofs] - f.A[:, None]
        u = (f.T2 - f.A) / f.tangent_mm
        along_face = u[0] * rel[0] + u[1] * rel[1]  # the triangle: z > 0, below the face, before T1 T2
        below_face = u[0] * rel[1] - u[1] * rel[0]
        n = np.array([math.cos(0.5 * f.theta_rad), math.sin(0.5 * f.theta_rad)])  # the bisector
        inside = (rel[1] > tol) & (below_face < tol) & (n[0] * rel[0] + n[1] * rel[1] <= float(n @ (f.T1 - f.A)) + tol)
        return dofs[inside & (along_face > -tol)]

    # residual and tangent -------------------------------------------------------
    def assemble(self, u, need_K=True):
        """Residual r (N,) and, with ``need_K``, the tangent K (CSR) at the displacement u.

        Works on any object with ``basis``, ``mu`` and ``lam`` (the tests reuse it on their own
        meshes); raises FloatingPointError when an element inverts (J <= 0).
        """
        asm = _assembler(self.basis)
        r, state = asm.residual(u, self.mu, self.lam)
        return r, (asm.tangent(state, self.mu, self.lam) if need_K else None)

    def obstacle(self, d):
        """Where each contact dof's u_z meets its obstacle at compression d (mm)."""
        return self.obstacle_u0 + self.obstacle_rate * d

    def rate(self, u, active, d):
        """(du/dd (N,), dF/dd in N/mm) of the converged state (u, active) at compression d: one
        linear solve with the state's tangent, the tip and the active inner contacts moving with
        the mirror plane, the active outer contacts held on the plate. dF/dd is the lock's test,
        du/dd the path's tangent (the next step's predictor)."""

        asm = _assembler(self.basis)
        if active is None:
            active = np.zeros(self.contact_dofs.size, bool)
        _, kin = asm.residual(u, self.mu, self.lam)
        K = asm.tangent(kin, self.mu, self.lam)
        contact = self.contact_dofs[active]
        block = self.free_block(np.sort(contact))
        free = block.free
        v = self.pinned_rate()
        v[contact] = self.obstacle_rate[active]
        v[free] = block.solve(K, -(K @ v)[free])
        f = K @ v
        inner = active.copy()
        inner[self.n_inner :] = False
        return v, float(-(f[self.tip_z].sum() + f[self.contact_dofs[inner]].sum()) * self.depth_factor)

    def pinned_rate(self) -> np.ndarray:
        """du/dd on the held dofs: the tip face moves by -1/2 per mm of compression, the bonded
        face stays (a tilted problem moves it too: mst_cli.model.mechanics.continuum_tilt)."""
        v = np.zeros(self.basis.N)
        v[self.tip_z] = -0.5
        return v

    def pad_margin(self, u, d):
        """Smallest clear gap between the inner pads, less the allowance (mm; <= 0: they meet)."""
        ob = self.obstacle(d)[: self.pad_z.size]
        return 2.0 * float((ob - u[self.pad_z]).min()) if self.pad_z.size else math.inf

    def free_block(self, pinned_extra=()) -> _FreeBlock:
        """The free dofs with ``pinned_extra`` also pinned, and how to cut their block out of a
        tangent (:class:`_FreeBlock`). Cached per pinned set: the pattern is fixed, so after the
        first time a block costs one gather."""
        key = np.asarray(pinned_extra, dtype=np.int64).tobytes()
        block = self._blocks.get(key)
        if block is None:
            block = self._blocks[key] = _FreeBlock(_assembler(self.basis), np.setdiff1d(self.free, pinned_extra))
        return block

    def solve_step(self, u, d, active=None, max_iter=60, rtol=1e-8, pads=False):
        """Newton at compression d from the state u, with frictionless contact of every face
        that can close (:meth:`_contact_sets`) as an active set updated inside the iterations
        (penetrating points are pinned to their obstacle, points whose contact force would
        pull are released; converged when the residual is small and the set no longer
        changes). ``pads``: whether the inner pads may touch (past the lock).

        Returns (u, iterations, active set); iterations counts the residual checks after the
        first pass (which imposes the new d), as :func:`~mst_cli.model.mechanics.path.follow_to_event` expects.
        """
        u, it, active, _ = self._newton(u, d, active, max_iter, rtol, pads)
        return u, it, active

    def _newton(self, u, d, active=None, max_iter=60, rtol=1e-8, pads=False):
        """:meth:`solve_step`, also returning the residual at the solution (for :meth:`force`)."""

        asm = _assembler(self.basis)
        dofs, sign = self.contact_dofs, self.contact_sign
        eligible = np.ones(dofs.size, bool)
        if not pads:
            eligible[: self.pad_z.size] = False
        active = np.zeros(dofs.size, bool) if active is None else active & eligible
        u = u.copy()
        obstacle = self.obstacle(d)
        tol = 1e-9 * self.cell.h_mm
        scale = None
        contact_set = _ActiveSet(eligible, tol)
        r, kin = asm.residual(u, self.mu, self.lam)
        for it in range(1, max_iter + 1):
            contact = dofs[active]
            pinned = np.concatenate([self.tip_z, contact])
            target = np.concatenate([np.full(self.tip_z.size, -0.5 * d), obstacle[active]])
            block = self.free_block(np.sort(contact))
            free = block.free
            reaction = abs(r[pinned].sum())
            scale = max(reaction, 1e-12 * self.mu * self.cell.t_mm) if scale is None else max(scale, reaction)
            jump = target - u[pinned]
            if it > 1 and np.linalg.norm(r[free]) <= rtol * scale and not np.any(np.abs(jump) > tol):
                updated = contact_set.update(active, sign * (u[dofs] - obstacle), sign * r[dofs])
                if updated is None:
                    return u, it - 1, active, r
                active = updated
                continue
            # the tangent only where a correction is solved (not at the converged point)
            K = asm.tangent(kin, self.mu, self.lam)
            jump_all = np.zeros(self.basis.N)
            jump_all[pinned] = jump
            rhs = -r[free] - (K @ jump_all)[free]
            du = block.solve(K, rhs)
            if not np.all(np.isfinite(du)):
                raise FloatingPointError("singular tangent")
            u_try = u.copy()
            u_try[pinned] = target
            # backtrack when the full update would invert an element (J <= 0); the residual of
            # the accepted update is the next iteration's
            for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625):
                u_try[free] = u[free] + alpha * du
                try:
                    r, kin = asm.residual(u_try, self.mu, self.lam)
                    break
                except FloatingPointError:
                    continue
            else:
                raise FloatingPointError("every damped Newton update inverts an element")
            u = u_try
            if it > 1:  # let the set follow the iterate (semi-smooth Newton)
                active = active | (eligible & (sign * (u[dofs] - obstacle) > tol))
        raise FloatingPointError("Newton did not converge")

    def force(self, u, active, r=None):
        """Layer force F (N) = what crosses the mirror plane (tip face + inner contact), and the
        relative imbalance against the support reactions (bonded face, pad cut, and the outer
        face's contact with the plate: an equilibrium check). ``r``: the residual at u."""
        if r is None:
            r, _ = self.assemble(u, need_K=False)
        inner = active.copy()
        inner[self.n_inner :] = False
        outer = active.copy()
        outer[: self.n_inner] = False
        f_mirror = -(r[self.tip_z].sum() + r[self.contact_dofs[inner]].sum())
        support = np.setdiff1d(self.support_z, self.contact_dofs[active])
        f_support = r[support].sum() + r[self.contact_dofs[outer]].sum()
        if self.plate is not None:  # the plate's push on the outer face, a penalty
            f_support += float(np.sum(self.plate.kappa * self.plate.overlap_mm(u)))
        balance = abs(f_mirror - f_support) / max(abs(f_mirror), 1e-300)
        return f_mirror * self.depth_factor, balance


def solve_continuum(
    cell: HexCell,
    material: Material,
    n_thick: int = DEFAULT_N_THICK,
    n_length: int = DEFAULT_N_LENGTH,
    levels: int = DEFAULT_LEVELS,
    first_step_frac: float = 0.125,
    max_steps: int = 200,
    path_levels: int = 0,
    path_corners: tuple[str, ...] = CORNERS,
    path_radius_in_t: float = REFINE_RADIUS_IN_T,
    plate_penalty_per_mm: float | None = None,
    root_fillet_mm: float = 0.0,
) -> ContinuumResult:
    """Nonlinear force-displacement of one layer through closure, up to its lock.

    Displacement control with adaptive steps: a step that fails to converge is halved, a step
    that converges in few Newton iterations lets the next grow. The lock, where the tangent
    stiffness jumps, is bracketed between two converged steps and bisected
    (:func:`follow_to_lock`; the driver is L1's too: :mod:`mst_cli.model.mechanics.path`).

    ``path_levels``: corner refinement rounds of the path's own mesh (default 0; its forces
    are scaled by the linear stiffness ratio to the ``levels`` mesh). A convergence study
    knob: studies/sweep_lock.py and docs/design.md section 4 give what it changes;
    ``path_corners`` and ``path_radius_in_t`` say where it refines (studies/steep_lock.py
    refines at the inner wall root alone, where a steep wall's contact front runs).
    ``plate_penalty_per_mm``: the outer face's contact with the plate as a penalty of that
    stiffness (pressure per mm of overlap, in units of the shear modulus; :class:`_PlatePenalty`)
    instead of the active set: a study knob for root-graded path meshes.
    ``root_fillet_mm``: the outer root's printed fillet (:class:`RootFillet`; 0 the sharp corner), a study knob.

    Raises
    ------
    ValueError          for a cell whose profile cannot be meshed (broken validity rule)
    ContinuumError      when the path cannot be followed (steps stalled below 1e-7 of the
                        stroke, no contact up to D_MAX_OVER_NOMINAL times it)
    """
    _require_meshable(cell)
    mesh = (cell, material, n_thick, n_length)
    fine = _Problem(*mesh, levels, root_fillet_mm=root_fillet_mm)
    k_lin = linear_k(fine)
    # The nonlinear path runs on the mesh without corner refinement: on the refined one the
    # elements at the cavity's near-crack tip invert long before contact. Its forces are
    # scaled by k_fine / k_coarse, the ratio of the two meshes' linear stiffnesses (the
    # corner singularity's mesh error; the benchmark's convergence study records it).
    own_path_mesh = levels != path_levels or plate_penalty_per_mm is not None
    prob = (
        _Problem(*mesh, path_levels, path_corners, path_radius_in_t, plate_penalty_per_mm, root_fillet_mm)
        if own_path_mesh
        else fine
    )
    k_path = linear_k(prob) if own_path_mesh else k_lin
    mesh_scale = k_lin / k_path
    try:
        path, ratio_after = follow_to_lock(
            prob, k_path, StepControl(first_step_rel=first_step_frac, max_steps=max_steps)
        )
    except PathError as exc:
        raise ContinuumError(f"continuum solve: {exc} for {cell}") from None
    return _result(prob, path, k_lin, mesh_scale, ratio_after, int(fine.basis.N))


def smallest_stretches(prob: _Problem, u: np.ndarray) -> np.ndarray:
    """The smallest principal stretch at every quadrature point (n_el, n_q) of the state ``u``."""
    asm = _assembler(prob.basis)
    asm = asm.base if isinstance(asm, _PlatePenalty) else asm
    grad = np.einsum("eqki,ei->keq", asm.B, u[asm.dofs])
    Fm = grad.reshape(2, 2, *grad.shape[1:]) + np.eye(2)[:, :, None, None]
    c11, c22 = Fm[0, 0] ** 2 + Fm[1, 0] ** 2, Fm[0, 1] ** 2 + Fm[1, 1] ** 2  # C = F^T F
    c12 = Fm[0, 0] * Fm[0, 1] + Fm[1, 0] * Fm[1, 1]
    return np.sqrt(0.5 * (c11 + c22) - np.sqrt(0.25 * (c11 - c22) ** 2 + c12**2))


def smallest_stretch(prob: _Problem, u: np.ndarray) -> float:
    """The smallest principal stretch anywhere in the state ``u``: where it falls below
    CREASE_ONSET_STRETCH (:mod:`~mst_cli.model.material`), a compressed free face creases."""
    return float(smallest_stretches(prob, u).min())


def _require_meshable(cell: HexCell) -> None:
    """Raise ValueError for a cell whose quarter profile cannot be meshed."""
    bad = [v for v in cell.violations() if v.rule in ("pad_width", "lock_stroke")]
    if bad:
        raise ValueError(f"continuum model needs a meshable cell: {bad[0].message}")
    if not (cell.p_mm > 0 and cell.h_mm > 2 * cell.t_mm):
        raise ValueError("continuum model needs a meshable cell: h <= 2t or p <= 0")


def _result(prob, path, k_lin: float, mesh_scale: float, ratio_after: float, n_dofs: int) -> ContinuumResult:
    """The path's samples on ``prob``'s mesh as a ContinuumResult, forces scaled to the refined mesh."""
    return ContinuumResult(
        np.array([0.0] + path.d_mm),
        np.array([0.0] + [F * mesh_scale for F, _, _ in path.observations]),
        k_lin,
        float(path.d_mm[-1]),
        path.event_at,
        path.iterations,
        n_dofs,
        float(path.observations[-1][1]),
        float(mesh_scale),
        float(ratio_after),
        np.array([0] + [n for _, _, n in path.observations]),
        smallest_stretch(prob, path.state.u),
    )


@dataclass(frozen=True)
class _PathPoint:
    """A converged point of the load path: what a solve restarts from, and what the lock test,
    the next step's predictor and the chord's error estimate read."""

    u: np.ndarray  # displacements (N,), mm
    active: np.ndarray | None  # contact points held on their obstacles
    residual: np.ndarray | None  # at u (None at rest)
    d_mm: float
    du_dd: np.ndarray  # the path's tangent
    k_t_N_per_mm: float  # dF/dd
    force: tuple[float, float]  # (F in N, equilibrium imbalance)


class _LockPath:
    """The callbacks :func:`~mst_cli.model.mechanics.path.follow_to_event` drives for one problem."""

    def __init__(self, prob, k_ref_N_per_mm: float):
        self.prob, self.k_ref = prob, k_ref_N_per_mm

    def point(self, u, active, r, d) -> _PathPoint:
        v, k_t = self.prob.rate(u, active, d)
        return _PathPoint(u, active, r, d, v, k_t, self.prob.force(u, active, r) if r is not None else (0.0, 0.0))

    def solve(self, at: _PathPoint, d: float, depth: int = 0) -> tuple[_PathPoint, int]:
        prob = self.prob
        try:
            try:  # from the path's tangent: first order in the step, Newton starts close
                u, it, active, r = prob._newton(at.u + (d - at.d_mm) * at.du_dd, d, at.active, pads=True)
            except FloatingPointError:  # that start inverts an element or does not converge
                u, it, active, r = prob._newton(at.u, d, at.active, pads=True)
        except FloatingPointError:
            # sub-step from the given point (the event search starts each trial from the
            # bracket's near end, which can be a long step away where a wall is pinched)
            if depth >= 3 or at.residual is None:
                raise
            mid, it0 = self.solve(at, 0.5 * (at.d_mm + d), depth + 1)
            end, it1 = self.solve(mid, d, depth + 1)
            return end, it0 + it1
        return self.point(u, active, r, d), it

    def margin(self, at: _PathPoint, d: float) -> tuple[float, str]:
        # a face pinched between the plate and its mirror, or the pads meeting
        return LOCK_STIFFNESS_FACTOR - at.k_t_N_per_mm / self.k_ref, _lock_label(self.prob, at.active)

    def guess(self, at: _PathPoint, d_lo: float, d_hi: float) -> float | None:
        """Where in (d_lo, d_hi) the next contact point is expected to touch: each idle point's
        gap over its closing rate along the path's tangent, the earliest (None: none closes
        there). The lock is a contact engaging, so this is where its tangent jumps."""
        prob = self.prob
        idle = ~at.active if at.active is not None else np.ones(prob.contact_dofs.size, bool)
        dofs, sign = prob.contact_dofs[idle], prob.contact_sign[idle]
        penetration = sign * (at.u[dofs] - prob.obstacle(at.d_mm)[idle])  # < 0: a gap
        closing = sign * (at.du_dd[dofs] - prob.obstacle_rate[idle])  # d(penetration)/dd
        ok = closing > 0.0
        touch = at.d_mm - penetration[ok] / closing[ok]
        touch = touch[(touch > d_lo) & (touch < d_hi)]
        return float(touch.min()) if touch.size else None

    @staticmethod
    def chord(at: _PathPoint, d: float, new: _PathPoint, d_new: float) -> float:
        # a quadratic between the two points bows off their chord by (d_new - d) |k_new - k| / 8
        return (d_new - d) * abs(new.k_t_N_per_mm - at.k_t_N_per_mm) / 8.0 / max(abs(new.force[0]), 1e-300)

    @staticmethod
    def observe(at: _PathPoint, d: float) -> tuple[float, float, int]:
        return at.force[0], at.force[1], int(at.active.sum()) if at.active is not None else 0


def follow_to_lock(
    prob: _Problem,
    k_ref_N_per_mm: float,
    steps: StepControl | None = None,
    d_max_over_nominal: float = D_MAX_OVER_NOMINAL,
) -> tuple:
    """Follow a built problem's load path from rest to its lock (the tangent stiffness reaching
    LOCK_STIFFNESS_FACTOR x ``k_ref_N_per_mm``), then one short step on into the locked branch.

    Works on any problem with L2's interface (``_newton``, ``rate``, ``force``; the 3D check in
    benchmarks/ reuses it). Steps are kept only while the chord between two points stays within
    ``steps.chord_tol_rel`` (LAW_CHORD_TOL_REL unless given) of the curve. Returns (the
    :class:`~mst_cli.model.mechanics.path.PathResult`, whose observations are (F in N,
    equilibrium imbalance, contact points in contact) and whose state is the lock's
    :class:`_PathPoint`, and the tangent / k just past the lock (nan when that step does not
    converge)). Raises PathError.
    """
    cell = prob.cell
    d_nom = cell.h_mm - 2 * cell.t_mm - cell.contact_allowance_mm  # pads meet here if rigid
    steps = steps or StepControl()
    if steps.chord_tol_rel is None:
        steps = replace(steps, chord_tol_rel=LAW_CHORD_TOL_REL)
    lp = _LockPath(prob, k_ref_N_per_mm)
    # the path's linear algebra is a few hundred banded solves of 500-1200 unknowns (half-band
    # ~43), where OpenBLAS's threads cost more than they give: one thread makes an in-process
    # law about an eighth faster on two cores (benchmarks/l2_cost.py, parts 1 and 2), and
    # makes it the law fork_map's one-thread workers solve
    with one_blas_thread():
        return _follow_path(prob, lp, d_nom, steps, d_max_over_nominal)


def _follow_path(prob, lp: _LockPath, d_nom: float, steps: StepControl, d_max_over_nominal: float) -> tuple:
    """:func:`follow_to_lock`'s path, its callbacks ``lp``, ``d_nom`` the rigid-pad stroke."""
    rest = lp.point(np.zeros(prob.basis.N), None, None, 0.0)
    path = follow_to_event(
        lp.solve,
        lp.margin,
        lp.observe,
        rest,
        d_nom,
        d_max_over_nominal * d_nom,
        steps,
        LOCK_TOLERANCES,
        chord=lp.chord,
        guess=lp.guess,
    )
    d_after = path.d_mm[-1] + LOCK_TOLERANCES.event_width_rel * d_nom * 10
    try:
        after, _ = lp.solve(path.state, d_after)
        ratio_after = after.k_t_N_per_mm / lp.k_ref
    except FloatingPointError:
        ratio_after = math.nan
    return path, ratio_after


def _lock_label(prob, active) -> str:
    """What closed at the lock: "pad" when the pads touch, else "wall" (a wall pinched)."""
    return "pad" if active is not None and active[: prob.pad_z.size].any() else "wall"


def linear_stiffness_N_per_mm(
    cell: HexCell,
    material: Material,
    n_thick: int = DEFAULT_N_THICK,
    n_length: int = DEFAULT_N_LENGTH,
    levels: int = DEFAULT_LEVELS,
) -> float:
    """Small-strain layer stiffness k (N/mm) of the L2 model alone (one linear solve)."""
    return linear_k(_Problem(cell, material, n_thick, n_length, levels))


def linear_k(problem: _Problem) -> float:
    """Small-strain stiffness of a built problem: one linear solve with the tangent at u = 0."""

    _, K0 = problem.assemble(np.zeros(problem.basis.N))
    ul = np.zeros(problem.basis.N)
    ul[problem.tip_z] = -0.5
    # cut directly: a one-off solve needs no cached banded block (free_block is the path's)
    f = problem.free
    K_ff = K0[f][:, f].tocsc()
    # at rest K_ff is linear elasticity held on the bonded face: symmetric positive definite,
    # so SuperLU's symmetric mode (an A + A^T ordering, no pivoting) is safe, and on the fine
    # meshes up to 2x faster than the general LU
    lu = splu(K_ff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    ul[f] = lu.solve(-(K0 @ ul)[f])
    if not np.all(np.isfinite(ul)):
        raise ContinuumError("singular small-strain tangent")
    return float(-(K0 @ ul)[problem.tip_z].sum() * problem.depth_factor)


@law_cache(maxsize=256)
def continuum_layer(cell: HexCell, material: Material) -> TabulatedLockingLayer:
    """The L2 law of one cell: the FE curve up to its lock, then the locked branch (walls + contact column)."""
    res = solve_continuum(cell, material)
    return locked_tabulated_law(
        cell, material, res.displacement_mm, res.force_N, res.k_linear_N_per_mm, False, res.min_stretch_at_lock
    )
