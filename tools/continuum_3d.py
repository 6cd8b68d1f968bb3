"""A 3D check of rung L2's plane strain (issue 20, part 4): the quarter profile extruded through
the web's depth, with faces free at y = +-D/2. A benchmark kernel, not part of the package
(imported by studies/bench_3d.py and tests/test_3d_check.py).

Model. The plane-strain rung (mst_cli/model/mechanics/continuum/) meshes a quarter of the
profile (x >= 0, z <= h/2) with P2 triangles. Here that triangle mesh (without corner
refinement, ``levels=0``) is extruded along y from the symmetry plane y = 0 (u_y = 0) to the
free face y = D/2, in prism layers graded toward the free face (its boundary layer is where 3D
differs from plane strain); each prism is split into 3 tetrahedra by the node-index rule (the
diagonal of every quad face is fixed by the global numbers of its two vertical edges, so the
faces of neighbouring prisms match), P2 tetrahedra (skfem MeshTet + ElementVector(ElementTetP2())).

Everything else is the 2D rung's, applied through the depth: bottom z = 0 bonded (u = 0), pad
cut u_x = 0, tip face z = h/2 at u_z = -d/2 (free in x and y), the same contact surfaces (their
z-dofs at every y, the same obstacles), full 3D compressible Neo-Hookean
P = mu F + (lam ln J - mu) F^-T with its tangent. :class:`Problem3D` subclasses the 2D
``ContactProblem`` and registers a 3D assembler for its basis, so the Newton/active-set solve, the
tangent stiffness, the force and the lock search are the 2D rung's own code, unchanged.

Force: the model carries half the depth (y in [0, D/2]) of one chevron's half profile, so the
layer force is F = 2 (chevrons) x 2 (halves of the depth) x the tip reaction.
"""

from __future__ import annotations

import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics.continuum.assembly import csr_scatter, lame_3d, set_assembler
from mst_cli.model.mechanics.path import PathError


# --------------------------------------------------------------------------- mesh
def graded_depth(length_mm: float, n_layers: int, first_mm: float, free_at_end: bool = True) -> np.ndarray:
    """n_layers + 1 positions on [0, length]: geometric layers, the one at the free face
    (y = length when ``free_at_end``) ``first_mm`` thick (uniform if that is not thinner)."""
    if first_mm * n_layers >= length_mm or n_layers == 1:
        return np.linspace(0.0, length_mm, n_layers + 1)
    lo, hi = 1.0, 10.0  # ratio r with first * (r^n - 1) / (r - 1) = length
    for _ in range(200):
        r = 0.5 * (lo + hi)
        total = first_mm * (r**n_layers - 1.0) / (r - 1.0)
        lo, hi = (r, hi) if total < length_mm else (lo, r)
    sizes = first_mm * r ** np.arange(n_layers)  # from the free face inward
    sizes *= length_mm / sizes.sum()
    y = np.concatenate([[0.0], np.cumsum(sizes[::-1])])
    y[-1] = length_mm
    return y if free_at_end else length_mm - y[::-1]


def extrude(points_xz: np.ndarray, triangles: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Prism layers of a triangle mesh (points (2, n) in x, z) between the depths ``y``, each
    prism split into 3 tetrahedra. Returns points (3, n (len(y))) in x, y, z and tets (4, m).

    Split: with the prism's vertices sorted by their 2D index i0 < i1 < i2 (b: bottom, t: top),
    the tets (b0 b1 b2 t0), (b1 b2 t0 t1), (b2 t0 t1 t2); the quad face over the edge i < j
    gets the diagonal b_j - t_i in every prism that shares it (conforming)."""
    n = points_xz.shape[1]
    nl = len(y) - 1
    pts = np.vstack([np.tile(points_xz[0], nl + 1), np.repeat(np.asarray(y, float), n), np.tile(points_xz[1], nl + 1)])
    s = np.sort(triangles, axis=0)
    tets = []
    for k in range(nl):
        b, t = s + k * n, s + (k + 1) * n
        tets += [
            np.stack([b[0], b[1], b[2], t[0]]),
            np.stack([b[1], b[2], t[0], t[1]]),
            np.stack([b[2], t[0], t[1], t[2]]),
        ]
    tet = np.concatenate(tets, axis=1)
    # positive orientation
    p0, p1, p2, p3 = (pts[:, tet[i]] for i in range(4))
    vol = np.einsum("ie,ie->e", np.cross(p1 - p0, p2 - p0, axis=0), p3 - p0)
    flip = vol < 0
    tet[1, flip], tet[2, flip] = tet[2, flip], tet[1, flip].copy()
    return pts, np.ascontiguousarray(tet)


# --------------------------------------------------------------------------- assembly
def kinematics(Fm, mu, lam):
    """Compressible Neo-Hookean at F (dim, dim, ...): P = mu F + (lam ln J - mu) F^-T, and the
    pieces of its tangent (F^-T, ln J). The 2D rung's formula, for any dimension."""
    Fq = np.moveaxis(Fm, (0, 1), (-2, -1))
    J = np.linalg.det(Fq)
    if np.any(J <= 0):
        raise FloatingPointError("inverted element")
    FiT = np.moveaxis(np.linalg.inv(Fq), (-2, -1), (1, 0))  # (dim, dim, ...) = F^-T
    lnJ = np.log(J)
    return mu * Fm + (lam * lnJ - mu) * FiT, FiT, lnJ


class Assembler:
    """The 2D rung's vectorised assembler (continuum.assembly.Assembler) for any dimension: gradients,
    weights and the CSR pattern are the reference mesh's, computed once."""

    def __init__(self, basis):

        dofs = basis.element_dofs
        n_loc, n_el = dofs.shape
        self.dim = dim = basis.mesh.dim()
        grads = np.array([basis.basis[i][0].grad for i in range(n_loc)])  # (n_loc, dim, dim, n_el, n_q)
        n_q = grads.shape[-1]
        self.B = np.ascontiguousarray(grads.reshape(n_loc, dim * dim, n_el, n_q).transpose(2, 3, 1, 0))
        Bw = self.B * basis.dx[:, :, None, None]
        self.BwT = np.ascontiguousarray(Bw.transpose(0, 3, 1, 2).reshape(n_el, n_loc, dim * dim * n_q))
        self.dofs = np.ascontiguousarray(dofs.T)
        self.N = basis.N
        self.indices, self.indptr, self.nnz, self.scatter = csr_scatter(self.dofs, self.N)

    def residual(self, u, mu, lam):
        dim = self.dim
        grad_u = np.einsum("eqki,ei->keq", self.B, u[self.dofs])
        Fm = grad_u.reshape(dim, dim, *grad_u.shape[1:]) + np.eye(dim)[:, :, None, None]
        P, FiT, lnJ = kinematics(Fm, mu, lam)
        if not np.all(np.isfinite(P)):
            raise FloatingPointError("inverted element")
        n_el, n_q = lnJ.shape
        Pk = P.reshape(dim * dim, n_el, n_q).transpose(1, 2, 0).reshape(n_el, dim * dim * n_q)
        r_el = np.einsum("eik,ek->ei", self.BwT, Pk)
        return np.bincount(self.dofs.ravel(), weights=r_el.ravel(), minlength=self.N), (FiT, lnJ)

    def tangent(self, state, mu, lam):
        """A[(a, b), (m, n)] = mu d_am d_bn - (lam ln J - mu) FiT_an FiT_mb + lam FiT_ab FiT_mn."""
        from scipy.sparse import csr_matrix

        FiT, lnJ = state
        dim = self.dim
        Fi = FiT.transpose(2, 3, 0, 1)
        n_el, n_q = lnJ.shape
        f = Fi.reshape(n_el, n_q, dim * dim)
        swap = np.einsum("eqan,eqmb->eqabmn", Fi, Fi).reshape(n_el, n_q, dim * dim, dim * dim)
        A = lam * f[..., :, None] * f[..., None, :] - (lam * lnJ - mu)[..., None, None] * swap + mu * np.eye(dim * dim)
        AB = (A @ self.B).reshape(n_el, dim * dim * n_q, -1)
        K_el = self.BwT @ AB
        data = np.bincount(self.scatter, weights=K_el.ravel(), minlength=self.nnz)
        return csr_matrix((data, self.indices, self.indptr), shape=(self.N, self.N))


# --------------------------------------------------------------------------- problem
class Problem3D(L2.ContactProblem):
    """The quarter profile extruded over y in ``y_mm`` (increasing from 0).

    ``y_sym``: u_y = 0 on y = 0 (the web's mid-plane); ``y_held_far``: u_y = 0 on the far face
    too (a slice of plane strain, for the checks), else that face is free. ``depth_factor``
    turns the quarter's tip reaction into the layer force (default 2 b / depth modelled, the 2D
    rung's 2 b per mm of depth: 4 for y in [0, D/2] with the mirror at y = 0)."""

    def __init__(
        self,
        cell: HexCell,
        material,
        y_mm,
        n_thick: int = 2,
        n_length: int = 8,
        y_sym: bool = True,
        y_held_far: bool = False,
        intorder: int = 4,
        depth_factor=None,
    ):
        from skfem import Basis, ElementTetP2, ElementVector, MeshTet

        self.cell = cell
        pts2, tri2, x_cut = L2.quarter_profile_mesh(cell, n_thick, n_length)
        y_mm = np.asarray(y_mm, float)
        self.mesh = MeshTet(*extrude(pts2, tri2, y_mm))
        self.basis = Basis(self.mesh, ElementVector(ElementTetP2()), intorder=intorder)
        set_assembler(self.basis, Assembler(self.basis))
        self.mu, self.lam = lame_3d(material.youngs_modulus_MPa, material.poisson_ratio)
        b = self.basis
        h2 = 0.5 * cell.h_mm
        tol = 1e-9 * max(cell.width_mm, cell.h_mm, float(y_mm[-1]))
        xyz = b.doflocs
        comp = np.zeros(b.N, int)
        for c in range(3):
            comp[b.nodal_dofs[c]] = c
            comp[b.edge_dofs[c]] = c
        is_x, is_y, is_z = comp == 0, comp == 1, comp == 2
        on_bottom = np.abs(xyz[2]) < tol
        on_cut = np.abs(xyz[0] - x_cut) < tol
        on_tip = np.abs(xyz[2] - h2) < tol
        held_y = np.zeros(b.N, bool)
        if y_sym:
            held_y |= np.abs(xyz[1] - y_mm[0]) < tol
        if y_held_far:
            held_y |= np.abs(xyz[1] - y_mm[-1]) < tol
        self.fixed_zero = np.flatnonzero(on_bottom | (on_cut & is_x) | (held_y & is_y))
        self.tip_z = np.flatnonzero(on_tip & is_z & ~on_bottom)
        self.support_z = np.flatnonzero((on_bottom | on_cut) & is_z)
        self.dirichlet = np.union1d(self.fixed_zero, self.tip_z)
        self.free = np.setdiff1d(np.arange(b.N), self.dirichlet)
        self._blocks = {}
        self.x_cut = x_cut
        # the 2D rung's contact surfaces, read in (x, z) at every y, on the z-dofs only
        self._contact_sets(cell, xyz[[0, 2]], ~is_z, tol, on_bottom, on_tip)
        self.h2 = h2
        depth = float(y_mm[-1] - y_mm[0])
        self.depth_factor = 2.0 * cell.b_mm / depth if depth_factor is None else depth_factor


def problem_2d(cell, material, n_thick: int = 2, n_length: int = 8):
    """The plane-strain rung's problem on the same in-plane mesh (no corner refinement)."""
    return L2.ContactProblem(cell, material, L2.MeshOptions(n_thick, n_length, 0))


# --------------------------------------------------------------------------- path to the lock
def solve_to_lock(prob) -> dict:
    """The 2D rung's path to the lock (solve_continuum with levels = 0) on any built problem.

    Returns k (small-load), d_lock, R (F at the lock), the equilibrium check, what closed,
    Newton iterations and the path's points (d, F)."""
    k = L2.linear_k(prob)
    try:
        path, _ = L2.follow_to_lock(prob, k)
    except PathError as exc:
        raise L2.ContinuumError(f"3D check: {exc} for {prob.cell}") from None
    return {
        "k": k,
        "d_lock": float(path.d_mm[-1]),
        "R": float(path.observations[-1][0]),
        "balance": float(path.observations[-1][1]),
        "at": path.event_at,
        "iterations": path.iterations,
        "d": np.array(path.d_mm),
        "F": np.array([o[0] for o in path.observations]),
    }


def depth_grading(cell: HexCell, fine: bool) -> np.ndarray:
    """The depth layers of the benchmark: y in [0, D/2], graded to the free face; coarse:
    6 layers, the one at the face t/2 thick; fine: 8 layers, t/4 at the face."""
    half = 0.5 * cell.b_mm
    n, first = (8, 0.25 * cell.t_mm) if fine else (6, 0.5 * cell.t_mm)
    return graded_depth(half, n, min(first, half / n))


def plane_stress_material(material):
    """The plane-strain constants that give plane stress in 2D: E* = E (1 + 2 nu) / (1 + nu)^2,
    nu* = nu / (1 + nu) (so E* / (1 - nu*^2) = E)."""
    from mst_cli.model.material import Material

    E, nu = material.youngs_modulus_MPa, material.poisson_ratio
    return Material(
        name=material.name + " (plane stress)",
        youngs_modulus_MPa=E * (1 + 2 * nu) / (1 + nu) ** 2,
        poisson_ratio=nu / (1 + nu),
    )


__all__ = [
    "Assembler",
    "Problem3D",
    "depth_grading",
    "extrude",
    "graded_depth",
    "kinematics",
    "plane_stress_material",
    "problem_2d",
    "solve_to_lock",
]
