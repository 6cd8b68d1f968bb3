"""Off-centre loads on one layer: compression and tilt with rigid plates (the tilt rung of L0).

A vertical force F pressed at (x0, y0) on the top face (mm; x across the width W, y along the
depth D, the origin on the magnet axis) reaches every layer as the same force and the same
moments, M_y = F x0 and M_x = F y0 (a vertical force's moment about a horizontal axis does not
depend on the axis's height; small rotations, no P-delta). Each layer answers independently.

The layer's web is two chevrons, one on each side, each running the whole depth D. With rigid
plates the top plate's motion relative to the bottom one is a compression d at the axis and two
small rotations, so a chevron's line of wall roots at x = +-x_c is compressed by

    delta(y) = d + phi_y x_c sign + phi_x y ,     y in [-D/2, D/2],

and carries, per mm of depth, half the layer's law at that compression, F_layer(delta) / (2 D):
the layer law of any rung (:mod:`mst_cli.model.mechanics`) is the force of the whole web at a
uniform compression. Equilibrium of force and both moments fixes (d, phi_y, phi_x).

Every layer law is piecewise linear in d, so the integrals over the depth are exact sums over
the pieces the line delta(y) crosses, and Newton's tangent is exact too. Beyond the last knot
the law goes on with its locked stiffness; in tension (delta < 0, a side lifting off, only for
loads outside the chevrons) with its small-load stiffness k: the web is bonded to both plates.

x_c is the midpoint of the wall's two roots on the pad (the outer root at x = p and the inner
one t tan(theta/2) further in): where the wall hands its force to the pad.

Pure numpy, no I/O. At (x0, y0) = (0, 0) it is the axial model exactly (phi = 0, F_layer(d) = F).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

NEWTON_TOL_REL = 1e-12  # force and moment residuals, relative to F (and F times the lever)
NEWTON_MAX_ITER = 60


class TiltError(RuntimeError):
    """The layer's equilibrium under an off-centre load was not found."""


@dataclass(frozen=True)
class PiecewiseForce:
    """F(d) of a layer law: linear between (d_knots, F_knots), from (0, 0) to the lock and beyond
    with ``k_after_N_per_mm``; below 0 with ``k_tension_N_per_mm``."""

    d_knots_mm: np.ndarray
    F_knots_N: np.ndarray
    k_tension_N_per_mm: float
    k_after_N_per_mm: float

    @classmethod
    def from_law(cls, law) -> PiecewiseForce:
        """From a layer law (``knots_N``, ``displacement_mm``, ``k_N_per_mm``, ``k_locked_N_per_mm``)."""
        F = np.concatenate([[0.0], np.asarray(law.knots_N, dtype=float)])
        d = np.asarray(law.displacement_mm(F), dtype=float)
        return cls(d, F, float(law.k_N_per_mm), float(law.k_locked_N_per_mm))

    @property
    def slopes_N_per_mm(self) -> np.ndarray:
        """Slope below 0, on every piece between knots, and past the last one."""
        inner = np.diff(self.F_knots_N) / np.diff(self.d_knots_mm)
        return np.concatenate([[self.k_tension_N_per_mm], inner, [self.k_after_N_per_mm]])

    def force_N(self, d_mm: np.ndarray) -> np.ndarray:
        d = np.asarray(d_mm, dtype=float)
        i = np.searchsorted(self.d_knots_mm, d, side="right")  # 0 below 0, len past the last knot
        j = np.clip(i - 1, 0, len(self.d_knots_mm) - 1)
        return self.F_knots_N[j] + self.slopes_N_per_mm[i] * (d - self.d_knots_mm[j])


def depth_moments(law: PiecewiseForce, a_mm: float, s: float, half_depth_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact integrals over y in [-D/2, D/2] of F(a + s y): (I0, I1) = (int F, int y F) in N mm and
    N mm^2, and their tangent [[int F', int y F'], [int y F', int y^2 F']] (F' the slope)."""
    y_lo, y_hi = -half_depth_mm, half_depth_mm
    cuts = [y_lo, y_hi]
    if s != 0.0:
        y_k = (law.d_knots_mm - a_mm) / s
        cuts += [y for y in y_k if y_lo < y < y_hi]
    y = np.sort(np.asarray(cuts))
    y1, y2 = y[:-1], y[1:]
    keep = y2 > y1
    y1, y2 = y1[keep], y2[keep]
    mid = a_mm + s * 0.5 * (y1 + y2)
    slope = law.slopes_N_per_mm[np.searchsorted(law.d_knots_mm, mid, side="right")]
    # on each piece F = c0 + c1 y exactly, with c1 = slope s
    c1 = slope * s
    c0 = law.force_N(mid) - c1 * 0.5 * (y1 + y2)
    m0, m1, m2 = (y2 - y1), (y2**2 - y1**2) / 2, (y2**3 - y1**3) / 3
    I0 = float(np.sum(c0 * m0 + c1 * m1))
    I1 = float(np.sum(c0 * m1 + c1 * m2))
    J = np.array([[np.sum(slope * m0), np.sum(slope * m1)], [np.sum(slope * m1), np.sum(slope * m2)]])
    return np.array([I0, I1]), J


@dataclass(frozen=True)
class LayerTilt:
    """One layer's answer to an off-centre load: compression at the axis and rotations."""

    d_mm: float  # compression at x = y = 0
    phi_y_rad: float  # rotation about y: the +x side compresses by phi_y x more
    phi_x_rad: float  # rotation about x: the +y side compresses by phi_x y more
    side_min_mm: tuple[float, float]  # least compression along the -x and +x chevrons
    side_max_mm: tuple[float, float]  # most compression along them


def chevron_lever_mm(theta_rad: float, t_mm: float, pad_half_width_mm: float) -> float:
    """x_c: the midpoint of the wall's outer root (x = p) and inner root (p - t tan(theta/2))."""
    return pad_half_width_mm - 0.5 * t_mm * math.tan(0.5 * theta_rad)


def solve_layer_tilt(
    law: PiecewiseForce,
    force_N: float,
    offset_mm: tuple[float, float],
    lever_mm: float,
    depth_mm: float,
    guess: tuple[float, float, float] | None = None,
) -> LayerTilt:
    """(d, phi_y, phi_x) of one layer carrying ``force_N`` pressed at ``offset_mm`` = (x0, y0).

    Newton on the three equilibrium equations with the exact tangent, from ``guess`` (the
    previous force's answer on a curve) or the axial solution. Raises TiltError."""
    x0, y0 = offset_mm
    half = 0.5 * depth_mm
    scale = 1.0 / (2.0 * depth_mm)  # each chevron carries half the web per mm of depth
    target = np.array([force_N, force_N * x0, force_N * y0])
    u = np.array(guess if guess is not None else (_axial_guess(law, force_N), 0.0, 0.0), dtype=float)
    norm = np.array([1.0, lever_mm, half]) * max(abs(force_N), 1e-12)
    r_norm = math.inf
    for _ in range(NEWTON_MAX_ITER):
        r, K = _residual(law, u, target, lever_mm, half, scale)
        r_norm = float(np.max(np.abs(r) / norm))
        if r_norm <= NEWTON_TOL_REL:
            return _layer_tilt(u, lever_mm, half)
        du = np.linalg.solve(K, -r)
        # damped: a full step across a stiff locked knot can overshoot into a flip-flop
        for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125):
            r_try, _ = _residual(law, u + alpha * du, target, lever_mm, half, scale)
            if float(np.max(np.abs(r_try) / norm)) < r_norm:
                break
        u = u + alpha * du
    raise TiltError(f"no equilibrium for {force_N:.4g} N at ({x0:g}, {y0:g}) mm (residual {r_norm:.2g} of the load)")


def _axial_guess(law: PiecewiseForce, force_N: float) -> float:
    return (
        float(np.interp(force_N, law.F_knots_N, law.d_knots_mm))
        if force_N <= law.F_knots_N[-1]
        else float(law.d_knots_mm[-1] + (force_N - law.F_knots_N[-1]) / law.k_after_N_per_mm)
    )


def _residual(law, u, target, lever, half, scale):
    """Equilibrium residual (force, M_y, M_x) and its Jacobian in (d, phi_y, phi_x)."""
    d, phi_y, phi_x = u
    r = -target.astype(float)
    K = np.zeros((3, 3))
    for sign in (-1.0, 1.0):
        x = sign * lever
        (I0, I1), J = depth_moments(law, d + phi_y * x, phi_x, half)
        r += scale * np.array([I0, x * I0, I1])
        # d(a)/d(d, phi_y, phi_x) = (1, x, 0); d(s)/d(...) = (0, 0, 1)
        dI0 = np.array([J[0, 0], x * J[0, 0], J[0, 1]])
        dI1 = np.array([J[1, 0], x * J[1, 0], J[1, 1]])
        K += scale * np.stack([dI0, x * dI0, dI1])
    return r, K


def _layer_tilt(u, lever, half) -> LayerTilt:
    d, phi_y, phi_x = (float(v) for v in u)
    sides = [d + phi_y * sign * lever for sign in (-1.0, 1.0)]
    spread = abs(phi_x) * half
    return LayerTilt(
        d,
        phi_y,
        phi_x,
        (sides[0] - spread, sides[1] - spread),
        (sides[0] + spread, sides[1] + spread),
    )
