"""The exact field of an axially magnetised cylinder, tabulated once over (rho, z) in its own frame:
a cheap field and its gradient for fits that need only a guess (the two-chip reader's table
stage, :mod:`mst_cli.estimation.two_chip_table`).

The cylinder's field is axisymmetric: in its own frame B = (g(rho, z) x, g(rho, z) y, B_z(rho, z))
with g = B_rho / rho (even in rho, finite on the axis, where div B = 0 makes it -dB_z/dz / 2).
Both are tabulated from magpylib's exact field on a uniform (rho, z) grid (mirrored past the axis
so the spline through them is even there) and read as bicubic Hermite patches whose node slopes
are those of scipy's interpolating spline: values and first derivatives continuous, the error
falling as the step's fourth power (tests/test_cylinder_table.py checks it against magpylib).
A turned magnet (rotation vector phi, its matrix R) gives B = R B_own(R^T q) at the point q from
its centre; a turn by a small extra rotation vector delta moves it by the left Jacobian J_l(phi)
delta, so dB/dphi = (-[B]x + R G R^T [q]x) J_l(phi), G the own frame's gradient.

Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.model import magnet_field as fld

# the Hermite patch's coefficients from (f, f') at its two ends: p(t) = [1 t t^2 t^3] HERMITE [f0 f1 f0' f1']
HERMITE = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [-3.0, 3.0, -2.0, -1.0], [2.0, -2.0, 1.0, 1.0]])
AXIS_RHO_MM = 1e-4  # g on the axis: B_rho / rho this close to it (B_rho is linear in rho there)


def skew(v: np.ndarray) -> np.ndarray:
    """(3, 3, m) the cross-product matrices [v]x of vectors ``v`` (3, m) (components first: numpy
    is fast along the rows, slow on many 3 x 3 matrices)."""
    zero = np.zeros_like(v[0])
    return np.array([[zero, -v[2], v[1]], [v[2], zero, -v[0]], [-v[1], v[0], zero]])


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3, m) the products of the matrices ``a`` and ``b`` (3, 3, m)."""
    return np.einsum("ijm,jkm->ikm", a, b)


def rotation_and_left_jacobian(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R, J_l), each (3, 3, m), of rotation vectors ``phi`` (3, m) (Rodrigues' formula; the
    series near zero)."""
    t2 = np.sum(phi * phi, axis=0)
    t = np.sqrt(t2)
    small = t < 1e-4
    ts = np.where(small, 1.0, t)
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(ts) / ts)
    b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(ts)) / ts**2)
    c = np.where(small, 1.0 / 6.0 - t2 / 120.0, (ts - np.sin(ts)) / ts**3)
    K = skew(phi)
    K2 = matmul(K, K)
    eye = np.eye(3)[:, :, None]
    return eye + a * K + b * K2, eye + b * K + c * K2


@dataclass(frozen=True)
class CylinderFieldTable:
    """(g, B_z) in T/mm and T as bicubic patches over the cells of a uniform grid from
    (rho0_mm, z0_mm) by (step_rho_mm, step_z_mm); ``coeffs`` (cells along rho, cells along z,
    2, 16) (i along rho, j along z: 4 i + j). Points past the grid are read from its end cells (extrapolated)."""

    rho0_mm: float
    z0_mm: float
    step_rho_mm: float
    step_z_mm: float
    coeffs: np.ndarray

    @classmethod
    def build(
        cls,
        diameter_mm: float,
        thickness_mm: float,
        remanence_T: float,
        rho_max_mm: float,
        z_range_mm: tuple[float, float],
        step_mm: float,
    ) -> CylinderFieldTable:
        """The table of the magnet over rho in [0, ``rho_max_mm``] and z in ``z_range_mm`` (from
        its centre, along its axis), nodes about ``step_mm`` apart."""
        from scipy.interpolate import RectBivariateSpline  # deferred: the exact model's libraries

        n_rho = int(np.ceil(rho_max_mm / step_mm)) + 1
        h_rho = rho_max_mm / (n_rho - 1)
        z_lo, z_hi = z_range_mm
        n_z = int(np.ceil((z_hi - z_lo) / step_mm)) + 1
        rho = h_rho * np.arange(-3, n_rho)  # three nodes past the axis, mirrored: g and B_z are even in rho
        z = np.linspace(z_lo, z_hi, n_z)
        R, Z = np.meshgrid(np.where(rho == 0.0, AXIS_RHO_MM, np.abs(rho)), z, indexing="ij")
        B = fld.cylinder_B_T(
            np.stack([R, np.zeros_like(R), Z], axis=-1).reshape(-1, 3), diameter_mm, thickness_mm, remanence_T
        )
        values = np.stack([B[:, 0] / R.ravel(), B[:, 2]]).reshape(2, len(rho), n_z)
        coeffs = [_patches(RectBivariateSpline(rho, z, v, kx=3, ky=3, s=0), rho[3:], z) for v in values]
        patches = np.stack(coeffs, axis=2)  # (cells along rho, along z, 2, 4, 4)
        return cls(
            0.0,
            float(z_lo),
            h_rho,
            float(z[1] - z[0]),
            np.ascontiguousarray(patches.reshape(*patches.shape[:2], 2, 16)),
        )

    def own_frame(self, p_mm: np.ndarray, gradient: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """(B (3, m) T, dB/dp (3, 3, m) T/mm or None) at points ``p_mm`` (3, m) in the magnet's
        own frame."""
        x, y, z = p_mm
        rho = np.hypot(x, y)
        n_rho, n_z = self.coeffs.shape[:2]
        a = (rho - self.rho0_mm) / self.step_rho_mm
        b = (z - self.z0_mm) / self.step_z_mm
        i = np.clip(a.astype(np.intp), 0, n_rho - 1)
        j = np.clip(np.floor(b).astype(np.intp), 0, n_z - 1)
        c = np.take(self.coeffs.reshape(n_rho * n_z, 2, 16), i * n_z + j, axis=0)  # (m, 2, 16)
        (U, dU), (V, dV) = _powers(a - i), _powers(b - j)
        f = np.einsum("mcw,wm->cm", c, (U[:, None] * V[None, :]).reshape(16, -1))
        g, Bz = f
        B = np.array([g * x, g * y, Bz])
        if not gradient:
            return B, None
        f_rho = np.einsum("mcw,wm->cm", c, (dU[:, None] * V[None, :]).reshape(16, -1)) / self.step_rho_mm
        f_z = np.einsum("mcw,wm->cm", c, (U[:, None] * dV[None, :]).reshape(16, -1)) / self.step_z_mm
        safe = np.where(rho > 0.0, rho, 1.0)
        cx, cy = np.where(rho > 0.0, x / safe, 0.0), np.where(rho > 0.0, y / safe, 0.0)  # d rho / dx, dy
        gr = f_rho[0]
        G = np.array(
            [
                [g + gr * x * cx, gr * x * cy, f_z[0] * x],
                [gr * y * cx, g + gr * y * cy, f_z[0] * y],
                [f_rho[1] * cx, f_rho[1] * cy, f_z[1]],
            ]
        )
        return B, G

    def field_T(
        self, q_mm: np.ndarray, rotvec_rad: np.ndarray, gradient: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """(B (3, m) T, dB/dq (3, 3, m) T/mm, dB/drotvec (3, 3, m) T/rad; the two None without
        ``gradient``) at the points ``q_mm`` (3, m) from the magnet's centre, the magnet turned by
        ``rotvec_rad`` (3, m) (components first, as the rows of numpy's fast loops)."""
        R, Jl = rotation_and_left_jacobian(rotvec_rad)
        own, G = self.own_frame(np.einsum("jim,jm->im", R, q_mm), gradient)  # R^T q
        B = np.einsum("ijm,jm->im", R, own)
        if G is None:
            return B, None, None
        dB_dq = np.einsum("ijm,jkm,lkm->ilm", R, G, R)
        dB_drot = matmul(matmul(dB_dq, skew(q_mm)) - skew(B), Jl)
        return B, dB_dq, dB_drot


def _powers(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((4, m) 1, t, t^2, t^3; (4, m) their derivatives)."""
    t2 = t * t
    one, zero = np.ones_like(t), np.zeros_like(t)
    return np.array([one, t, t2, t2 * t]), np.array([zero, one, 2.0 * t, 3.0 * t2])


def _patches(spline, rho: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(len(rho) - 1, len(z) - 1, 4, 4) the bicubic Hermite patches through the spline's values,
    slopes and cross slopes at the nodes, in each cell's unit coordinates."""
    P, Q = np.meshgrid(rho, z, indexing="ij")
    h_rho, h_z = rho[1] - rho[0], z[1] - z[0]
    f = spline.ev(P, Q)
    fr, fz, frz = spline.ev(P, Q, dx=1) * h_rho, spline.ev(P, Q, dy=1) * h_z, spline.ev(P, Q, dx=1, dy=1) * h_rho * h_z

    def corners(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return a[:-1, :-1], a[:-1, 1:], a[1:, :-1], a[1:, 1:]

    (f00, f01, f10, f11), (r00, r01, r10, r11) = corners(f), corners(fr)
    (z00, z01, z10, z11), (x00, x01, x10, x11) = corners(fz), corners(frz)
    F = np.stack(
        [
            np.stack([f00, f01, z00, z01], -1),
            np.stack([f10, f11, z10, z11], -1),
            np.stack([r00, r01, x00, x01], -1),
            np.stack([r10, r11, x10, x11], -1),
        ],
        -2,
    )  # (cells, cells, 4 along rho, 4 along z)
    return np.einsum("ia,rzab,jb->rzij", HERMITE, F, HERMITE)
