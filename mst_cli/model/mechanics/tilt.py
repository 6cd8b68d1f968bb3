"""Off-centre loads on one layer: compression and tilt with rigid plates (the tilt rung of L0).

A vertical force F pressed at (x0, y0) on the top face (mm; x across the width W, y along the
depth D, the origin on the magnet axis) reaches every layer as the same force and the same
moments, M_y = F x0 and M_x = F y0 (a vertical force's moment about a horizontal axis does not
depend on the axis's height; small rotations, no P-delta). Each layer answers independently.

The layer's web is two chevrons, one on each side, each running the whole depth D, and between
them the pads, which meet when the layer locks. With rigid plates the top plate's motion
relative to the bottom one is a compression d at the axis and two small rotations, so the plates
close by d + phi_y x + phi_x y at (x, y), and

* each chevron's walls, on a line x = +-x_c, carry per mm of depth half the walls' law at that
  closure, W(delta) / (2 D): the layer law of any rung (:mod:`mst_cli.model.mechanics`) up to
  its lock, the walls' own stiffness beyond (the law's locked stiffness less the pads' column);
* the pads, the rectangle |x| <= a (the inner pad's half width), |y| <= D/2, touch where the
  closure passes the lock stroke d_lock and press there with the pads' column stiffness spread
  over their area (:mod:`mst_cli.model.mechanics.contact_patch`).

At a uniform closure that is the layer law exactly: W(d) + k_pads (d - d_lock)+. Tilted, the pads
touch first at the loaded end x = +-a, not at the chevron's lever: L2 under tilted plates locks
there on a thin shallow cell to 0.1 % of the stroke (tests/test_offcentre.py); over the box its
loaded side's lock stroke is a median 3.4 % from it (studies/check_tilt_rung.py, where a wall
pinches first or a thick pad's contact spreads). Equilibrium of force and both moments fixes
(d, phi_y, phi_x).

Every law is piecewise linear in d, so the integrals over the depth are exact sums over the
pieces the line delta(y) crosses, the pads' are exact polygon moments, and Newton's tangent is
exact too. In tension (delta < 0, a side lifting off, only for loads outside the chevrons) the
walls go on with their small-load stiffness k: the web is bonded to both plates.

x_c is where the chevron's force sits under a tilt: not at its wall roots (the midpoint x_r of
the outer root at x = p and the inner one t tan(theta/2) further in) but between them and the
tip W/2, because turning the pad turns the wall's root too and the wall answers with a
deflection along its run. L2 measures it at small strain (two linear solves,
:func:`mst_cli.model.mechanics.continuum_tilt.linear_tilt_lever_mm`); the rung uses a fit of
a = (x_c - x_r) / (W/2 - x_r) in theta, t/L, t/(h - t) and t/(t + a) (tools/fit_tilt_lever.py,
mst_cli/model/data/tilt_lever.json, with its out-of-sample error).

A member in series that never closes (the housing's cover under layer 1,
:class:`MemberInSeries`) stays outside the layer's contact problem: the layer solves its own
equilibrium, and the member adds its drop and its turns as a beam's under the couple; the pads'
contact is the layer's own closure.

Pure numpy; the lever's coefficients load once from the package data. At (x0, y0) = (0, 0) it is
the axial model exactly (phi = 0).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mst_cli.model.mechanics.contact_patch import pressed_patch
from mst_cli.model.mechanics.spring import contact_stiffness_N_per_mm

NEWTON_TOL_REL = 1e-12  # force and moment residuals, relative to F (and F times the lever)
NEWTON_MAX_ITER = 60
# A solve whose damped steps no longer lower the residual has reached round-off: with a soft layer
# pressed far off the axis (a lever of tens of mm, stiff pads touching) that floor sits near 1e-11
# of the load. Below this it is an equilibrium; above it, none was found.
NEWTON_FLOOR_REL = 1e-9
LEVER_DATA = Path(__file__).resolve().parent.parent / "data" / "tilt_lever.json"


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

    @functools.cached_property
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
class MemberInSeries:
    """A member in series with a layer and outside its contact problem (the housing's cover under
    layer 1, :class:`~mst_cli.model.part_laws.SeriesMember`): its drop m(F), piecewise linear in
    the layer's force (through ``F_knots_N`` from 0 and ``drop_mm`` there, ``rate_after_mm_per_N``
    past the last knot), and its turns as a beam under the layer's couple, c(F) M_y / x_c^2 and
    c(F) M_x / (D^2 / 12) (c = dm/dF: the chevron lines' pair and the depth's uniform strip);
    ``moment_gain_after`` (F_N, g): from F_N on, the turn under M_y is g times that (the cover's
    portal under a locked layer 1, :func:`mst_cli.model.part_laws.unit_tilt_law`)."""

    F_knots_N: np.ndarray
    drop_mm: np.ndarray
    rate_after_mm_per_N: float
    moment_gain_after: tuple[float, float] = (math.inf, 1.0)

    @functools.cached_property
    def rates_mm_per_N(self) -> np.ndarray:
        """dm/dF on every piece between knots and past the last one."""
        return np.append(np.diff(self.drop_mm) / np.diff(self.F_knots_N), self.rate_after_mm_per_N)

    def rate_mm_per_N(self, force_N) -> np.ndarray:
        """dm/dF just past ``force_N`` (right-continuous at a knot)."""
        i = np.searchsorted(self.F_knots_N, np.asarray(force_N, dtype=float), side="right") - 1
        return self.rates_mm_per_N[np.clip(i, 0, len(self.F_knots_N) - 1)]

    def drop_at_mm(self, force_N) -> np.ndarray:
        """m(F), mm: linear on each piece, on past the last knot at ``rate_after_mm_per_N``."""
        F = np.asarray(force_N, dtype=float)
        i = np.clip(np.searchsorted(self.F_knots_N, F, side="right") - 1, 0, len(self.F_knots_N) - 1)
        return self.drop_mm[i] + self.rates_mm_per_N[i] * (F - self.F_knots_N[i])


@dataclass(frozen=True)
class LayerTiltLaw:
    """One layer as the tilt rung sees it (module docstring): walls on two lines, pads between,
    and a member in series outside the contact problem (``member``; None: none)."""

    walls: PiecewiseForce  # the web's walls at a uniform closure (N against mm)
    lever_mm: float  # x_c of the chevrons' lines
    depth_mm: float  # D
    pad_half_width_mm: float  # a
    pad_gap_mm: float  # the lock stroke: the pads touch past it
    pad_stiffness_N_per_mm: float  # the closed pads' column, over their whole area
    member: MemberInSeries | None = None

    @classmethod
    def from_layer(cls, law, cell, modulus_MPa: float, poisson_ratio: float) -> LayerTiltLaw:
        """From a layer law of any rung and its cell; ``modulus_MPa`` the one the law was made
        with (the web's, :func:`mst_cli.model.mechanics.depth.in_web`) for the pads' column."""
        theta = math.radians(cell.theta_deg)
        k_pads = float(
            contact_stiffness_N_per_mm(theta, cell.t_mm, cell.width_mm, cell.b_mm, modulus_MPa, poisson_ratio)
        )
        F = np.concatenate([[0.0], np.asarray(law.knots_N, dtype=float)])
        d = np.asarray(law.displacement_mm(F), dtype=float)
        k_walls_after = max(float(law.k_locked_N_per_mm) - k_pads, 0.0)
        walls = PiecewiseForce(d, F, float(law.k_N_per_mm), k_walls_after)
        a = max(cell.p_mm - cell.t_mm * math.tan(0.5 * theta), 0.0)
        lever = chevron_lever_mm(theta, cell.t_mm, cell.h_mm, cell.width_mm)
        return cls(walls, lever, cell.depth_mm, a, float(law.d_lock_mm), k_pads)

    @property
    def lock_force_N(self) -> float:
        return float(self.walls.F_knots_N[-1])

    def with_lever_factor(self, factor: float) -> LayerTiltLaw:
        """The same layer with its levers (the chevrons' x_c and the pads' half width) scaled: what
        a load test at known offsets calibrates (``mst calibrate`` with x_mm, y_mm columns)."""
        return replace(self, lever_mm=self.lever_mm * factor, pad_half_width_mm=self.pad_half_width_mm * factor)


def member_state(layer: LayerTiltLaw, target: np.ndarray) -> np.ndarray:
    """(..., 3) what the layer's member adds to its (d, phi_y, phi_x) under the loads ``target``
    (..., 3) = (F, M_y, M_x): (m(F), c M_y / x_c^2, c M_x / (D^2 / 12)) (:class:`MemberInSeries`);
    zeros without one."""
    target = np.asarray(target, dtype=float)
    if layer.member is None:
        return np.zeros_like(target)
    F = target[..., 0]
    turns = member_compliance(layer, F)[..., 1:] * target[..., 1:]
    return np.concatenate([layer.member.drop_at_mm(F)[..., None], turns], axis=-1)


def member_compliance(layer: LayerTiltLaw, force_N) -> np.ndarray:
    """(..., 3) d :func:`member_state` / d (F, M_y, M_x) just past ``force_N``: (c, g c / x_c^2,
    12 c / D^2), c = dm/dF, g the member's moment gain there (zeros without a member)."""
    F = np.asarray(force_N, dtype=float)
    if layer.member is None:
        return np.zeros((*F.shape, 3))
    c = layer.member.rate_mm_per_N(F)[..., None]
    out = c * np.array([1.0, 1.0 / layer.lever_mm**2, 12.0 / layer.depth_mm**2])
    start, gain = layer.member.moment_gain_after
    if gain != 1.0:
        out[..., 1] *= np.where(F >= start, gain, 1.0)
    return out


@dataclass(frozen=True)
class LayerTilt:
    """One layer's answer to an off-centre load: compression at the axis and rotations, its
    member's included; the pads' ends and contact its own."""

    d_mm: float  # compression at x = y = 0
    phi_y_rad: float  # rotation about y: the +x side closes by phi_y x more
    phi_x_rad: float  # rotation about x: the +y side closes by phi_x y more
    pad_end_mm: tuple[float, float]  # the largest closure at the pads' -x and +x ends
    pads_touch: tuple[bool, bool]  # whether the pads touch at those ends


def root_midpoint_mm(theta_rad: float, t_mm: float, pad_half_width_mm: float) -> float:
    """x_r: the midpoint of the wall's outer root (x = p) and inner root (p - t tan(theta/2))."""
    return pad_half_width_mm - 0.5 * t_mm * math.tan(0.5 * theta_rad)


def lever_features(theta_rad: float, t_mm: float, h_mm: float, width_mm: float) -> list[float]:
    """The lever fit's terms: polynomial in s = theta - pi/4, x = t/L, y = t/(h - t), and
    z = t / (t + a) with a the inner pad's half width (a short pad turns with its wall)."""
    s = theta_rad - 0.25 * math.pi
    x = t_mm / (0.5 * (h_mm - t_mm) / math.sin(theta_rad))
    y = t_mm / (h_mm - t_mm)
    a = max(0.5 * width_mm - 0.5 * h_mm / math.tan(theta_rad) - t_mm * math.tan(0.5 * theta_rad), 0.0)
    z = t_mm / (t_mm + a)
    return [1.0, s, s * s, s**3, x, x * s, x * x, y, y * s, z, z * s, z * z, z * x]


@functools.lru_cache(maxsize=1)
def _lever_coef() -> tuple[float, ...]:
    return tuple(json.loads(LEVER_DATA.read_text())["coef"])


def chevron_lever_mm(theta_rad: float, t_mm: float, h_mm: float, width_mm: float) -> float:
    """x_c: where a chevron's force sits when the plates tilt (mm from the axis), from the fit
    to L2 (module docstring)."""
    p = 0.5 * width_mm - 0.5 * h_mm / math.tan(theta_rad)
    x_r = root_midpoint_mm(theta_rad, t_mm, p)
    a = float(np.dot(_lever_coef(), lever_features(theta_rad, t_mm, h_mm, width_mm)))
    return x_r + a * (0.5 * width_mm - x_r)


def solve_layer_tilt(
    layer: LayerTiltLaw,
    force_N: float,
    offset_mm: tuple[float, float],
    guess: tuple[float, float, float] | None = None,
) -> LayerTilt:
    """(d, phi_y, phi_x) of one layer carrying ``force_N`` pressed at ``offset_mm`` = (x0, y0).

    Newton on the three equilibrium equations with the exact tangent, from ``guess`` (the
    previous force's answer on a curve) or the axial solution. Raises TiltError."""
    x0, y0 = offset_mm
    target = np.array([force_N, force_N * x0, force_N * y0])
    shift = member_state(layer, target)  # the member in series: the layer's own state is the rest
    u = np.array(guess if guess is not None else (_axial_guess(layer, force_N), 0.0, 0.0), dtype=float)
    if guess is not None:
        u = u - shift
    norm = np.array([1.0, layer.lever_mm, 0.5 * layer.depth_mm]) * max(abs(force_N), 1e-12)
    r, K = _residual(layer, u, target)
    r_norm = float(np.max(np.abs(r) / norm))
    for _ in range(NEWTON_MAX_ITER):
        if r_norm <= NEWTON_TOL_REL:
            return _layer_tilt(layer, u, shift)
        du = np.linalg.solve(K, -r)
        # damped: a full step across a stiff knot (the pads touching) can overshoot into a flip-flop;
        # the accepted trial's residual and tangent are the next iteration's
        for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125):
            r_try, K_try = _residual(layer, u + alpha * du, target)
            norm_try = float(np.max(np.abs(r_try) / norm))
            if norm_try < r_norm:
                break
        u, r, K, r_norm = u + alpha * du, r_try, K_try, norm_try
    if r_norm <= NEWTON_FLOOR_REL:
        return _layer_tilt(layer, u, shift)
    raise TiltError(f"no equilibrium for {force_N:.4g} N at ({x0:g}, {y0:g}) mm (residual {r_norm:.2g} of the load)")


def tilt_compliance_rad_per_Nmm(layer: LayerTiltLaw, force_N: float) -> float:
    """The layer's turn about y per N mm of moment about y at the centred force ``force_N``, its
    member's included: the equilibrium's tangent at the centred state (right-continuous at a
    knot, as :func:`member_compliance`)."""
    d = float(centred_compression_mm(layer, force_N))
    _, K = _residual(layer, np.array([d, 0.0, 0.0]), np.zeros(3))
    return float(np.linalg.inv(K)[1, 1] + member_compliance(layer, force_N)[1])


def _axial_guess(layer: LayerTiltLaw, force_N: float) -> float:
    """The layer's own centred closure at this force (walls and pads together)."""
    return float(centred_compression_mm(layer, force_N))


def centred_compression_mm(layer: LayerTiltLaw, force_N) -> np.ndarray:
    """The layer's own closure under a centred force (walls and pads together, its member's drop
    not included), over an array of forces."""
    w = layer.walls
    F = np.asarray(force_N, dtype=float)
    k_locked = max(w.k_after_N_per_mm + layer.pad_stiffness_N_per_mm, 1e-300)
    past = w.d_knots_mm[-1] + (F - w.F_knots_N[-1]) / k_locked
    return np.where(F <= w.F_knots_N[-1], np.interp(F, w.F_knots_N, w.d_knots_mm), past)


def _residual(layer: LayerTiltLaw, u: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equilibrium residual (force, M_y, M_x) and its Jacobian in (d, phi_y, phi_x)."""
    d, phi_y, phi_x = u
    half = 0.5 * layer.depth_mm
    scale = 1.0 / (2.0 * layer.depth_mm)  # each chevron carries half the walls per mm of depth
    r = -target.astype(float)
    K = np.zeros((3, 3))
    for sign in (-1.0, 1.0):
        x = sign * layer.lever_mm
        (I0, I1), J = depth_moments(layer.walls, d + phi_y * x, phi_x, half)
        r += scale * np.array([I0, x * I0, I1])
        # d(a)/d(d, phi_y, phi_x) = (1, x, 0); d(s)/d(...) = (0, 0, 1)
        dI0 = np.array([J[0, 0], x * J[0, 0], J[0, 1]])
        dI1 = np.array([J[1, 0], x * J[1, 0], J[1, 1]])
        K += scale * np.stack([dI0, x * dI0, dI1])
    a = layer.pad_half_width_mm
    if a > 0.0 and layer.pad_stiffness_N_per_mm > 0.0:
        kappa = layer.pad_stiffness_N_per_mm / (4.0 * a * half)
        f_pad, J_pad = pressed_patch(a, half, d - layer.pad_gap_mm, phi_y, phi_x)
        r += kappa * f_pad
        K += kappa * J_pad
    return r, K


def _layer_tilt(layer: LayerTiltLaw, u: np.ndarray, shift: np.ndarray) -> LayerTilt:
    """The unit's answer from the layer's own state ``u`` and its member's ``shift``: the pads'
    ends and contact are the layer's own closure."""
    d, phi_y, phi_x = (float(v) for v in u)
    a, spread = layer.pad_half_width_mm, abs(phi_x) * 0.5 * layer.depth_mm
    ends = (d - phi_y * a + spread, d + phi_y * a + spread)
    unit = u + shift
    touch = (ends[0] > layer.pad_gap_mm, ends[1] > layer.pad_gap_mm)
    return LayerTilt(float(unit[0]), float(unit[1]), float(unit[2]), ends, touch)
