"""The 3D kernel of the plane-strain check (tools/continuum_3d.py, issue 20 part 4):
a patch test, the tangent against central differences, and the two limits of a thin slice
(free faces: plane stress; held faces: plane strain, the 2D rung)."""

import sys
from pathlib import Path

import numpy as np
import pytest

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics.continuum.assembly import assembler_of, lame_3d

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import continuum_3d as C3

pytestmark = pytest.mark.slow

MAT = Material()
E, NU = MAT.youngs_modulus_MPa, MAT.poisson_ratio
MU, LAM = lame_3d(E, NU)
MID = HexCell(33, 1.0, 2.8)


def _block(a=2.0, b=1.5, H=1.0):
    """A distorted block [0, a] x [0, b] x [0, H] (x, y, z): uneven spacing in x and z, graded
    layers in y, the prisms split as in the benchmark's mesh."""
    from skfem import Basis, ElementTetP2, ElementVector, MeshTet, MeshTri

    tri = MeshTri.init_tensor(np.array([0.0, 0.3, 1.1, a]), np.array([0.0, 0.45, H]))
    pts, tet = C3.extrude(tri.p, tri.t, C3.graded_depth(b, 3, 0.2))
    basis = Basis(MeshTet(pts, tet), ElementVector(ElementTetP2()), intorder=4)
    comp = np.zeros(basis.N, int)
    for c in range(3):
        comp[basis.nodal_dofs[c]] = c
        comp[basis.edge_dofs[c]] = c
    return basis, comp


def _solve_block(basis, comp, asm, stretch, H=1.0):
    """Uniaxial compression between frictionless plates (u_z = 0 on z = 0, u_z = (stretch - 1) H on
    top), the symmetry planes x = 0 and y = 0 holding u_x and u_y, the sides free: Newton."""
    X = basis.doflocs
    top = (comp == 2) & np.isclose(X[2], H)
    fixed = (
        ((comp == 2) & np.isclose(X[2], 0.0))
        | ((comp == 0) & np.isclose(X[0], 0.0))
        | ((comp == 1) & np.isclose(X[1], 0.0))
    )
    pinned = np.flatnonzero(fixed | top)
    free = np.setdiff1d(np.arange(basis.N), pinned)
    u = np.where(comp == 2, (stretch - 1.0) * X[2], 0.0)  # start: the plates' motion spread through z
    for _ in range(30):
        r, state = asm.residual(u, MU, LAM)
        if np.linalg.norm(r[free]) < 1e-12 * max(1.0, abs(r[top]).sum()):
            break
        K = asm.tangent(state, MU, LAM).tocsc()
        from scipy.sparse.linalg import spsolve

        u[free] -= spsolve(K[free][:, free], r[free])
    return u, r, top


def test_patch_uniaxial_block_reproduces_E_d_over_H_and_finite_strain_neo_hooke():
    a, b, H = 2.0, 1.5, 1.0
    basis, comp = _block(a, b, H)
    asm = C3.Assembler(basis)
    # small strain: F = E a b d / H, lateral strain nu d / H, exactly (the field is linear)
    d = 1e-7
    u, r, top = _solve_block(basis, comp, asm, 1.0 - d / H)
    force = -r[top].sum()
    assert force == pytest.approx(E * a * b * d / H, rel=1e-6)
    X = basis.doflocs
    ux = comp == 0
    assert np.allclose(u[ux], NU * d / H * X[0][ux], rtol=0, atol=1e-6 * d)
    # 30 % compression: the homogeneous Neo-Hooke state, lambda_1 = lambda_2 from P_11 = 0
    lam3 = 0.7
    lo, hi = 1.0, 2.0
    for _ in range(200):
        l1 = 0.5 * (lo + hi)
        P11 = MU * l1 + (LAM * np.log(l1 * l1 * lam3) - MU) / l1
        lo, hi = (l1, hi) if P11 < 0 else (lo, l1)
    P33 = MU * lam3 + (LAM * np.log(l1 * l1 * lam3) - MU) / lam3
    u, r, top = _solve_block(basis, comp, asm, lam3)
    assert -r[top].sum() == pytest.approx(-P33 * a * b, rel=1e-9)
    assert np.allclose(u[ux], (l1 - 1.0) * X[0][ux], rtol=0, atol=1e-9)


def test_material_at_rest_is_3d_hooke_and_tangent_matches_central_differences_at_large_strain():
    # at rest: C_1111 = E (1 - nu) / ((1 + nu)(1 - 2 nu)), C_1122 = E nu / (...), C_1212 = E / (2 (1 + nu))
    eps = 1e-7
    I = np.eye(3)[:, :, None]
    C = np.zeros((3, 3, 3, 3))
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3, 1))
            dF[k, l] = eps
            C[:, :, k, l] = (C3.kinematics(I + dF, MU, LAM)[0] - C3.kinematics(I - dF, MU, LAM)[0])[..., 0] / (2 * eps)
    den = (1 + NU) * (1 - 2 * NU)
    assert C[0, 0, 0, 0] == pytest.approx(E * (1 - NU) / den, rel=1e-6)
    assert C[2, 2, 1, 1] == pytest.approx(E * NU / den, rel=1e-6)
    assert C[0, 2, 0, 2] == pytest.approx(E / (2 * (1 + NU)), rel=1e-6)
    # the assembled tangent against central differences of the residual, on a slab of the
    # cell's mesh deformed to large strain (compression, shear and a twist through the depth)
    prob = C3.Problem3D(MID, MAT, C3.graded_depth(2.0, 2, 0.5))
    asm = assembler_of(prob.basis)
    X = prob.basis.doflocs
    comp = np.zeros(prob.basis.N, int)
    for c in range(3):
        comp[prob.basis.nodal_dofs[c]] = c
        comp[prob.basis.edge_dofs[c]] = c
    x, y, z = X[0], X[1], X[2]
    u = np.where(comp == 0, 0.15 * z + 0.05 * y * z, np.where(comp == 1, 0.1 * x * z, -0.25 * z + 0.03 * x * x))
    _, state = asm.residual(u, prob.mu, prob.lam)
    K = asm.tangent(state, prob.mu, prob.lam)
    v = np.random.default_rng(3).standard_normal(prob.basis.N) * 1e-2
    h = 1e-6
    fd = (asm.residual(u + h * v, prob.mu, prob.lam)[0] - asm.residual(u - h * v, prob.mu, prob.lam)[0]) / (2 * h)
    assert np.linalg.norm(K @ v - fd) <= 1e-6 * np.linalg.norm(fd)
    # the tangent is symmetric (hyperelastic)
    assert abs(K - K.T).max() <= 1e-10 * abs(K).max()


def _k_per_mm(prob, depth):
    """Small-load tip stiffness of the modelled slab per mm of its depth (N/mm/mm)."""
    return L2.linear_k(prob) / prob.depth_factor / depth


def test_thin_slice_with_held_faces_is_the_2d_plane_strain_rung():
    # u_y = 0 on both faces: the continuum answer is plane strain at any depth. The tetrahedra's
    # space holds the extruded P2 field but is richer, so the 3D k is lower by a discretisation
    # term that vanishes like the slice's depth squared; at s = t / 1000 it is below 1e-5.
    p2 = L2.ContactProblem(MID, MAT, L2.MeshOptions(2, 8, 0))
    k2 = L2.linear_k(p2) / p2.depth_factor
    gaps = []
    for s in (1e-2, 1e-3):
        prob = C3.Problem3D(MID, MAT, [0.0, s], y_sym=True, y_held_far=True)
        gaps.append(1.0 - _k_per_mm(prob, s) / k2)
    assert 0.0 <= gaps[1] < 1e-5
    assert gaps[1] < gaps[0] / 30.0


def test_thin_slice_with_free_faces_tends_to_plane_stress():
    # both faces free, s = t / 100: generalised plane stress. The 3D elements must carry the
    # thickness strain eps_yy as a continuous field where plane stress has it discontinuous
    # (it follows the in-plane strains), so the slice is stiffer by a term of order of the
    # in-plane element size: refined in the plane, it goes to the plane-stress k (the 2D rung
    # with E* = E (1 + 2 nu) / (1 + nu)^2, nu* = nu / (1 + nu)).
    s = 0.01
    over = []
    for n_thick, n_length in ((3, 12), (6, 24)):
        ps = L2.ContactProblem(MID, C3.plane_stress_material(MAT), L2.MeshOptions(n_thick, n_length, 0))
        k_ps = L2.linear_k(ps) / ps.depth_factor
        k3 = _k_per_mm(C3.Problem3D(MID, MAT, [0.0, s], n_thick, n_length, y_sym=False), s)
        over.append(k3 / k_ps - 1.0)
    assert 0.0 < over[1] < over[0] < 0.04
    # error ~ element size: the Richardson extrapolation lands on plane stress
    assert abs(2.0 * over[1] - over[0]) < 3e-3
    # and the slice is far from plane strain (about 20 % softer here)
    pe = L2.ContactProblem(MID, MAT, L2.MeshOptions(6, 24, 0))
    assert k3 < 0.9 * L2.linear_k(pe) / pe.depth_factor
