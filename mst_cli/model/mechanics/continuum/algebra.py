"""The path's linear algebra: a tangent's free block in banded form and its solve, and the
contact active set's update inside Newton."""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgbsv, dpbsv
from scipy.sparse import csc_matrix, csr_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mst_cli.model.mechanics.continuum.assembly import Assembler, PlatePenalty

# Newton's active set: after this many changes of the set within one solve, a contact point
# released once and back in contact stays held (:meth:`ContactProblem._newton`)
SET_CHANGES_BEFORE_HOLDING = 4


class FreeBlock:
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

    def __init__(self, asm: Assembler | PlatePenalty, free: np.ndarray):
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


class ActiveSet:
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
