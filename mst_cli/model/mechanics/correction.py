"""Corrections of rung L0 fitted against rung L2: joint stiffness, lock force, lock stroke.

Beam theory clamps each wall at the pad's mid-plane and at the chevron's tip; the real
profile's joints are finite blocks with a near-crack at the cavity's tip vertex, so thick or
shallow walls (large t/L, small theta) are stiffer or softer than the beam says. The ratio
k_L2 / k_L0 depends only on theta and t/L (and nu: both are plane strain and scale with E b;
see tools/fit_l0_correction.py, which fits and stores the coefficients in
mst_cli/model/data/l0_correction.json):

    ln(k_L2 / k_L0) = sum_i c_i f_i(x, s, y),   x = t/L, s = theta - pi/4,
                      y = x / (2 sin theta) = t / (h - t)

with terms x, x^2, x^3, x s, ... (the polynomial of the thin and moderately thick walls) and
y, ln(1/(1 - y)) (times powers of s): y is the part of the centre line L that lies inside the
two joints -- the free inner face is L (1 - y) long -- and the beam's bending compliance goes
with the cube of the free length, so ln(L / L_free) = ln(1/(1 - y)) is what makes shallow
walls (theta 5-15 deg, where the tip joint is a solid wedge t / tan(theta) long) up to ten
times stiffer than the beam. Every term vanishes with x, so the factor tends to 1 for slender
walls (x -> 0), the beam-theory limit. y < t / (t + 0.4 mm) < 0.9 for every valid cell.

Beam theory is also linear, but the walls rotate a lot before the cavity closes (the stroke
is most of their height), so the real lock force R differs from k d_lock -- below it for
tall steep walls, which soften, above it where faces zipping shut stiffen the walls first --
and the lock (L2's stiffness knee: a wall pinched between the plate and its mirror, or the
pads meeting; docs/design.md section 4) can come a little before the rigid pads' stroke. Two
more fits give R / (k d_lock) and d_lock / (h - 2t - a):

    ln(ratio) = sigma * sum_i c_i g_i(x, s, y, sigma, e),   sigma = d_lock / (L sin theta),
                                                            e = exp(-2x / sigma)

sigma is the stroke as a fraction of one wall's rise: the softening is a large-rotation
effect, first order in the stroke, so both ratios tend to 1 as the stroke vanishes. g is a
full cubic in (x, s) plus terms in y, sigma, e and w; 2x / sigma = 2 t sin(theta) / d_lock is
the inner wall face's gap at rest, one wall thickness from the cavity's tip vertex, over the
stroke: where it is small the walls touch before the pads do, and e switches those terms on;
w = 1 - t / L_in (smoothly floored at 0) is the part of the inner face that can touch at all.
At given (x, theta), sigma = 2 (1 - y (1 + a/t)) also carries the allowance over the wall
thickness, r = a/t, which decides where a shallow cavity's thin tip counts as closed; terms
r, r s, r sigma (r recovered from x, theta, sigma) carry it for the thin walls (t 0.4-0.6 mm,
r 0.17-0.25) where compact designs live, sampled apart in the fit (its thin band). The lock
force adds a smooth hinge on the lock-stroke fit's own q = d_lock / (h - 2t - a) (HINGE_TERMS):
where a wall is pinched before the pads meet (q below ~0.97) L2's lock force follows other
terms; over uniform cells it took the fit's out-of-sample median from 3.5 % to 2.6 %.

Fitted for nu = 0.45 and a 0.1 mm contact allowance, plane strain (the web of b = D), against
the plane-strain L2 (``fitted_on`` in the data file), over the printable box (theta 5-75 deg,
t 0.4-3 mm, h 1.2-8 mm, every cell rule met: t/L up to 1.7); b drops out of every ratio.
Outside the fitted box the inputs are held at its edge. The errors left, measured out of
sample per band of t/L and theta, are in the data file too (:func:`expected_error_rel`).
Vectorised, pure.
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.arrays import stacked_terms

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

TERMS = [
    "x",
    "x^2",
    "x^3",
    "x*s",
    "x^2*s",
    "x*s^2",
    "x^2*s^2",
    "x*s^3",
    "x^3*s",
    "ly",
    "ly*s",
    "ly*s^2",
    "ly^2",
    "ly^2*s",
    "y",
    "y*s",
]
LOCK_TERMS = [
    "1",
    "x",
    "s",
    "x^2",
    "x*s",
    "s^2",
    "x^3",
    "x^2*s",
    "x*s^2",
    "s^3",
    "y",
    "y*s",
    "y^2",
    "y*x",
    "sigma",
    "sigma*x",
    "sigma*s",
    "sigma^2",
    "sigma*y",
    "e",
    "e*s",
    "e*x",
    "e^2",
    "e*sigma",
    "w",
    "w*s",
    "w*x",
    "w^2",
    "w*sigma",
    "r",
    "r*s",
    "r*sigma",
]
# The wall-pinch hinge of the lock-force fit: L2 locks either where the pads meet or earlier,
# where a wall is pinched between the plate and its mirror, and the two regimes' lock forces
# follow different shapes. The lock-stroke fit predicts which (its q = d_lock / (h - 2t - a)
# falls below ~0.97 where the walls close early), so the hinge p = HINGE_WIDTH ln(1 +
# exp(-(ln q + HINGE_OFFSET) / HINGE_WIDTH)), less its value at q = 1 so that it vanishes with
# the stroke, about zero where the pads meet and -ln q - 0.03 once a wall closes first, times
# these shape terms, is added to ln(R / (k d_lock)) (not times sigma). The width is the
# smallest of 0.01-0.05 that held out best (studies/l0_lock_regime.py).
HINGE_TERMS = ["p", "p*x", "p*s", "p*sigma", "p^2", "p*x^2", "p*s^2"]
HINGE_WIDTH = 0.01
HINGE_OFFSET = 0.03
DATA = Path(__file__).resolve().parent.parent / "data" / "l0_correction.json"

# The printable box every rung is fitted and measured on, and the default design bounds
# (mst_cli.sensor.document reads it; so do mst_cli.bench.ladder_bench and the fit): walls from one nozzle line to
# 3 mm, from 5 deg (shallow) to 75 deg (steep), 1.2-8 mm layers; the cell rules
# (HexCell.violations) cut out what does not print or has no stroke. Inside it t/L reaches 1.7
# (walls shorter than they are thick). Below 5 deg a 30 mm cell's pads vanish for most h (the
# pad rule), above 75 deg the walls are columns whose stroke is mostly their own shortening.
VERIFIED_BOX = {"theta_deg": (5.0, 75.0), "t_mm": (0.4, 3.0), "h_mm": (1.2, 8.0)}
# y = t / (h - t) < t / (t + min cavity) = 0.88 for every valid cell (t <= 3 mm, h - 2t >= 0.4
# mm); the fitted box holds it there (``fitted_on.y_range``), this only keeps the log finite
Y_MAX = 0.95
# r = allowance / t is recovered from (t/L, theta, sigma) (sigma = 2 (1 - y (1 + r))) and held in
# [0, R_MAX] (printable cells: a / 3 mm to a / 0.4 mm = 0.03-0.25 at a = 0.1 mm); _on_cells
# keeps the probes on the fitted cells, this only keeps the terms bounded anywhere
R_MAX = 1.0


def _y(x, theta):
    """y = x / (2 sin theta) = t / (h - t), held below Y_MAX."""
    return np.minimum(x / (2.0 * np.sin(theta)), Y_MAX)


def design_matrix(t_over_L: ArrayLike, theta_rad: ArrayLike) -> np.ndarray:
    """The stiffness fit's terms (TERMS) at (x = t/L, theta), stacked on a last axis."""
    x = np.asarray(t_over_L, dtype=float)
    th = np.asarray(theta_rad, dtype=float)
    s = th - np.pi / 4
    y = _y(x, th)
    ly = -np.log1p(-y)
    return stacked_terms(
        x,
        x**2,
        x**3,
        x * s,
        x**2 * s,
        x * s**2,
        x**2 * s**2,
        x * s**3,
        x**3 * s,
        ly,
        ly * s,
        ly * s**2,
        ly**2,
        ly**2 * s,
        y,
        y * s,
    )


def lock_design_matrix(t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """The lock fits' terms g_i (LOCK_TERMS), stacked on a last axis (not yet times sigma)."""
    x = np.asarray(t_over_L, dtype=float)
    th = np.asarray(theta_rad, dtype=float)
    sig = np.asarray(sigma, dtype=float)
    s = th - np.pi / 4
    y = _y(x, th)
    e = np.exp(-2.0 * x / np.maximum(sig, 1e-12))
    w = _face_beyond_wedge(x, y)
    r = allowance_over_t(x, th, sig)
    return stacked_terms(
        np.ones_like(x),
        x,
        s,
        x**2,
        x * s,
        s**2,
        x**3,
        x**2 * s,
        x * s**2,
        s**3,
        y,
        y * s,
        y**2,
        y * x,
        sig,
        sig * x,
        sig * s,
        sig**2,
        sig * y,
        e,
        e * s,
        e * x,
        e**2,
        e * sig,
        w,
        w * s,
        w * x,
        w**2,
        w * sig,
        r,
        r * s,
        r * sig,
    )


def _hinge(ln_q: np.ndarray, width: float, offset: float) -> np.ndarray:
    """p = width (softplus(-(ln q + offset) / width) - softplus(-offset / width)), softplus(z) =
    ln(1 + e^z) written as max(z, 0) + ln(1 + e^-|z|): no overflow, and a NaN probe stays NaN
    without a warning, as through every other term."""
    z = -(ln_q + offset) / width
    z0 = -offset / width
    p0 = max(z0, 0.0) + math.log1p(math.exp(-abs(z0)))
    return width * (np.maximum(z, 0.0) + np.log1p(np.exp(-np.abs(z))) - p0)


def hinge_design_matrix(
    t_over_L: ArrayLike,
    theta_rad: ArrayLike,
    sigma: ArrayLike,
    ln_stroke_ratio: ArrayLike,
    width: float = HINGE_WIDTH,
    offset: float = HINGE_OFFSET,
) -> np.ndarray:
    """The wall-pinch hinge's terms (HINGE_TERMS) on a last axis, from ln q = ln(d_lock / (h -
    2t - a)) as the lock-stroke fit predicts it. Smooth (C-infinity) in every input; p is taken
    from its value at q = 1, so that like every lock term it vanishes with the stroke."""
    x = np.asarray(t_over_L, dtype=float)
    s = np.asarray(theta_rad, dtype=float) - np.pi / 4
    sig = np.asarray(sigma, dtype=float)
    p = _hinge(np.asarray(ln_stroke_ratio, dtype=float), width, offset)
    return stacked_terms(p, p * x, p * s, p * sig, p * p, p * x * x, p * s * s)


def hinge_sum(x: np.ndarray, theta: np.ndarray, sig: np.ndarray, ln_q: np.ndarray, coef, width, offset) -> np.ndarray:
    """sum_j coef[j] HINGE_TERMS_j: :func:`hinge_design_matrix` times coef without building the
    matrix (the design loop calls this on a few dozen cells at a time, where every array op
    counts; elementwise, so a cell's bits do not depend on its batch). Tested equal."""
    p = _hinge(ln_q, width, offset)
    s = theta - np.pi / 4
    c = coef
    return p * (c[0] + c[1] * x + c[2] * s + c[3] * sig + c[4] * p + c[5] * (x * x) + c[6] * (s * s))


def allowance_over_t(t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """r = allowance / t of the cell with this (t/L, theta, sigma): sigma = 2 (1 - y (1 + r)),
    so r = (1 - sigma / 2) / y - 1, held in [0, R_MAX] (and finite as y -> 0). At the thinnest
    printable wall r = 0.25: the allowance (the pads' touch gap) is a quarter of the wall."""
    x = np.asarray(t_over_L, dtype=float)
    y = _y(x, np.asarray(theta_rad, dtype=float))
    r = (1.0 - 0.5 * np.asarray(sigma, dtype=float)) / np.maximum(y, 1e-6) - 1.0
    return np.clip(r, 0.0, R_MAX)


def _face_beyond_wedge(x, y, eps=0.05):
    """w = 1 - t / L_in, smoothly floored at 0: the part of the inner wall face (L_in = L (1 - y)
    long) more than one wall thickness from the cavity's tip vertex, the part that can touch
    its mirror image before the pads meet. w = 0: only the pads can close the cavity."""
    u = 1.0 - x / np.maximum(1.0 - y, 1e-3)
    return 0.5 * (u + np.sqrt(u * u + eps * eps))


@functools.lru_cache(maxsize=1)
def _fit() -> dict:
    """The stored fit; a missing file is an installation error, never a silent 'no correction'."""
    return json.loads(DATA.read_text())


@functools.lru_cache(maxsize=8)
def _coef(key: str | None = None) -> np.ndarray:
    return np.array(coefficients(key))


@functools.lru_cache(maxsize=8)
def coefficients(key: str | None = None) -> tuple[float, ...]:
    """Stored coefficients: of the stiffness fit (None), "lock_force", "lock_stroke" or
    "lock_force_hinge" (the wall-pinch hinge's; empty in a file fitted without it)."""
    if key == "lock_force_hinge":
        return tuple(map(float, _fit()["lock_force"].get("hinge", {}).get("coefficients", ())))
    return tuple(map(float, _fit()["coefficients"] if key is None else _fit()[key]["coefficients"]))


def clear_caches() -> None:
    """Forget the stored fit (after tools/fit_l0_correction.py rewrote the file)."""
    for f in (_fit, _coef, coefficients):
        f.cache_clear()


def fitted_t_over_L_max() -> float:
    return float(_fit()["fitted_on"]["t_over_L_range"][1])


def fitted_theta_rad_range() -> tuple[float, float]:
    lo, hi = _fit()["fitted_on"]["theta_deg_range"]
    return float(np.radians(lo)), float(np.radians(hi))


def _clipped(t_over_L, theta_rad):
    """(t/L, theta) held inside the fitted box: theta in its range, then 0 <= t/L <= the
    fitted maximum and y = t/L / (2 sin theta) = t / (h - t) <= its fitted maximum -- the box
    of valid cells is not a rectangle in (t/L, theta): at theta = 15 deg t/L stops at 0.45."""
    theta = np.clip(np.asarray(theta_rad, dtype=float), *fitted_theta_rad_range())
    x_max = np.minimum(fitted_t_over_L_max(), 2.0 * np.sin(theta) * _fit()["fitted_on"]["y_range"][1])
    x = np.clip(np.asarray(t_over_L, dtype=float), 0.0, x_max)
    return x, theta


def stroke_ratio(d_lock_mm: ArrayLike, wall_length_mm: ArrayLike, theta_rad: ArrayLike) -> np.ndarray:
    """sigma = d_lock / (L sin theta): the stroke over one wall's rise (0 to about 2)."""
    return np.asarray(d_lock_mm, dtype=float) / (np.asarray(wall_length_mm, dtype=float) * np.sin(theta_rad))


def _on_cells(x, theta, sigma):
    """sigma moved onto the cells the fit saw. For a cell sigma = 2 (1 - y (1 + a/t)) (a the
    contact allowance), so at given (t/L, theta) it only spans a/t = a/3 mm to a/0.4 mm
    (``fitted_on.allowance_over_t_range``); the terms are evaluated there, and at the
    fitted stroke range's edges."""
    fit = _fit()["fitted_on"]
    r_lo, r_hi = fit["allowance_over_t_range"]
    y = _y(x, theta)
    lo = np.maximum(2.0 * (1.0 - y * (1.0 + r_hi)), fit["stroke_ratio_range"][0])
    hi = np.maximum(np.minimum(2.0 * (1.0 - y * (1.0 + r_lo)), fit["stroke_ratio_range"][1]), lo)
    return np.clip(sigma, lo, hi)


def _weighted_sum(terms: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """sum_j terms[..., j] coef[j], the same bits for a cell whatever batch it comes in.

    ``terms @ coef`` hands the product to BLAS, whose kernel (and so its summation order)
    depends on the array's shape: a cell's law then moved by ~1e-13 between a batch of 19
    stacks and the same cells in another shape, and the optimiser's path, which is chaotic in
    the last bits, with it. numpy's own einsum loop (no BLAS without ``optimize``) sums every
    cell's terms in one order, and is faster here than the BLAS call.
    """
    return np.einsum("...j,j->...", terms, coef)


def _lock_ratios(keys, t_over_L, theta_rad, sigma, clipped=None):
    """exp(sigma g(x, theta, sigma')) for each fit in ``keys``, one design matrix for all: the
    leading sigma is the cell's own (held in [0, the largest fitted]), so the ratio tends to 1
    with the stroke; the terms g are taken at the nearest fitted cell, (x, theta) in the box and
    sigma' = :func:`_on_cells`. The lock force adds the wall-pinch hinge on the lock-stroke
    fit's own ln q (HINGE_TERMS). ``clipped``: :func:`_clipped` (t/L, theta), when the caller has it."""
    sig = np.clip(np.asarray(sigma, dtype=float), 0.0, _fit()["fitted_on"]["stroke_ratio_range"][1])
    x, theta = _clipped(t_over_L, theta_rad) if clipped is None else clipped
    terms = lock_design_matrix(x, theta, _on_cells(x, theta, sig))
    hinge = _coef("lock_force_hinge") if "lock_force" in keys else ()
    ln = {key: sig * _weighted_sum(terms, _coef(key)) for key in (*keys, *(("lock_stroke",) if len(hinge) else ()))}
    if len(hinge):
        shape = _fit()["lock_force"]["hinge"]  # the width and offset the file was fitted with
        ln["lock_force"] = ln["lock_force"] + hinge_sum(
            x, theta, sig, ln["lock_stroke"], hinge, shape["width"], shape["offset"]
        )
    return [np.exp(ln[key]) for key in keys]


def _lock_ratio(key, t_over_L, theta_rad, sigma):
    return _lock_ratios((key,), t_over_L, theta_rad, sigma)[0]


def lock_factors(
    t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike, clipped: tuple | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(:func:`lock_force_factor`, :func:`lock_stroke_factor`) from one design matrix: what
    the design loop's L0 kernel needs per call, at half the cost of the two calls."""
    force, stroke = _lock_ratios(("lock_force", "lock_stroke"), t_over_L, theta_rad, sigma, clipped)
    return (
        np.minimum(force, _fit()["lock_force"]["ratio_range"][1]),
        np.minimum(stroke, _fit()["lock_stroke"]["ratio_range"][1]),
    )


def lock_force_factor(t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """R_L2 / (k d_lock) predicted by the fit (k the corrected L0 stiffness, d_lock = h - 2t - a).

    Held inside the fitted (t/L, theta, sigma) box like :func:`stiffness_factor`, and at most
    the largest ratio L2 gave on the fitted cells: the box of (t/L, theta, sigma) holds
    corners no cell reaches (a small t/L at a shallow theta has a small sigma), where the
    polynomial would climb past 100.
    """
    return np.minimum(_lock_ratio("lock_force", t_over_L, theta_rad, sigma), _fit()["lock_force"]["ratio_range"][1])


def lock_stroke_factor(t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """d_lock,L2 / (h - 2t - a) predicted by the fit, at most the largest ratio L2 gave on
    the fitted cells (a few per cent above 1: the pads are elastic and, under stiff walls,
    meet a little after the rigid-pad stroke)."""
    return np.minimum(_lock_ratio("lock_stroke", t_over_L, theta_rad, sigma), _fit()["lock_stroke"]["ratio_range"][1])


def stiffness_factor(t_over_L: ArrayLike, theta_rad: ArrayLike) -> np.ndarray:
    """k_L2 / k_L0 predicted by the fit.

    x = t/L is clipped to [0, the largest t/L fitted] and theta to its fitted range (optimisers
    probe far outside the bounds, where the terms would swing or overflow): cells outside the
    box keep the factor of its nearest edge.
    """
    x, theta = _clipped(t_over_L, theta_rad)
    return np.exp(_weighted_sum(design_matrix(x, theta), _coef()))


def spring_factors(t_over_L: ArrayLike, theta_rad: ArrayLike, sigma: ArrayLike) -> tuple:
    """(:func:`stiffness_factor`, then :func:`lock_factors`) with (t/L, theta) held in the fitted
    box once: the three corrections the L0 kernel applies (model.mechanics.spring)."""
    clipped = _clipped(t_over_L, theta_rad)
    stiffness = np.exp(_weighted_sum(design_matrix(*clipped), _coef()))
    return stiffness, *lock_factors(t_over_L, theta_rad, sigma, clipped)


def expected_error_rel(t_over_L: ArrayLike, theta_rad: ArrayLike, t_mm: ArrayLike | None = None) -> np.ndarray:
    """Median |relative error| of the corrected L0 lock force R against L2, measured out of
    sample in the band of (t/L, theta) each cell falls in (``out_of_sample`` in the data
    file; bands: t/L 0-0.6-1.0-, theta 5-15-60-75 deg). Vectorised, pure.

    A band the measurement had no cell in (e.g. t/L > 0.6 at theta < 15 deg, which the cell
    rules exclude) takes the worst band of the same t/L range. Points outside the bands fall in
    the nearest one. Given the wall thickness t_mm, cells of the thin band (the compact
    designs: t below ``thin.t_mm_max``, theta below ``thin.theta_deg_max``, sampled and
    measured apart) take its own measured median instead.
    """
    table = _fit()["out_of_sample"]["expected_error"]
    x_edges = np.asarray(table["t_over_L_edges"], dtype=float)
    th_edges = np.radians(np.asarray(table["theta_deg_edges"], dtype=float))
    err = np.asarray(table["median_abs_err_lock_force"], dtype=float)  # (n_x, n_theta)
    i = np.clip(np.searchsorted(x_edges, np.asarray(t_over_L, dtype=float), side="right") - 1, 0, err.shape[0] - 1)
    j = np.clip(np.searchsorted(th_edges, np.asarray(theta_rad, dtype=float), side="right") - 1, 0, err.shape[1] - 1)
    out = err[i, j]
    thin = table.get("thin")
    if t_mm is None or thin is None:
        return out
    in_thin = (np.asarray(t_mm, dtype=float) < thin["t_mm_max"]) & (
        np.asarray(theta_rad, dtype=float) < np.radians(thin["theta_deg_max"])
    )
    return np.where(in_thin, thin["median_abs_err_lock_force"], out)
