"""The tilt rung's equilibrium (:mod:`mst_cli.model.mechanics.tilt`) for many loads at once.

The same residual and exact tangent as :func:`~mst_cli.model.mechanics.tilt.solve_layer_tilt`,
written over arrays of m loads: the walls' integral over the depth cut at every knot the closure
line crosses (a fixed count of cuts, pieces outside the depth of zero length), the pads' pressed
polygon with a fixed count of vertex slots (an unused slot repeats its neighbour, so its edge adds
nothing to Green's sums). Newton from a guess close to the answer (a table's, or the previous
load's) then needs no damping: the fast readers (:mod:`mst_cli.estimation.two_chip_table`) take a
few full steps and make a tabulated state exact.

Pure numpy, no I/O.
"""

from __future__ import annotations

import numpy as np

from mst_cli.model.mechanics.tilt import NEWTON_TOL_REL, LayerTiltLaw, PiecewiseForce

ALPHAS = (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125)  # the step's shares tried, as the scalar solve's


def depth_moments_many(
    law: PiecewiseForce, a_mm: np.ndarray, s: np.ndarray, half_depth_mm: float
) -> tuple[np.ndarray, ...]:
    """(I0, I1, J00, J01, J11), each (m,): the integrals over y in [-D/2, D/2] of F(a + s y)
    and y F, and of F', y F', y^2 F' (the tangent), exactly, for every load."""
    knots = law.d_knots_mm
    with np.errstate(divide="ignore", invalid="ignore"):
        y_k = (knots[None, :] - a_mm[:, None]) / s[:, None]
    y_k = np.clip(np.where(np.isfinite(y_k), y_k, -half_depth_mm), -half_depth_mm, half_depth_mm)
    ends = np.full((len(a_mm), 1), half_depth_mm)
    y = np.sort(np.concatenate([-ends, y_k, ends], axis=1), axis=1)
    y1, y2 = y[:, :-1], y[:, 1:]
    y_mid = 0.5 * (y1 + y2)
    mid = a_mm[:, None] + s[:, None] * y_mid
    slope = law.slopes_N_per_mm[np.searchsorted(knots, mid, side="right")]
    c1 = slope * s[:, None]  # on each piece F = c0 + c1 y exactly
    c0 = law.force_N(mid) - c1 * y_mid
    m0, m1, m2 = y2 - y1, (y2**2 - y1**2) / 2, (y2**3 - y1**3) / 3
    sums = (c0 * m0 + c1 * m1, c0 * m1 + c1 * m2, slope * m0, slope * m1, slope * m2)
    return tuple(v.sum(axis=1) for v in sums)


def pressed_patch_many(
    half_x: float, half_y: float, c: np.ndarray, alpha: np.ndarray, beta: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(m, 3) and (m, 3, 3): :func:`~mst_cli.model.mechanics.contact_patch.pressed_patch` for
    every load: the rectangle clipped to c + alpha x + beta y >= 0 (eight vertex slots: a corner
    and an edge's crossing per side), its area moments by Green's theorem."""
    box = np.array([(-half_x, -half_y), (half_x, -half_y), (half_x, half_y), (-half_x, half_y)])
    f = c[:, None] + alpha[:, None] * box[None, :, 0] + beta[:, None] * box[None, :, 1]  # (m, 4)
    fq = np.roll(f, -1, axis=1)
    q = np.roll(box, -1, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(f != fq, f / (f - fq), 0.0)
    cross_pt = box[None, :, :] + t[:, :, None] * (q - box)[None, :, :]
    verts = np.stack([np.broadcast_to(box, cross_pt.shape), cross_pt], axis=2).reshape(len(c), 8, 2)
    valid = np.stack([f >= 0.0, (f >= 0.0) != (fq >= 0.0)], axis=2).reshape(len(c), 8)
    idx = np.where(valid, np.arange(8), -1)
    last = idx.max(axis=1, keepdims=True)
    idx = np.maximum.accumulate(idx, axis=1)
    idx = np.where(idx < 0, np.maximum(last, 0), idx)  # leading empty slots repeat the polygon's last vertex
    v = np.take_along_axis(verts, idx[:, :, None], axis=1)
    x0, y0 = v[..., 0], v[..., 1]
    x1, y1 = np.roll(x0, -1, axis=1), np.roll(y0, -1, axis=1)
    cr = x0 * y1 - x1 * y0
    A = cr.sum(1) / 2.0
    Sx, Sy = ((x0 + x1) * cr).sum(1) / 6.0, ((y0 + y1) * cr).sum(1) / 6.0
    Sxx = ((x0 * x0 + x0 * x1 + x1 * x1) * cr).sum(1) / 12.0
    Syy = ((y0 * y0 + y0 * y1 + y1 * y1) * cr).sum(1) / 12.0
    Sxy = ((x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cr).sum(1) / 24.0
    J = np.stack([np.stack([A, Sx, Sy], -1), np.stack([Sx, Sxx, Sxy], -1), np.stack([Sy, Sxy, Syy], -1)], -2)
    return np.einsum("mij,mj->mi", J, np.stack([c, alpha, beta], -1)), J


def residual_many(layer: LayerTiltLaw, u: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The equilibrium residual (m, 3) (force, M_y, M_x) at states ``u`` (m, 3) = (d, phi_y,
    phi_x) against ``target`` (m, 3), and its exact tangent (m, 3, 3)."""
    d, phi_y, phi_x = u[:, 0], u[:, 1], u[:, 2]
    half = 0.5 * layer.depth_mm
    scale = 1.0 / (2.0 * layer.depth_mm)  # each chevron carries half the walls per mm of depth
    r = -np.array(target, dtype=float)
    K = np.zeros((len(u), 3, 3))
    for sign in (-1.0, 1.0):
        x = sign * layer.lever_mm
        I0, I1, J00, J01, J11 = depth_moments_many(layer.walls, d + phi_y * x, phi_x, half)
        r += scale * np.stack([I0, x * I0, I1], -1)
        dI0 = np.stack([J00, x * J00, J01], -1)
        dI1 = np.stack([J01, x * J01, J11], -1)
        K += scale * np.stack([dI0, x * dI0, dI1], -2)
    a = layer.pad_half_width_mm
    if a > 0.0 and layer.pad_stiffness_N_per_mm > 0.0:
        kappa = layer.pad_stiffness_N_per_mm / (4.0 * a * half)
        f_pad, J_pad = pressed_patch_many(a, half, d - layer.pad_gap_mm, phi_y, phi_x)
        r += kappa * f_pad
        K += kappa * J_pad
    return r, K


def newton_many(
    layer: LayerTiltLaw, force_N: np.ndarray, offset_mm: np.ndarray, guess: np.ndarray, steps: int
) -> np.ndarray:
    """(m, 3) the states after ``steps`` Newton steps from ``guess`` (m, 3) toward the equilibrium
    under ``force_N`` (m,) pressed at ``offset_mm`` (m, 2): each step halved until the residual
    (relative to the load, as the scalar solve measures it) falls, for each load on its own; a
    load whose step cannot lower it stays put (and is not tried again: its next step would be the
    same), one within the scalar solve's tolerance too."""
    F = np.asarray(force_N, dtype=float)
    target = np.column_stack([F, F * offset_mm[:, 0], F * offset_mm[:, 1]])
    norm = np.array([1.0, layer.lever_mm, 0.5 * layer.depth_mm])[None, :] * np.maximum(np.abs(F), 1e-12)[:, None]
    u = np.array(guess, dtype=float)
    r, K = residual_many(layer, u, target)
    size = np.max(np.abs(r) / norm, axis=1)
    stuck = np.zeros(len(u), dtype=bool)  # no step lowered the residual: the next would be the same
    for _ in range(steps):
        todo = np.flatnonzero((size > NEWTON_TOL_REL) & ~stuck & (np.abs(np.linalg.det(K)) > 1e-300))
        if not len(todo):
            break
        du = np.linalg.solve(K[todo], -r[todo][:, :, None])[:, :, 0]
        for alpha in ALPHAS:
            if not len(todo):
                break
            trial = u[todo] + alpha * du
            r_t, K_t = residual_many(layer, trial, target[todo])
            s_t = np.max(np.abs(r_t) / norm[todo], axis=1)
            down = s_t < size[todo]
            take = todo[down]
            u[take], r[take], K[take], size[take] = trial[down], r_t[down], K_t[down], s_t[down]
            todo, du = todo[~down], du[~down]
        stuck[todo] = True
    return u
