"""Correction of the L0 wall stiffness for the finite joints, fitted against rung L2.

Beam theory clamps each wall at the pad's mid-plane and at the chevron's tip; the real
profile's joints are finite blocks with a near-crack at the cavity's tip vertex, so thick or
shallow walls (large t/L, small theta) are stiffer or softer than the beam says. The ratio
k_L2 / k_L0 depends only on theta and t/L (both scale with E b; see
benchmarks/fit_l0_correction.py, which fits and stores the coefficients in
mst_cli/data/l0_correction.json):

    ln(k_L2 / k_L0) = x * P(x, s),  P a cubic in (x, s),  x = t/L, s = theta - pi/4

so the factor tends to 1 for slender walls (x -> 0), the beam-theory limit. Vectorised, pure.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

TERMS = ["x", "x^2", "x^3", "x^4", "x*s", "x^2*s", "x^3*s", "x*s^2", "x^2*s^2", "x*s^3"]
DATA = Path(__file__).resolve().parent.parent / "data" / "l0_correction.json"


def design_matrix(t_over_L, theta_rad):
    x = np.asarray(t_over_L, dtype=float)
    s = np.asarray(theta_rad, dtype=float) - np.pi / 4
    return np.stack(np.broadcast_arrays(x, x ** 2, x ** 3, x ** 4, x * s, x ** 2 * s, x ** 3 * s,
                                         x * s ** 2, x ** 2 * s ** 2, x * s ** 3), axis=-1)


@functools.lru_cache(maxsize=1)
def _fit() -> dict:
    """The stored fit; a missing file is an installation error, never a silent 'no correction'."""
    return json.loads(DATA.read_text())


def coefficients() -> np.ndarray:
    return np.asarray(_fit()["coefficients"], dtype=float)


def fitted_t_over_L_max() -> float:
    return float(_fit()["fitted_on"]["t_over_L_range"][1])


def fitted_theta_rad_range() -> tuple[float, float]:
    lo, hi = _fit()["fitted_on"]["theta_deg_range"]
    return float(np.radians(lo)), float(np.radians(hi))


def stiffness_factor(t_over_L, theta_rad):
    """k_L2 / k_L0 predicted by the fit.

    x = t/L is clipped to [0, the largest t/L fitted]: past its data the cubic swings (at
    theta 60 deg it would fall from 0.87 at t/L 0.6 to 0.41 at 1.0), so stubbier walls keep
    the factor of the stubbiest fitted wall. theta is held inside its fitted range likewise
    (optimisers probe far outside the bounds, where the polynomial in theta would overflow).
    """
    x = np.clip(np.asarray(t_over_L, dtype=float), 0.0, fitted_t_over_L_max())
    theta = np.clip(np.asarray(theta_rad, dtype=float), *fitted_theta_rad_range())
    return np.exp(design_matrix(x, theta) @ coefficients())
