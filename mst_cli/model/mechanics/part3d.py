"""The 3D linear check: a body of tetrahedra held at its mount and pressed over a strip
(docs/design.md section 4.8).

Linear small-strain elasticity on P1 or P2 tetrahedra (scikit-fem), a modulus and a Poisson's
ratio per tetrahedron. Dirichlet: every node of the held face fixed. Load: a uniform pressure
over the strip |x - x_c| <= c/2 of the contact face (the whole depth), scaled so that its
resultant is exactly 1 N: a facet that the strip's edge crosses is weighted by its quadrature
points inside, so the strip's width is resolved to a facet and the force is exact. The magnet's
motion is the least-squares rigid motion (translation and small rotation) of a set of nodes
(the pocket's floor under a resting magnet, or the magnet's own nodes when it is bonded); the
field change per newton at the chip is that motion applied to the magnet in the exact cylinder
field model (:func:`~mst_cli.model.magnet_field.cylinder_pose_B_T`), by a central difference.
Everything is per newton: the solve is linear.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.magnet_field import cylinder_pose_B_T

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix
    from skfem import Basis

FACE_TOL_MM = 1e-6  # a node or facet on a plane face lies within this of it
FIELD_STEP_MM = 1e-3  # the central difference's largest displacement (the field is smooth on this scale)


@dataclass(frozen=True)
class RigidMotion:
    """A rigid motion per newton: translation (mm/N, x y z) and rotation vector (rad/N) about
    ``centre_mm``."""

    translation_mm_per_N: np.ndarray
    rotation_rad_per_N: np.ndarray
    centre_mm: np.ndarray


@dataclass(frozen=True)
class Solution:
    """The displacement per newton at every dof, the basis it lives on, and the cost."""

    u_mm_per_N: np.ndarray
    basis: Basis
    dofs: int
    seconds: float


def lame_MPa(E_MPa: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lambda, mu) per element, MPa."""
    E, nu = np.asarray(E_MPa, dtype=float), np.asarray(nu, dtype=float)
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def vector_basis(points_mm: np.ndarray, tets: np.ndarray, order: int) -> Basis:
    """scikit-fem's vector Basis on P1 or P2 tetrahedra."""
    from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet  # deferred: heavy

    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, not {order!r}")
    mesh = MeshTet(np.ascontiguousarray(points_mm.T), np.ascontiguousarray(tets.T))
    # the stiffness integrand is a product of two gradients (degree 2 (order - 1)) times a constant
    # per element: a rule of that degree is exact, and for P2 it is 4 points where the default has 15
    return Basis(
        mesh, ElementVector(ElementTetP2() if order == 2 else ElementTetP1()), intorder=max(1, 2 * (order - 1))
    )


def stiffness(basis, E_MPa: np.ndarray, nu: np.ndarray) -> csr_matrix:
    """The elasticity matrix: 2 mu eps(u):eps(v) + lambda div u div v, constant per element."""
    from skfem import BilinearForm, asm  # deferred: heavy
    from skfem.helpers import ddot, sym_grad, trace

    lam_e, mu_e = lame_MPa(E_MPa, nu)
    lam, mu = lam_e[:, None], mu_e[:, None]

    @BilinearForm
    def elasticity(u, v, w):
        eu, ev = sym_grad(u), sym_grad(v)
        return 2.0 * mu * ddot(eu, ev) + lam * trace(eu) * trace(ev)

    return asm(elasticity, basis)


def plane_facets(basis, axis: int, value: float) -> np.ndarray:
    """The boundary facets lying on the plane x_axis = value."""
    return basis.mesh.facets_satisfying(lambda x: np.abs(x[axis] - value) < FACE_TOL_MM, boundaries_only=True)


def strip_load(basis, top_z_mm: float, centre_x_mm: float, width_mm: float, direction: int = 2) -> np.ndarray:
    """The load vector of a uniform traction over |x - centre| <= width/2 of the face z = top,
    along -z (``direction`` 2) or +x (0), its resultant exactly 1 N."""
    from skfem import FacetBasis, LinearForm, asm  # deferred: heavy

    fb = FacetBasis(basis.mesh, basis.elem, facets=plane_facets(basis, 2, top_z_mm))
    sign = -1.0 if direction == 2 else 1.0

    @LinearForm
    def traction(v, w):
        inside = np.abs(w.x[0] - centre_x_mm) <= 0.5 * width_mm
        return sign * inside * v[direction]

    f = asm(traction, fb)
    total = abs(f.sum())
    if not total > 0.0:
        raise ValueError(
            f"no facet of the face z = {top_z_mm} mm lies in the strip |x - {centre_x_mm}| <= {width_mm}/2"
        )
    return f / total


def solve_held(basis, K, f: np.ndarray, held_dofs: np.ndarray) -> np.ndarray:
    """K u = f with u = 0 on ``held_dofs``: a sparse direct solve (SuperLU)."""
    from skfem import condense, solve  # deferred: heavy

    return solve(*condense(K, f, D=held_dofs))


def press(
    points_mm: np.ndarray,
    tets: np.ndarray,
    E_MPa: np.ndarray,
    nu: np.ndarray,
    *,
    held_z_mm: float,
    top_z_mm: float,
    centre_x_mm: float = 0.0,
    width_mm: float = 6.0,
    order: int = 2,
) -> Solution:
    """The displacement per newton of the body held (every component) on its face z = held and
    pressed down over the strip on its face z = top (module docstring)."""
    t0 = time.perf_counter()
    basis = vector_basis(points_mm, tets, order)
    K = stiffness(basis, E_MPa, nu)
    f = strip_load(basis, top_z_mm, centre_x_mm, width_mm)
    held = basis.get_dofs(plane_facets(basis, 2, held_z_mm)).all()
    if held.size == 0:
        raise ValueError(f"no facet of the body lies on its held face z = {held_z_mm} mm")
    u = solve_held(basis, K, f, held)
    return Solution(u, basis, int(basis.N), time.perf_counter() - t0)


def node_displacements(solution: Solution, nodes: np.ndarray) -> np.ndarray:
    """(k, 3) displacement per newton of mesh vertices ``nodes``."""
    return solution.u_mm_per_N[solution.basis.nodal_dofs[:, nodes]].T


def rigid_fit(points_mm: np.ndarray, u: np.ndarray) -> RigidMotion:
    """The least-squares rigid motion u ~ U + omega x (p - c) of points ``points_mm`` (k, 3)
    moved by ``u`` (k, 3), about their centroid c (needs three points not on a line)."""
    c = points_mm.mean(axis=0)
    d = points_mm - c
    # u_i = U + omega x d_i = U - [d_i]x omega: with sum d_i = 0, U and omega decouple
    U = u.mean(axis=0)
    cross = np.zeros((len(d), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2] = -d[:, 2], d[:, 1]
    cross[:, 1, 0], cross[:, 1, 2] = d[:, 2], -d[:, 0]
    cross[:, 2, 0], cross[:, 2, 1] = -d[:, 1], d[:, 0]
    A = -cross.reshape(-1, 3)  # omega x d = -[d]x omega
    omega, *_ = np.linalg.lstsq(A, (u - U).reshape(-1), rcond=None)
    return RigidMotion(U, omega, c)


def field_change_uT_per_N(
    motion: RigidMotion, magnet_centre_mm, chip_mm, diameter_mm: float, thickness_mm: float, remanence_T: float
) -> np.ndarray:
    """dB/dF (uT/N, x y z) at the chip when the magnet (centre ``magnet_centre_mm``, upright,
    magnetised +z) moves by ``motion`` per newton: the exact cylinder field at the moved pose,
    a central difference scaled so that no point of the magnet moves more than FIELD_STEP_MM."""
    centre = np.asarray(magnet_centre_mm, dtype=float)
    lever = np.linalg.norm(motion.centre_mm - centre) + 0.5 * np.hypot(diameter_mm, thickness_mm)
    reach = np.linalg.norm(motion.translation_mm_per_N) + np.linalg.norm(motion.rotation_rad_per_N) * lever
    s = FIELD_STEP_MM / reach if reach > 0.0 else 1.0

    def B(scale: float) -> np.ndarray:
        omega = scale * motion.rotation_rad_per_N
        # the magnet's centre moves with the rigid motion about the fitted points' centroid
        moved = centre + scale * motion.translation_mm_per_N + np.cross(omega, centre - motion.centre_mm)
        r = np.asarray(chip_mm, dtype=float)[None, :] - moved[None, :]
        return cylinder_pose_B_T(r, diameter_mm, thickness_mm, remanence_T, omega[None, :])[0]

    return 1e6 * (B(s) - B(-s)) / (2.0 * s)
