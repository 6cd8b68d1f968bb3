"""The trilinear kernels of the one-chip tables (:mod:`~mst_cli.estimation.inverse_table`): a
cell's field and its Jacobian at cell coordinates, the ridged Gauss-Newton step on it (a 3 x 3
solve by Cramer's rule, as the C header does), and an estimate and its Jacobian in the table's
coordinates or the shear table's forces (their Cramer-Rao 1-sigma is the one bound's,
:func:`~mst_cli.model.load_bound.crb_sigma`). Batched over points; no I/O."""

from __future__ import annotations

import numpy as np

RIDGE = 1e-9  # the Gauss-Newton system's ridge, relative to its trace (a flat direction stays put)


def bilinear(X: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """X (P, 2, 2, 3) at (u, v) (P, 1) each."""
    x0 = X[:, 0, 0] + (X[:, 0, 1] - X[:, 0, 0]) * v
    x1 = X[:, 1, 0] + (X[:, 1, 1] - X[:, 1, 0]) * v
    return x0 + (x1 - x0) * u


def trilinear(C: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The trilinear field (P, 3) of cells with corners C (P, 2, 2, 2, 3) at cell coordinates t
    (P, 3), and its Jacobian (P, 3, 3) in those coordinates."""
    t0, t1, t2 = t[:, 0:1], t[:, 1:2], t[:, 2:3]
    lower, upper = bilinear(C[:, 0], t1, t2), bilinear(C[:, 1], t1, t2)
    d1 = bilinear(C[:, :, 1] - C[:, :, 0], t0, t2)
    d2 = bilinear(C[:, :, :, 1] - C[:, :, :, 0], t0, t1)
    return lower + (upper - lower) * t0, np.stack([upper - lower, d1, d2], axis=2)


def solve3(A: np.ndarray, g: np.ndarray) -> np.ndarray:
    """x of A x = g for many symmetric 3 x 3 systems (P, 3, 3) by Cramer's rule (as the C header
    does); inf or NaN where A is singular."""
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 1], A[:, 1, 2], A[:, 2, 2]
    c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
    c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * c00 + b * c01 + c * c02
    g0, g1, g2 = g[:, 0], g[:, 1], g[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        return (
            np.stack(
                [c00 * g0 + c01 * g1 + c02 * g2, c01 * g0 + c11 * g1 + c12 * g2, c02 * g0 + c12 * g1 + c22 * g2], axis=1
            )
            / det[:, None]
        )


def normal_step(J: np.ndarray, r: np.ndarray, held: np.ndarray) -> np.ndarray:
    """The ridged Gauss-Newton step of J dt = r, with the ``held`` coordinates' columns left out
    (0 where the system is singular)."""
    Jh = J * ~held[:, None, :]
    A = np.einsum("pki,pkj->pij", Jh, Jh)
    A += (RIDGE * (A[:, 0, 0] + A[:, 1, 1] + A[:, 2, 2]) + 1e-30)[:, None, None] * np.eye(3)
    dt = solve3(A, np.einsum("pki,pk->pi", Jh, r))
    return np.where(np.isfinite(dt), dt, 0.0)  # 0 where singular (as the C header does)


def to_output(kind: str, p: np.ndarray, J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The roots p (K, 3) and field Jacobians J (K, 3, 3) in the estimate's coordinates: the
    offset table's are its own; the shear table's (F, u, v) become (Fz, Fx, Fy) = (F, u F, v F),
    dB/dq = dB/dp dp/dq with dp/dq the inverse of [[1, 0, 0], [u, F, 0], [v, 0, F]]."""
    if kind != "shear":
        return p, J
    F = np.maximum(p[:, 0], 1e-12)  # a press of no force has no shear (its ratio is any)
    q = np.column_stack([p[:, 0], p[:, 1] * p[:, 0], p[:, 2] * p[:, 0]])
    Jq = np.empty_like(J)
    Jq[:, :, 1], Jq[:, :, 2] = J[:, :, 1] / F[:, None], J[:, :, 2] / F[:, None]
    Jq[:, :, 0] = J[:, :, 0] - (p[:, 1] / F)[:, None] * J[:, :, 1] - (p[:, 2] / F)[:, None] * J[:, :, 2]
    return q, Jq
