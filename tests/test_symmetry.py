"""Mirror symmetry: the reduced models of rungs L1 and L2 against the full chevron they stand for.

Rung L1 solves one wall with a guided tip on the mirror plane z = h/2 (no rotation, free to
slide in x, moved down by d/2); rung L2 solves a quarter of the profile with the same tip
condition and the pad cut a few t from the wall root. Here both are checked against models
with NO symmetry assumed across z = h/2: the whole chevron (lower wall, tip joint, upper wall),
bottom pad bonded, top pad bonded to a plate pushed down by d. The full model must carry the
same force at every d, and its solution must come out mirror-symmetric by itself (tip at -d/2,
no tip rotation, upper half the mirror image of the lower). A wrong tip condition in the
reduced model -- the tip held in x, or free to rotate -- breaks both.
"""

import math

import numpy as np
import pytest

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics.continuum.assembly import lame_3d
from mst_cli.model.mechanics.frame import _element_forces, _Wall, solve_frame

MAT = Material()
CELLS = [HexCell(35, 0.8, 3.0), HexCell(25, 0.6, 2.0), HexCell(55, 0.5, 5.0)]


# --------------------------------------------------------------------------- rung L1
class FullChevronFrame:
    """The chevron as one chain of corotational elements: bottom root, tip, top root."""

    def __init__(self, cell, n_el_per_wall=12):
        wall = _Wall(cell, MAT, n_el_per_wall)
        lower = wall.X
        upper = np.column_stack([lower[::-1, 0], cell.h_mm - lower[::-1, 1]])[1:]
        self.X = np.vstack([lower, upper])
        seg = np.diff(self.X, axis=0)
        self.l0 = np.hypot(seg[:, 0], seg[:, 1])
        self.beta0 = np.arctan2(seg[:, 1], seg[:, 0])
        self.EA, self.EI = wall.EA, wall.EI
        self.phi = np.concatenate([wall.phi, wall.phi[::-1]])
        self.n_nodes = len(self.X)
        self.tip = n_el_per_wall
        self.ndof = 3 * self.n_nodes
        top = 3 * (self.n_nodes - 1)
        self.top_w = top + 1
        self.pinned = np.array([0, 1, 2, top, top + 1, top + 2])  # clamps; top u_z prescribed
        self.free = np.setdiff1d(np.arange(self.ndof), self.pinned)
        self.dofs = 3 * np.arange(self.n_nodes - 1)[:, None] + np.arange(6)[None, :]

    def assemble(self, u):
        fe, Ke = _element_forces(self.X, u.reshape(-1, 3), self.l0, self.beta0, self.EA, self.EI, self.phi)
        f = np.zeros(self.ndof)
        np.add.at(f, self.dofs, fe)
        K = np.zeros((self.ndof, self.ndof))
        np.add.at(K, (self.dofs[:, :, None], self.dofs[:, None, :]), Ke)
        return f, K

    def solve(self, u, d):
        u = u.copy()
        u[self.top_w] = -d
        for _ in range(40):
            f, K = self.assemble(u)
            if np.linalg.norm(f[self.free]) < 1e-11 * max(1.0, abs(f[self.top_w])):
                return u, -f[self.top_w]
            u[self.free] += np.linalg.solve(K[np.ix_(self.free, self.free)], -f[self.free])
        raise AssertionError("full-chevron Newton did not converge")


@pytest.mark.parametrize("cell", CELLS, ids=str)
def test_frame_one_wall_equals_full_chevron_along_the_whole_path(cell):
    one_wall = solve_frame(cell, MAT)
    full = FullChevronFrame(cell)
    u = np.zeros(full.ndof)
    d_prev = 0.0
    for d, F in zip(one_wall.displacement_mm[1:], one_wall.force_N[1:]):
        # march in sub-steps (the full chain has no adaptive stepping of its own)
        for dd in np.linspace(d_prev, d, 4)[1:]:
            u, f_top = full.solve(u, dd)
        d_prev = d
        F_full = 2 * f_top  # two chevrons of the web in parallel
        assert F_full == pytest.approx(F, rel=1e-7)
        U = u.reshape(-1, 3)
        n = full.tip
        assert U[n, 1] == pytest.approx(-0.5 * d, rel=1e-8)  # tip on the moving mirror plane
        assert abs(U[n, 2]) < 1e-9  # tip does not rotate
        lower, upper = U[: n + 1], U[n:][::-1]
        assert np.allclose(upper[:, 0], lower[:, 0], atol=1e-9 * d)  # mirror image in z
        assert np.allclose(upper[:, 1], -d - lower[:, 1], atol=1e-9 * d)
        assert np.allclose(upper[:, 2], -lower[:, 2], atol=1e-9)


# --------------------------------------------------------------------------- rung L2
def _mirrored_half_chevron(cell, levels):
    """The quarter mesh plus its mirror image across z = h/2, nodes on the plane merged."""
    from skfem import MeshTri

    mesh, x_cut = L2.refined_quarter_mesh(cell, L2.MeshOptions(levels=levels))
    p, t = mesh.p, mesh.t
    h = cell.h_mm
    on_plane = np.abs(p[1] - 0.5 * h) < 1e-9 * h
    mirror_index = np.empty(p.shape[1], dtype=int)
    off = np.flatnonzero(~on_plane)
    mirror_index[on_plane] = np.flatnonzero(on_plane)
    mirror_index[off] = p.shape[1] + np.arange(off.size)
    p_all = np.hstack([p, np.vstack([p[0, off], h - p[1, off]])])
    t_mirror = mirror_index[t][[0, 2, 1]]  # reflection flips orientation
    return MeshTri(p_all, np.hstack([t, t_mirror])), x_cut


class HalfChevronContinuum:
    """Right half of the profile (both pads, both walls), no symmetry across z = h/2."""

    def __init__(self, cell, levels):
        from skfem import Basis, ElementTriP2, ElementVector

        mesh, x_cut = _mirrored_half_chevron(cell, levels)
        self.basis = Basis(mesh, ElementVector(ElementTriP2()), intorder=4)
        self.mu, self.lam = lame_3d(MAT.youngs_modulus_MPa, MAT.poisson_ratio)
        xy = self.basis.doflocs
        tol = 1e-9 * cell.h_mm
        is_x = np.zeros(self.basis.N, bool)
        is_x[self.basis.nodal_dofs[0]] = True
        is_x[self.basis.facet_dofs[0]] = True
        bottom = np.abs(xy[1]) < tol
        top = np.abs(xy[1] - cell.h_mm) < tol
        cut = np.abs(xy[0] - x_cut) < tol
        self.top_z = np.flatnonzero(top & ~is_x)
        self.zero = np.flatnonzero(bottom | (top & is_x) | (cut & is_x))
        self.pinned = np.union1d(self.zero, self.top_z)
        self.free = np.setdiff1d(np.arange(self.basis.N), self.pinned)
        self.depth_factor = 2.0 * cell.b_mm  # two chevrons of a web b = D wide
        self.is_x = is_x

    def assemble(self, u, need_K=True):
        return L2.ContactProblem.assemble(self, u, need_K)  # the L2 kernel, on this mesh

    def linear(self, d):
        """Small-strain solution for a top-plate motion d: one solve with the tangent at rest."""
        from scipy.sparse.linalg import spsolve

        _, K = self.assemble(np.zeros(self.basis.N))
        u = np.zeros(self.basis.N)
        u[self.top_z] = -d
        u[self.free] = spsolve(K[self.free][:, self.free].tocsc(), -K[self.free][:, self.pinned] @ u[self.pinned])
        return u, -(K @ u)[self.top_z].sum() * self.depth_factor

    def solve(self, u, d, iterations=30):
        from scipy.sparse.linalg import spsolve

        u = u.copy()
        jump = np.zeros(self.basis.N)
        jump[self.top_z] = -d - u[self.top_z]
        for _ in range(iterations):
            r, K = self.assemble(u)
            rhs = -r[self.free] - K[self.free][:, self.pinned] @ jump[self.pinned]
            if not jump.any() and np.linalg.norm(rhs) < 1e-9 * max(abs(r[self.top_z].sum()), 1e-12):
                return u, -r[self.top_z].sum() * self.depth_factor
            u[self.free] += spsolve(K[self.free][:, self.free].tocsc(), rhs)
            u[self.pinned] += jump[self.pinned]
            jump[:] = 0.0
        raise AssertionError("half-chevron Newton did not converge")


@pytest.mark.slow
@pytest.mark.parametrize("cell", CELLS, ids=str)
def test_continuum_quarter_equals_half_chevron_small_strain(cell):
    half = HalfChevronContinuum(cell, L2.DEFAULT_LEVELS)
    d = 1.0
    u, F = half.linear(d)
    assert F / d == pytest.approx(L2.linear_stiffness_N_per_mm(cell, MAT), rel=1e-6)
    # the solution is the mirror image of itself: u_x(x, h - z) = u_x, u_z(x, h - z) = -d - u_z
    xy = half.basis.doflocs
    key = np.round(np.vstack([xy[0], np.minimum(xy[1], cell.h_mm - xy[1]), half.is_x]) * 1e7).astype(np.int64)
    _, pair = np.unique(key, axis=1, return_inverse=True)
    pair = pair.ravel()
    pairs = [np.flatnonzero(pair == g) for g in np.unique(pair)]
    pairs = [m for m in pairs if m.size == 2]
    assert len(pairs) > 0.4 * half.basis.N  # every dof off the plane has its mirror twin
    for a, b in pairs:
        if half.is_x[a]:
            assert u[a] == pytest.approx(u[b], abs=1e-8 * d)
        else:
            assert u[a] + u[b] == pytest.approx(-d, abs=1e-8 * d)


@pytest.mark.slow
@pytest.mark.parametrize("cell", CELLS[:2], ids=str)
def test_continuum_quarter_equals_half_chevron_large_strain(cell):
    # the nonlinear path runs on the unrefined mesh (solve_continuum scales its forces by
    # mesh_scale); compare on that mesh, up to half the stroke and before any face touches
    res = L2.solve_continuum(cell, MAT)
    half = HalfChevronContinuum(cell, levels=0)
    u = np.zeros(half.basis.N)
    d_prev = 0.0
    checked = 0
    for d, F, n_contact in zip(res.displacement_mm[1:], res.force_N[1:], res.contact_points[1:]):
        if d > 0.5 * res.d_contact_mm or n_contact:
            break
        for dd in np.linspace(d_prev, d, 3)[1:]:
            u, F_half = half.solve(u, dd)
        d_prev = d
        assert F_half * res.mesh_scale == pytest.approx(F, rel=1e-6)
        checked += 1
    assert checked >= 2, res.displacement_mm


@pytest.mark.slow
def test_continuum_pad_cut_is_far_enough_from_the_wall(monkeypatch):
    # the quarter model keeps PAD_LENGTH_IN_T wall thicknesses of pad and holds the cut in x;
    # the bonded pad's stresses decay within a few t (Saint-Venant), so keeping the whole pad
    # (cut on the x = 0 mirror plane, where u_x = 0 is exact) must change k by < 1 %
    cell = HexCell(35, 0.8, 3.0)
    k_cut = L2.linear_stiffness_N_per_mm(cell, MAT)
    monkeypatch.setattr(L2, "PAD_LENGTH_IN_T", 1e6)
    k_whole = L2.linear_stiffness_N_per_mm(cell, MAT)
    assert k_cut == pytest.approx(k_whole, rel=1e-2)
    assert math.isfinite(k_whole)
