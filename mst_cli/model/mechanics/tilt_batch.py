"""The tilt rung's equilibrium (:mod:`mst_cli.model.mechanics.tilt`) for many loads at once,
compiled.

The same residual and exact tangent as :func:`~mst_cli.model.mechanics.tilt.solve_layer_tilt`,
one load at a time in a compiled loop (numba): the walls' integral over the depth cut at every knot
the closure line crosses, the pads' pressed polygon clipped from their rectangle, its area moments
by Green's theorem. Newton from a guess close to the answer (a table's, or the previous load's)
then mostly takes full steps (the scalar solve's damping is kept for a step across the pads'
stiff contact): the fast readers (:mod:`mst_cli.estimation.two_chip_table`) take a few steps and
make a tabulated state exact.

Why compiled: a live two-chip stream at 2,000 readings a second leaves 0.5 ms a reading, and the
same arithmetic as numpy's array calls cost about 9 us a load per residual, mostly in the calls'
temporaries and the cuts' sort (issue 45). A load's residual is a few dozen flops here.
The scalar solve in :mod:`~mst_cli.model.mechanics.tilt` stays the reference the tests hold these
to (1e-12).

Pure, no I/O. numba is imported with this module, which only the two-chip reader imports.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mst_cli.model.mechanics.tilt import NEWTON_TOL_REL, LayerTiltLaw, member_state

ALPHAS = (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125)  # the step's shares tried, as the scalar solve's
_ALPHAS = np.array(ALPHAS)
_DET_MIN = 1e-300  # a tangent this singular takes no step


def _law_arrays(layer: LayerTiltLaw) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(the walls' knots, forces and slopes, the scalars (lever, half depth, a, pad gap, kappa))."""
    w = layer.walls
    half = 0.5 * layer.depth_mm
    a = layer.pad_half_width_mm
    k = layer.pad_stiffness_N_per_mm
    kappa = k / (4.0 * a * half) if a > 0.0 and k > 0.0 else 0.0
    scalars = np.array([layer.lever_mm, half, a, layer.pad_gap_mm, kappa, 1.0 / (2.0 * layer.depth_mm)])
    return (
        np.ascontiguousarray(w.d_knots_mm, dtype=float),
        np.ascontiguousarray(w.F_knots_N, dtype=float),
        np.ascontiguousarray(w.slopes_N_per_mm, dtype=float),
        scalars,
    )


@njit(cache=True, nogil=True)
def _piece(knots, d):  # pragma: no cover - compiled
    """The slope's index of d: 0 below the first knot, len(knots) past the last (searchsorted right)."""
    lo, hi = 0, len(knots)
    while lo < hi:
        mid = (lo + hi) // 2
        if knots[mid] <= d:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def _depth_moments(knots, F_knots, slopes, a, s, half, out):  # pragma: no cover - compiled
    """out[:] = (I0, I1, J00, J01, J11): the integrals over y in [-half, half] of F(a + s y), y F,
    and of F', y F', y^2 F', exactly (F piecewise linear: cut at the knots the line crosses)."""
    n = len(knots)
    cuts = np.empty(n + 2)
    cuts[0] = -half
    m = 1
    if s != 0.0:
        for k in range(n):
            y = (knots[k] - a) / s
            if -half < y < half:
                cuts[m] = y
                m += 1
    cuts[m] = half
    m += 1
    for i in range(1, m):  # insertion sort: a handful of cuts
        v = cuts[i]
        j = i - 1
        while j >= 0 and cuts[j] > v:
            cuts[j + 1] = cuts[j]
            j -= 1
        cuts[j + 1] = v
    for q in range(5):
        out[q] = 0.0
    for i in range(m - 1):
        y1, y2 = cuts[i], cuts[i + 1]
        if y2 <= y1:
            continue
        ym = 0.5 * (y1 + y2)
        mid = a + s * ym
        p = _piece(knots, mid)
        slope = slopes[p]
        jk = min(max(p - 1, 0), n - 1)
        c1 = slope * s  # on each piece F = c0 + c1 y exactly
        c0 = F_knots[jk] + slope * (mid - knots[jk]) - c1 * ym
        m0 = y2 - y1
        m1 = (y2 * y2 - y1 * y1) / 2.0
        m2 = (y2 * y2 * y2 - y1 * y1 * y1) / 3.0
        out[0] += c0 * m0 + c1 * m1
        out[1] += c0 * m1 + c1 * m2
        out[2] += slope * m0
        out[3] += slope * m1
        out[4] += slope * m2


@njit(cache=True, nogil=True)
def _pressed_patch(hx, hy, c, alpha, beta, f_out, J_out):  # pragma: no cover - compiled
    """f_out (3,), J_out (3, 3): the rectangle [-hx, hx] x [-hy, hy] clipped to c + alpha x + beta y
    >= 0, its area moments J (symmetric) and J (c, alpha, beta) (contact_patch.pressed_patch's)."""
    bx = (-hx, hx, hx, -hx)
    by = (-hy, -hy, hy, hy)
    vx = np.empty(8)
    vy = np.empty(8)
    n = 0
    for i in range(4):
        q = (i + 1) % 4
        fp = c + alpha * bx[i] + beta * by[i]
        fq = c + alpha * bx[q] + beta * by[q]
        if fp >= 0.0:
            vx[n], vy[n] = bx[i], by[i]
            n += 1
        if (fp >= 0.0) != (fq >= 0.0):
            t = fp / (fp - fq)
            vx[n], vy[n] = bx[i] + t * (bx[q] - bx[i]), by[i] + t * (by[q] - by[i])
            n += 1
    A = Sx = Sy = Sxx = Syy = Sxy = 0.0
    if n >= 3:
        for i in range(n):
            x0, y0 = vx[i], vy[i]
            x1, y1 = vx[(i + 1) % n], vy[(i + 1) % n]
            cr = x0 * y1 - x1 * y0
            A += cr
            Sx += (x0 + x1) * cr
            Sy += (y0 + y1) * cr
            Sxx += (x0 * x0 + x0 * x1 + x1 * x1) * cr
            Syy += (y0 * y0 + y0 * y1 + y1 * y1) * cr
            Sxy += (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cr
        A, Sx, Sy, Sxx, Syy, Sxy = A / 2.0, Sx / 6.0, Sy / 6.0, Sxx / 12.0, Syy / 12.0, Sxy / 24.0
    J_out[0, 0], J_out[0, 1], J_out[0, 2] = A, Sx, Sy
    J_out[1, 0], J_out[1, 1], J_out[1, 2] = Sx, Sxx, Sxy
    J_out[2, 0], J_out[2, 1], J_out[2, 2] = Sy, Sxy, Syy
    for i in range(3):
        f_out[i] = J_out[i, 0] * c + J_out[i, 1] * alpha + J_out[i, 2] * beta


@njit(cache=True, nogil=True)
def _residual(knots, F_knots, slopes, sc, d, phi_y, phi_x, t0, t1, t2, r, K, work, f_pad, J_pad):  # pragma: no cover
    """r (3,), K (3, 3): the equilibrium residual (force, M_y, M_x) at (d, phi_y, phi_x) against
    the target (t0, t1, t2), and its exact tangent (tilt._residual's)."""
    lever, half, a, gap, kappa, scale = sc[0], sc[1], sc[2], sc[3], sc[4], sc[5]
    r[0], r[1], r[2] = -t0, -t1, -t2
    for i in range(3):
        for j in range(3):
            K[i, j] = 0.0
    for side in range(2):
        x = -lever if side == 0 else lever
        _depth_moments(knots, F_knots, slopes, d + phi_y * x, phi_x, half, work)
        I0, I1, J00, J01, J11 = work[0], work[1], work[2], work[3], work[4]
        r[0] += scale * I0
        r[1] += scale * x * I0
        r[2] += scale * I1
        # rows (force, M_y, M_x) against columns (d, phi_y, phi_x)
        K[0, 0] += scale * J00
        K[0, 1] += scale * x * J00
        K[0, 2] += scale * J01
        K[1, 0] += scale * x * J00
        K[1, 1] += scale * x * x * J00
        K[1, 2] += scale * x * J01
        K[2, 0] += scale * J01
        K[2, 1] += scale * x * J01
        K[2, 2] += scale * J11
    if kappa > 0.0:
        _pressed_patch(a, half, d - gap, phi_y, phi_x, f_pad, J_pad)
        for i in range(3):
            r[i] += kappa * f_pad[i]
            for j in range(3):
                K[i, j] += kappa * J_pad[i, j]


@njit(cache=True, nogil=True)
def _det3(K):  # pragma: no cover - compiled
    return (
        K[0, 0] * (K[1, 1] * K[2, 2] - K[1, 2] * K[2, 1])
        - K[0, 1] * (K[1, 0] * K[2, 2] - K[1, 2] * K[2, 0])
        + K[0, 2] * (K[1, 0] * K[2, 1] - K[1, 1] * K[2, 0])
    )


@njit(cache=True, nogil=True)
def _solve3(K, b, x):  # pragma: no cover - compiled
    """x = K^-1 b by Gaussian elimination with partial pivoting (K, b left as they were)."""
    A = np.empty((3, 4))
    for i in range(3):
        for j in range(3):
            A[i, j] = K[i, j]
        A[i, 3] = b[i]
    for col in range(3):
        p = col
        for i in range(col + 1, 3):
            if abs(A[i, col]) > abs(A[p, col]):
                p = i
        if p != col:
            for j in range(4):
                A[col, j], A[p, j] = A[p, j], A[col, j]
        for i in range(col + 1, 3):
            f = A[i, col] / A[col, col]
            for j in range(col, 4):
                A[i, j] -= f * A[col, j]
    for i in range(2, -1, -1):
        s = A[i, 3]
        for j in range(i + 1, 3):
            s -= A[i, j] * x[j]
        x[i] = s / A[i, i]


@njit(cache=True, nogil=True)
def _residual_rows(knots, F_knots, slopes, sc, u, target, r_out, K_out):  # pragma: no cover - compiled
    work, f_pad, J_pad = np.empty(5), np.empty(3), np.empty((3, 3))
    for i in range(u.shape[0]):
        _residual(
            knots, F_knots, slopes, sc, u[i, 0], u[i, 1], u[i, 2],
            target[i, 0], target[i, 1], target[i, 2], r_out[i], K_out[i], work, f_pad, J_pad,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def _newton_rows(knots, F_knots, slopes, sc, F, off, u, steps, alphas, tol):  # pragma: no cover - compiled
    """u (m, 3) moved in place by up to ``steps`` Newton steps per load (newton_many's rule)."""
    work, f_pad, J_pad = np.empty(5), np.empty(3), np.empty((3, 3))
    r, K = np.empty(3), np.empty((3, 3))
    r_t, K_t = np.empty(3), np.empty((3, 3))
    du, minus_r = np.empty(3), np.empty(3)
    norm = np.empty(3)
    lever, half = sc[0], sc[1]
    for i in range(u.shape[0]):
        t0, t1, t2 = F[i], F[i] * off[i, 0], F[i] * off[i, 1]
        scale = max(abs(F[i]), 1e-12)
        norm[0], norm[1], norm[2] = scale, lever * scale, half * scale
        d, py, px = u[i, 0], u[i, 1], u[i, 2]
        _residual(knots, F_knots, slopes, sc, d, py, px, t0, t1, t2, r, K, work, f_pad, J_pad)
        size = max(abs(r[0]) / norm[0], abs(r[1]) / norm[1], abs(r[2]) / norm[2])
        for _ in range(steps):
            if not size > tol or not abs(_det3(K)) > _DET_MIN:
                break
            for q in range(3):
                minus_r[q] = -r[q]
            _solve3(K, minus_r, du)
            # the scalar solve's rule: the first share that lowers the residual, else the smallest
            # (a step across the pads' stiff contact can raise it before the next one falls)
            for alpha in alphas:
                td, tpy, tpx = d + alpha * du[0], py + alpha * du[1], px + alpha * du[2]
                _residual(knots, F_knots, slopes, sc, td, tpy, tpx, t0, t1, t2, r_t, K_t, work, f_pad, J_pad)
                s_t = max(abs(r_t[0]) / norm[0], abs(r_t[1]) / norm[1], abs(r_t[2]) / norm[2])
                if s_t < size:
                    break
            d, py, px, size = td, tpy, tpx, s_t
            r[:] = r_t
            K[:, :] = K_t
        u[i, 0], u[i, 1], u[i, 2] = d, py, px


def residual_many(layer: LayerTiltLaw, u: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The equilibrium residual (m, 3) (force, M_y, M_x) at states ``u`` (m, 3) = (d, phi_y,
    phi_x) against ``target`` (m, 3), and its exact tangent (m, 3, 3) in the layer's own state
    (the state less what its member adds under ``target``, :func:`~mst_cli.model.mechanics.tilt.member_state`)."""
    target = np.ascontiguousarray(np.broadcast_to(np.asarray(target, dtype=float), np.shape(u)), dtype=float)
    target = target.reshape(-1, 3)
    u = np.ascontiguousarray(np.asarray(u, dtype=float).reshape(-1, 3) - member_state(layer, target))
    r, K = np.empty((len(u), 3)), np.empty((len(u), 3, 3))
    _residual_rows(*_law_arrays(layer), u, target, r, K)
    return r, K


def newton_many(
    layer: LayerTiltLaw, force_N: np.ndarray, offset_mm: np.ndarray, guess: np.ndarray, steps: int
) -> np.ndarray:
    """(m, 3) the states after ``steps`` Newton steps from ``guess`` (m, 3) toward the equilibrium
    under ``force_N`` (m,) pressed at ``offset_mm`` (m, 2): each step halved until the residual
    (relative to the load, as the scalar solve measures it) falls, the smallest share taken when
    none does (the scalar solve's rule), for each load on its own; a load within the scalar
    solve's tolerance stays put. The states are the unit's: its member's part (the cover's,
    :func:`~mst_cli.model.mechanics.tilt.member_state`) taken off before and put back after."""
    F = np.ascontiguousarray(force_N, dtype=float).ravel()
    off = np.ascontiguousarray(offset_mm, dtype=float).reshape(-1, 2)
    shift = member_state(layer, np.column_stack([F, F * off[:, 0], F * off[:, 1]]))  # the member in series
    u = np.array(guess, dtype=float).reshape(-1, 3) - shift
    _newton_rows(*_law_arrays(layer), F, off, u, int(steps), _ALPHAS, NEWTON_TOL_REL)
    return u + shift
