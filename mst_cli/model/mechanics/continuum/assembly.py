"""The Neo-Hookean kinematics and the vectorised assembler of its residual and tangent on a P2
basis, the plate's contact as a penalty, and the principal stretches of a state."""

from __future__ import annotations

import weakref

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix


def lame_3d(E_MPa: float, nu: float) -> tuple[float, float]:
    """The 3D Lame constants (mu, lambda) of the small-strain E and nu."""
    mu = E_MPa / (2.0 * (1.0 + nu))
    lam = E_MPa * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return mu, lam


def kinematics(Fm: np.ndarray, mu: float, lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plane-strain Neo-Hookean at the in-plane F (2, 2, ...), lambda_3 = 1: the first Piola
    stress P = mu F + (lam ln J - mu) F^-T and the pieces of its tangent (F^-T, ln J)."""
    J = Fm[0, 0] * Fm[1, 1] - Fm[0, 1] * Fm[1, 0]
    Finv_T = np.array([[Fm[1, 1], -Fm[1, 0]], [-Fm[0, 1], Fm[0, 0]]]) / J
    lnJ = np.log(J)
    P = mu * Fm + (lam * lnJ - mu) * Finv_T
    return P, Finv_T, lnJ


def csr_scatter(dofs: np.ndarray, n_dofs: int) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """The CSR pattern of a stiffness matrix over elements with ``dofs`` (n_el, n_loc): its
    (indices, indptr, nnz), and where element entry (e, i, j) goes in its data (the rank of its
    key row * N + col among the pattern's keys). scipy merges the duplicate entries in C."""
    n_el, n_loc = dofs.shape
    rows = np.broadcast_to(dofs[:, :, None], (n_el, n_loc, n_loc)).ravel()
    cols = np.broadcast_to(dofs[:, None, :], (n_el, n_loc, n_loc)).ravel()
    pattern = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n_dofs, n_dofs)).tocsr()
    pattern.sort_indices()
    keys = np.repeat(np.arange(n_dofs, dtype=np.int64), np.diff(pattern.indptr)) * n_dofs + pattern.indices
    scatter = np.searchsorted(keys, rows.astype(np.int64) * n_dofs + cols)
    return pattern.indices, pattern.indptr, pattern.nnz, scatter


class Assembler:
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
        self.indices, self.indptr, self.nnz, self.scatter = csr_scatter(self.dofs, self.N)

    def residual(self, u, mu, lam) -> tuple[np.ndarray, tuple]:
        """r = int P : grad v; also returns what the tangent at u needs (F^-T, ln J)."""
        grad_u = np.einsum("eqki,ei->keq", self.B, u[self.dofs])  # (4, n_el, n_q)
        Fm = grad_u.reshape(2, 2, *grad_u.shape[1:]) + np.eye(2)[:, :, None, None]
        if np.any(Fm[0, 0] * Fm[1, 1] - Fm[0, 1] * Fm[1, 0] <= 0):
            raise FloatingPointError("inverted element")
        P, FiT, lnJ = kinematics(Fm, mu, lam)
        if not np.all(np.isfinite(P)):
            raise FloatingPointError("inverted element")
        n_el, n_q = lnJ.shape
        Pk = P.reshape(4, n_el, n_q).transpose(1, 2, 0).reshape(n_el, 4 * n_q)
        r_el = np.einsum("eik,ek->ei", self.BwT, Pk)
        r = np.bincount(self.dofs.ravel(), weights=r_el.ravel(), minlength=self.N)
        return r, (FiT, lnJ)

    def tangent(self, state, mu, lam) -> csr_matrix:
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


class PlatePenalty:
    """An assembler with the outer wall face's contact with the plate as a penalty.

    The plate pushes a point of the outer face that has gone below it (u_z < -z) back with a
    force kappa (overlap), kappa = ``per_mm`` mu L (L the point's share of the face's length,
    mm): a pressure mu ``per_mm`` per mm of overlap. Unlike the active set, the contact force
    is continuous in u, so Newton does not churn where many small elements touch one after the
    other (the root-graded meshes of docs/design.md section 4, "Steep walls"); the answer is
    the active set's as ``per_mm`` grows (tests/test_continuum.py). Only where the plate stays
    put (the centred problem).
    """

    def __init__(self, base: Assembler, dofs: np.ndarray, obstacle_mm: np.ndarray, kappa: np.ndarray):
        self.base, self.dofs, self.obstacle_mm, self.kappa = base, dofs, obstacle_mm, kappa
        self.N, self.nnz, self.indices, self.indptr = base.N, base.nnz, base.indices, base.indptr
        # where each dof's diagonal entry sits in the CSR pattern
        starts = base.indptr[dofs]
        self.diag_pos = np.array(
            [a + np.searchsorted(base.indices[a : base.indptr[i + 1]], i) for a, i in zip(starts, dofs)]
        )

    def overlap_mm(self, u: np.ndarray) -> np.ndarray:
        return np.maximum(self.obstacle_mm - u[self.dofs], 0.0)

    def residual(self, u, mu, lam) -> tuple[np.ndarray, tuple]:
        r, state = self.base.residual(u, mu, lam)
        pen = self.overlap_mm(u)
        r[self.dofs] -= self.kappa * pen  # the plate pushes up
        return r, (state, pen > 0.0)

    def tangent(self, state, mu, lam) -> csr_matrix:
        inner, touching = state
        K = self.base.tangent(inner, mu, lam)
        K.data[self.diag_pos[touching]] += self.kappa[touching]
        return K


_ASSEMBLERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def assembler_of(basis) -> Assembler | PlatePenalty:
    """The assembler of a basis, built on first use (kept as long as the basis lives)."""
    asm = _ASSEMBLERS.get(basis)
    if asm is None:
        asm = _ASSEMBLERS[basis] = Assembler(basis)
    return asm


def set_assembler(basis, asm) -> None:
    """Make ``asm`` the assembler of ``basis`` (a penalty's, or another dimension's: tools/continuum_3d.py)."""
    _ASSEMBLERS[basis] = asm


def smallest_stretches(prob, u: np.ndarray) -> np.ndarray:
    """The smallest principal stretch at every quadrature point (n_el, n_q) of the state ``u``."""
    asm = assembler_of(prob.basis)
    asm = asm.base if isinstance(asm, PlatePenalty) else asm  # the elastic body's gradients
    grad = np.einsum("eqki,ei->keq", asm.B, u[asm.dofs])
    Fm = grad.reshape(2, 2, *grad.shape[1:]) + np.eye(2)[:, :, None, None]
    c11, c22 = Fm[0, 0] ** 2 + Fm[1, 0] ** 2, Fm[0, 1] ** 2 + Fm[1, 1] ** 2  # C = F^T F
    c12 = Fm[0, 0] * Fm[0, 1] + Fm[1, 0] * Fm[1, 1]
    return np.sqrt(0.5 * (c11 + c22) - np.sqrt(0.25 * (c11 - c22) ** 2 + c12**2))


def smallest_stretch(prob, u: np.ndarray) -> float:
    """The smallest principal stretch anywhere in the state ``u``: where it falls below
    CREASE_ONSET_STRETCH (:mod:`~mst_cli.model.material`), a compressed free face creases."""
    return float(smallest_stretches(prob, u).min())
