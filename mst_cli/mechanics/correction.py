"""Corrections of rung L0 fitted against rung L2: joint stiffness, lock force, lock stroke.

Beam theory clamps each wall at the pad's mid-plane and at the chevron's tip; the real
profile's joints are finite blocks with a near-crack at the cavity's tip vertex, so thick or
shallow walls (large t/L, small theta) are stiffer or softer than the beam says. The ratio
k_L2 / k_L0 depends only on theta and t/L (and nu: both are plane strain and scale with E b;
see
benchmarks/fit_l0_correction.py, which fits and stores the coefficients in
mst_cli/data/l0_correction.json):

    ln(k_L2 / k_L0) = x * P(x, s),  P a cubic in (x, s),  x = t/L, s = theta - pi/4

so the factor tends to 1 for slender walls (x -> 0), the beam-theory limit.

Beam theory is also linear, but the walls rotate a lot before the cavity closes (the stroke
is most of their height), so the real lock force R is below k d_lock -- by 35 % at the
median of the 24 bench cells, up to 70 % for steep walls -- and the cavity closes a little before the pads meet. Two more
fits give R / (k d_lock) and d_lock / (h - 2t - a):

    ln(ratio) = sigma * Q(x, s),  Q a full cubic,  sigma = d_lock / (L sin theta)

sigma is the stroke as a fraction of one wall's rise: the softening is a large-rotation
effect, first order in the stroke, so both ratios tend to 1 as the stroke vanishes.

Fitted for nu = 0.45 and a 0.1 mm contact allowance, plane strain (the web of b = D), against
the plane-strain L2 (``fitted_on`` in the data file); b drops out of every ratio.
Vectorised, pure.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

TERMS = ["x", "x^2", "x^3", "x^4", "x*s", "x^2*s", "x^3*s", "x*s^2", "x^2*s^2", "x*s^3"]
LOCK_TERMS = ["1", "x", "s", "x^2", "x*s", "s^2", "x^3", "x^2*s", "x*s^2", "s^3"]
DATA = Path(__file__).resolve().parent.parent / "data" / "l0_correction.json"


def design_matrix(t_over_L, theta_rad):
    x = np.asarray(t_over_L, dtype=float)
    s = np.asarray(theta_rad, dtype=float) - np.pi / 4
    return np.stack(np.broadcast_arrays(x, x ** 2, x ** 3, x ** 4, x * s, x ** 2 * s, x ** 3 * s,
                                         x * s ** 2, x ** 2 * s ** 2, x * s ** 3), axis=-1)


def lock_design_matrix(t_over_L, theta_rad):
    x = np.asarray(t_over_L, dtype=float)
    s = np.asarray(theta_rad, dtype=float) - np.pi / 4
    return np.stack(np.broadcast_arrays(np.ones_like(x), x, s, x ** 2, x * s, s ** 2, x ** 3,
                                         x ** 2 * s, x * s ** 2, s ** 3), axis=-1)


@functools.lru_cache(maxsize=1)
def _fit() -> dict:
    """The stored fit; a missing file is an installation error, never a silent 'no correction'."""
    return json.loads(DATA.read_text())


@functools.lru_cache(maxsize=4)
def coefficients(key: str | None = None) -> tuple[float, ...]:
    """Stored coefficients: of the stiffness fit (None), "lock_force" or "lock_stroke"."""
    return tuple(map(float, _fit()["coefficients"] if key is None else _fit()[key]["coefficients"]))


def _stiffness_poly(x, s, c):
    """design_matrix(x, s) @ c, written out: 16 us of stacking less per scalar call (L0 is
    called one cell at a time by simulate and the bench)."""
    return (x * (c[0] + x * (c[1] + x * (c[2] + x * c[3]))) + x * s * (c[4] + x * (c[5] + x * c[6]))
            + x * s * s * (c[7] + x * c[8]) + c[9] * x * s ** 3)


def _lock_poly(x, s, c):
    """lock_design_matrix(x, s) @ c, written out."""
    return (c[0] + c[1] * x + c[2] * s + c[3] * x * x + c[4] * x * s + c[5] * s * s
            + c[6] * x ** 3 + c[7] * x * x * s + c[8] * x * s * s + c[9] * s ** 3)


def fitted_t_over_L_max() -> float:
    return float(_fit()["fitted_on"]["t_over_L_range"][1])


def fitted_theta_rad_range() -> tuple[float, float]:
    lo, hi = _fit()["fitted_on"]["theta_deg_range"]
    return float(np.radians(lo)), float(np.radians(hi))


def _clipped(t_over_L, theta_rad):
    x = np.clip(np.asarray(t_over_L, dtype=float), 0.0, fitted_t_over_L_max())
    theta = np.clip(np.asarray(theta_rad, dtype=float), *fitted_theta_rad_range())
    return x, theta


def stroke_ratio(d_lock_mm, wall_length_mm, theta_rad):
    """sigma = d_lock / (L sin theta): the stroke over one wall's rise (0 to about 2)."""
    return np.asarray(d_lock_mm, dtype=float) / (np.asarray(wall_length_mm, dtype=float) * np.sin(theta_rad))


def _lock_ratio(key, t_over_L, theta_rad, sigma):
    sig = np.clip(np.asarray(sigma, dtype=float), 0.0, _fit()["fitted_on"]["stroke_ratio_range"][1])
    x, theta = _clipped(t_over_L, theta_rad)
    return np.exp(sig * _lock_poly(x, theta - np.pi / 4, coefficients(key)))


def lock_force_factor(t_over_L, theta_rad, sigma):
    """R_L2 / (k d_lock) predicted by the fit (k the corrected L0 stiffness, d_lock = h - 2t - a).

    Held inside the fitted (t/L, theta, sigma) box like :func:`stiffness_factor`.
    """
    return _lock_ratio("lock_force", t_over_L, theta_rad, sigma)


def lock_stroke_factor(t_over_L, theta_rad, sigma):
    """d_lock,L2 / (h - 2t - a) predicted by the fit, capped at 1 (the pads' stroke)."""
    return np.minimum(_lock_ratio("lock_stroke", t_over_L, theta_rad, sigma), 1.0)


def stiffness_factor(t_over_L, theta_rad):
    """k_L2 / k_L0 predicted by the fit.

    x = t/L is clipped to [0, the largest t/L fitted]: past its data the cubic swings (at
    theta 60 deg it would fall from 0.87 at t/L 0.6 to 0.41 at 1.0), so stubbier walls keep
    the factor of the stubbiest fitted wall. theta is held inside its fitted range likewise
    (optimisers probe far outside the bounds, where the polynomial in theta would overflow).
    """
    x, theta = _clipped(t_over_L, theta_rad)
    return np.exp(_stiffness_poly(x, theta - np.pi / 4, coefficients()))
