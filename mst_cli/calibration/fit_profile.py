"""A fitted parameter's sigma where the model has a corner at the fit (issue 44).

The fit's sigma is the Jacobian's (:func:`~mst_cli.calibration.fit._uncertainty`): the model taken
as linear about the fitted values. The part's model is not smooth everywhere: the housing's cover
lands on the board after its air (which the gap offset sets), and where that landing enters the
load test's force range the cost turns a corner. A fit that ends on such a corner (the data
prefer the cover's landing just past the test's largest force, and the cost climbs steeply below
it but hardly above) gets the steep side's slope in its Jacobian: a sigma several times too
small on the flat side (0.0024 mm for a gap offset the data fix to about 0.015 mm above it).

A corner is told by the one-sided slopes of the residuals over one linear sigma, each way
(smooth: they agree to within :data:`CORNER_SLOPE_REL`). For a parameter at a corner the sigma is
the profile's: the parameter moved each way, the other free parameters fitted again, until the
chi-square has risen by 4 x the reduced chi-square (2 sigma with the fit's own scaling), and
half that reach (the larger side's) is the sigma: a corner's profile is no parabola (on the flat
side it rises about linearly), so its 1-sigma reach would understate the interval the data allow
at 2 sigma, which is what +-2 sigma is read as. Smooth parameters keep the Jacobian's sigma; the
correlations stay the Jacobian's.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from mst_cli.errors import CalibrationFailed
from mst_cli.sensor.as_printed import PARAMETERS

CORNER_SLOPE_REL = 0.5  # one-sided slopes differing by this share of their mean: a corner
PROFILE_STEPS = 12  # bisections of the profile's 1-sigma crossing
PROFILE_MAX_SIGMAS = 8.0  # the profile is searched this many linear 2-sigma reaches out
BOUND_MARGIN = 1e-3  # the profile stays this share of the bounds' span inside them (at a bound
# the housing cannot take the gap offset)
PROFILE_SIGMAS = 2.0  # the sigma is the profile's 2-sigma reach halved (module doc)

Residual = Callable[[np.ndarray], np.ndarray]  # scaled parameters -> residuals in noise units


def _chi2(residual: Residual, x: np.ndarray) -> float:
    return float(np.sum(residual(x) ** 2))


def at_corner(residual: Residual, x: np.ndarray, step: np.ndarray) -> bool:
    """Whether the residuals' one-sided slopes along ``step`` (scaled units) disagree."""
    r0 = residual(x)
    up, down = residual(x + step) - r0, r0 - residual(x - step)
    mean = 0.5 * (np.linalg.norm(up) + np.linalg.norm(down))
    return bool(mean > 0 and np.linalg.norm(up - down) > CORNER_SLOPE_REL * mean)


def _profile_chi2(residual: Residual, x: np.ndarray, i: int, value: float, lo, hi) -> float:
    """The chi-square with parameter ``i`` held at ``value``, the others fitted again."""
    from scipy.optimize import least_squares  # deferred: scipy.optimize is 0.2 s, only a profile needs it

    others = [j for j in range(len(x)) if j != i]
    if not others:
        y = x.copy()
        y[i] = value
        return _chi2(residual, y)

    def sub(z):
        y = x.copy()
        y[i], y[others] = value, z
        return residual(y)

    z0 = np.clip(x[others], lo[others] + 1e-9, hi[others] - 1e-9)
    res = least_squares(sub, z0, bounds=(lo[others], hi[others]), diff_step=1e-6, max_nfev=60)
    return float(np.sum(res.fun**2))


def _side_sigma(residual: Residual, x: np.ndarray, i: int, sigma: float, side: float, lo, hi, rise: float) -> float:
    """How far parameter ``i`` moves to ``side`` before the profile's chi-square rises by ``rise``."""
    chi0 = _chi2(residual, x)
    limit = ((hi[i] - x[i]) if side > 0 else (x[i] - lo[i])) - BOUND_MARGIN * (hi[i] - lo[i])
    a, b = 0.0, min(PROFILE_MAX_SIGMAS * sigma, limit)
    if b <= 0:
        return 0.0
    if _profile_chi2(residual, x, i, x[i] + side * b, lo, hi) - chi0 < rise:
        return b  # flat as far as searched (or to the bound)
    for _ in range(PROFILE_STEPS):
        m = 0.5 * (a + b)
        a, b = (m, b) if _profile_chi2(residual, x, i, x[i] + side * m, lo, hi) - chi0 < rise else (a, m)
    return 0.5 * (a + b)


def corner_sigmas(
    residual: Residual, x: np.ndarray, cov: np.ndarray, chi2_red: float, lo: Sequence[float], hi: Sequence[float]
) -> np.ndarray:
    """The sigmas (scaled units, per free parameter) of the Jacobian's covariance ``cov``, each
    parameter at a corner of the cost given its profile's sigma (the larger side's). The corner
    is looked for along the covariance's own 1-sigma direction of the parameter (the others
    following as the linear fit has them: their smooth share of the slope cancels there)."""
    x = np.asarray(x, float)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    out = std.copy()
    lo_a, hi_a = np.asarray(lo, float), np.asarray(hi, float)
    rise = PROFILE_SIGMAS**2 * max(chi2_red, 1.0)
    for i, sd in enumerate(std):
        if not (np.isfinite(sd) and sd > 0):
            continue
        step = cov[:, i] / sd
        margin = BOUND_MARGIN * (hi_a - lo_a)
        if np.any(x - np.abs(step) < lo_a + margin) or np.any(x + np.abs(step) > hi_a - margin):
            continue  # a sigma reaching a bound: the fit's own bound check speaks there
        try:
            if not at_corner(residual, x, step):
                continue
            sides = [_side_sigma(residual, x, i, PROFILE_SIGMAS * float(sd), s, lo_a, hi_a, rise) for s in (1.0, -1.0)]
        except CalibrationFailed:  # values the housing cannot take: no profile
            continue
        out[i] = max(float(sd), max(sides) / PROFILE_SIGMAS)
    return out


def corner_checked_std(model, force_N, B_abs_T, sigma_T: float, free: Sequence[str], values: dict, bounds: dict,
                       std: np.ndarray, corr: np.ndarray, chi2_red: float) -> np.ndarray:  # fmt: skip
    """:func:`corner_sigmas` of a fit of ``free`` (a :class:`~mst_cli.calibration.fit.ForwardModel`,
    the load test, the fitted ``values`` and ``bounds``), in the fit's scaled units."""
    P = [PARAMETERS[n] for n in free]
    x = np.array([(values[n] - p.nominal) / p.scale for n, p in zip(free, P)])
    lo = [(bounds[n][0] - p.nominal) / p.scale for n, p in zip(free, P)]
    hi = [(bounds[n][1] - p.nominal) / p.scale for n, p in zip(free, P)]

    def residual(z: np.ndarray) -> np.ndarray:
        v = {**values, **{n: p.nominal + p.scale * zi for n, p, zi in zip(free, P, z)}}
        return (model.field_abs_T(force_N, v) - B_abs_T) / sigma_T

    if not np.all(np.isfinite(std)):
        return std
    return corner_sigmas(residual, x, corr * np.outer(std, std), chi2_red, lo, hi)
