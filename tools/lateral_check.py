"""An independent check of L2's lateral stiffness (mst_cli/model/mechanics/continuum_lateral.py).

Built apart from the continuum package on purpose: its own mesh, its own forms, no symmetry:

* the mesh: the whole layer profile (the outer hexagon less the cavity, both chevrons, the full
  pads) as a Delaunay triangulation (scipy) of a triangular lattice of spacing s inside the ring
  plus points every s along its edges, the triangles whose centroid lies in the ring kept
  (:func:`ring_mesh`; the kept area is checked against the polygon's), then ``levels`` rounds of
  red-green refinement within t / 2^i of the ten corners;
* the forms: scikit-fem's own ``linear_elasticity(*lame_parameters(E, nu))`` (plane strain in 2D)
  and a scalar ``laplace`` on P2, assembled by scikit-fem;
* the loads: bottom face held, the top face moved by (1, 0) for k_x, the antiplane u_y = 1 for
  k_y (infinite depth), the reaction summed on the top face times the depth D.

And the depth's own 3D check (:func:`check_k_y_3d_N_per_mm`): the same kind of mesh of the
quarter (x >= 0, z <= h/2) extruded through half the depth, P2 tetrahedra, linear elasticity, the
top plate moved along y (odd about the mid-plane: u_x = 0, u_y = 1/2 there; x = 0 and y = 0
are mirror planes; the face y = D/2 free).

Run:  PYTHONPATH=. .venv/bin/python tools/lateral_check.py    # the bundled sensor's three layers
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.sparse.linalg import spsolve
from scipy.spatial import Delaunay
from skfem import (
    Basis,
    BilinearForm,
    ElementTetP2,
    ElementTriP2,
    ElementVector,
    MeshTet,
    MeshTri,
    asm,
)
from skfem.helpers import dot, grad
from skfem.models.elasticity import lame_parameters, linear_elasticity

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.whole_part_mesh import edge_distance, point_in_polygon, polygon_area

sys.path.insert(0, str(Path(__file__).resolve().parent))
from continuum_3d import extrude, graded_depth  # the 3D check's prism split

# the five cells of docs/design.md section 4.4, inside the printable box (mst_cli/bench/sampling.py)
CHECK_CELLS = {
    "shallow": HexCell(15, 0.8, 2.4),
    "mid": HexCell(33, 1.0, 2.8),
    "steep": HexCell(60, 1.0, 4.0),
    "stubby": HexCell(40, 2.0, 5.0),
    "thin": HexCell(30, 0.45, 3.0),
}
SPACING_IN_T = 0.2  # lattice spacing, in wall thicknesses
LEVELS = 3  # rounds of refinement at the corners


def _edge_points(poly: np.ndarray, spacing: float) -> np.ndarray:
    out = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        n = max(1, int(np.ceil(np.hypot(*(b - a)) / spacing)))
        out.append(a + np.linspace(0.0, 1.0, n, endpoint=False)[:, None] * (b - a))
    return np.concatenate(out)


def _lattice_row(x0: float, x1: float, spacing: float, z: float) -> np.ndarray:
    xs = np.arange(x0, x1, spacing)
    return np.stack([xs, np.full_like(xs, z)], axis=1)


def polygon_mesh(
    outer: np.ndarray, hole: np.ndarray | None, spacing: float, corners: np.ndarray, levels: int, r: float
):
    """MeshTri of ``outer`` less ``hole``: Delaunay of a lattice and the edges' points (module
    docstring), then ``levels`` red-green refinements within r / 2^i of ``corners`` (k, 2)."""
    lo, hi = outer.min(axis=0), outer.max(axis=0)
    dz = spacing * np.sqrt(3.0) / 2.0
    rows = np.arange(lo[1], hi[1] + dz, dz)
    lattice = np.concatenate(
        [_lattice_row(lo[0] + (i % 2) * 0.5 * spacing, hi[0], spacing, z) for i, z in enumerate(rows)]
    )
    edges = [outer] + ([hole] if hole is not None else [])
    keep = point_in_polygon(lattice, outer) & (edge_distance(lattice, outer) > 0.45 * spacing)
    if hole is not None:
        keep &= ~point_in_polygon(lattice, hole) & (edge_distance(lattice, hole) > 0.45 * spacing)
    pts = np.concatenate([lattice[keep]] + [_edge_points(e, spacing) for e in edges])
    tri = Delaunay(pts).simplices
    mid = pts[tri].mean(axis=1)
    solid = point_in_polygon(mid, outer) & (~point_in_polygon(mid, hole) if hole is not None else True)
    e1, e2 = pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    flat = area < 1e-9 * spacing * spacing  # qhull's slivers on collinear edge points
    tri, area = tri[solid & ~flat], area[solid & ~flat]
    want = polygon_area(outer) - (polygon_area(hole) if hole is not None else 0.0)
    if abs(area.sum() - want) > 1e-9 * want:
        raise ValueError(f"lattice mesh covers {area.sum():.9g} mm^2 of {want:.9g}")
    mesh = MeshTri(pts.T.copy(), np.ascontiguousarray(tri.T))
    for i in range(levels):
        c = mesh.p[:, mesh.t].mean(axis=1)
        dist = np.hypot(c[0][None, :] - corners[:, :1], c[1][None, :] - corners[:, 1:])
        marked = np.flatnonzero((dist < r * 0.5**i).any(axis=0))
        if marked.size:
            mesh = mesh.refined(marked)
    return mesh


def ring_mesh(
    cell: HexCell, spacing_in_t: float = SPACING_IN_T, levels: int = LEVELS, mirror: bool = False, filled: bool = False
):
    """The whole profile's mesh (``mirror``: built on the profile mirrored in x, x -> -x;
    ``filled``: the outer hexagon with its cavity filled, a closed layer)."""
    outer, inner = np.array(cell.outer_profile_xz()), np.array(cell.inner_profile_xz())
    if mirror:
        outer, inner = outer[::-1] * [-1, 1], inner[::-1] * [-1, 1]
    if filled:
        return polygon_mesh(outer, None, spacing_in_t * cell.t_mm, outer, levels, 0.5 * cell.t_mm)
    corners = np.concatenate([outer, inner])
    return polygon_mesh(outer, inner, spacing_in_t * cell.t_mm, corners, levels, 0.5 * cell.t_mm)


def quarter_polygon(cell: HexCell) -> np.ndarray:
    """The quarter x >= 0, z <= h/2 of the profile: the bottom pad's right half and the lower wall."""
    (p, _), (w2, h2) = cell.outer_profile_xz()[:2]
    (a, t), (c, _) = cell.inner_profile_xz()[:2]
    return np.array([(0.0, 0.0), (p, 0.0), (w2, h2), (c, h2), (a, t), (0.0, t)])


def _component_dofs(basis) -> tuple[np.ndarray, ...]:
    """Per component of a P2 vector basis, its dofs (at the vertices and on the edges: facets
    in 2D, edges in 3D)."""
    parts = [basis.nodal_dofs, basis.facet_dofs if basis.mesh.dim() == 2 else basis.edge_dofs]
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(basis.mesh.dim()))


def _held_solve(K, N: int, values: dict[int, float] | np.ndarray, held: np.ndarray) -> np.ndarray:
    """u with u[held] = values[held] and K u = 0 on the rest."""
    u = np.zeros(N)
    u[held] = np.asarray(values)[held]
    free = np.setdiff1d(np.arange(N), held)
    u[free] = spsolve(K[free][:, free].tocsc(), -(K @ u)[free])
    return u


def check_k_x_N_per_mm(
    cell: HexCell, material: Material, spacing_in_t: float = SPACING_IN_T, levels: int = LEVELS, mirror: bool = False,
    filled: bool = False,
) -> float:  # fmt: skip
    """k_x (N/mm) of the whole profile in plane-strain linear elasticity: bottom held, top at (1, 0)
    (``filled``: of the cavity filled)."""
    basis = Basis(ring_mesh(cell, spacing_in_t, levels, mirror, filled), ElementVector(ElementTriP2()))
    K = asm(linear_elasticity(*lame_parameters(material.youngs_modulus_MPa, material.poisson_ratio)), basis).tocsr()
    z = basis.doflocs[1]
    tol = 1e-9 * cell.h_mm
    bottom, top = np.abs(z) < tol, np.abs(z - cell.h_mm) < tol
    xdofs, _ = _component_dofs(basis)
    values = np.zeros(basis.N)
    is_x = np.zeros(basis.N, bool)
    is_x[xdofs] = True
    values[top & is_x] = 1.0
    u = _held_solve(K, basis.N, values, np.flatnonzero(bottom | top))
    return float((K @ u)[top & is_x].sum()) * cell.depth_mm


def check_k_y_inf_N_per_mm(
    cell: HexCell, material: Material, spacing_in_t: float = SPACING_IN_T, levels: int = LEVELS, filled: bool = False
) -> float:
    """k_y (N/mm) of an infinitely deep web: antiplane shear G laplace(u_y) = 0 on the whole
    profile (``filled``: the cavity filled), bottom at 0, top at 1, times the depth D."""
    basis = Basis(ring_mesh(cell, spacing_in_t, levels, filled=filled), ElementTriP2())
    G = material.shear_modulus_MPa

    @BilinearForm
    def shear(u, v, w):
        return G * dot(grad(u), grad(v))

    K = asm(shear, basis).tocsr()
    z = basis.doflocs[1]
    tol = 1e-9 * cell.h_mm
    bottom, top = np.abs(z) < tol, np.abs(z - cell.h_mm) < tol
    u = _held_solve(K, basis.N, top.astype(float), np.flatnonzero(bottom | top))
    return float((K @ u)[top].sum()) * cell.depth_mm


def check_k_y_3d_N_per_mm(
    cell: HexCell, material: Material, spacing_in_t: float = 0.35, levels: int = 2, n_layers: int = 10
) -> float:
    """k_y (N/mm) of the web D deep in 3D linear elasticity (module docstring): the quarter's
    mesh extruded through D/2, layers graded towards the free face (first t/2 thick)."""
    quarter = quarter_polygon(cell)
    corners = quarter[1:5]
    mesh2 = polygon_mesh(quarter, None, spacing_in_t * cell.t_mm, corners, levels, 0.5 * cell.t_mm)
    y = graded_depth(0.5 * cell.depth_mm, n_layers, 0.5 * cell.t_mm)
    mesh = MeshTet(*extrude(mesh2.p, mesh2.t, y))
    basis = Basis(mesh, ElementVector(ElementTetP2()))
    K = asm(linear_elasticity(*lame_parameters(material.youngs_modulus_MPa, material.poisson_ratio)), basis).tocsr()
    x, yy, z = basis.doflocs
    tol = 1e-9 * cell.h_mm
    comp = np.zeros(basis.N, np.int64)
    for i, d in enumerate(_component_dofs(basis)):
        comp[d] = i
    bottom, tip = np.abs(z) < tol, np.abs(z - 0.5 * cell.h_mm) < tol
    held = bottom | (tip & (comp != 2)) | ((np.abs(x) < tol) & (comp == 0)) | ((np.abs(yy) < tol) & (comp != 1))
    values = np.where(tip & (comp == 1), 0.5, 0.0)
    u = _held_solve(K, basis.N, values, np.flatnonzero(held))
    return 4.0 * float((K @ u)[tip & (comp == 1)].sum())


if __name__ == "__main__":
    import time

    mat = Material()
    for cell in (HexCell(25, 0.6, 2.0), HexCell(33, 1.0, 2.8), HexCell(37, 1.4, 3.5)):
        t0 = time.time()
        kx, ky = check_k_x_N_per_mm(cell, mat), check_k_y_inf_N_per_mm(cell, mat)
        t1 = time.time()
        ky3 = check_k_y_3d_N_per_mm(cell, mat)
        print(
            cell.theta_deg, cell.t_mm, cell.h_mm, f"{kx:.3f} {ky:.3f} {ky3:.3f} {t1 - t0:.1f}s {time.time() - t1:.1f}s"
        )
