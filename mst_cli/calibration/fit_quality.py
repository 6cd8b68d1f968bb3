"""Is a calibration fit's misfit noise, or structure? (issue 38)

Given the normalised residuals r_i = (data - model) / sigma of a fit with p free parameters, in
row (time) order:

* the reduced chi-square chi2_nu = sum r^2 / (n - p): 1 for a right model and a right noise;
* a Wald-Wolfowitz runs test on the residuals' signs: R runs against the expectation
  mu = 2 n+ n- / n + 1 and variance (mu - 1)(mu - 2) / (n - 1), z = (R - mu) / sd; a model that
  misses the data leaves long runs of one sign (z strongly negative);
* the lag-1 autocorrelation sum r_i r_(i+1) / sum r_i^2;
* the cause, when the residuals are structured: "hysteresis" when the mean residual of the
  loading rows differs from the unloading rows' (Welch t beyond :data:`CAUSE_T`), else "drift"
  when the residuals trend with time (or row order; least-squares slope's t beyond CAUSE_T),
  else "model" (an unmodelled nonlinearity, or the wrong design);
* one warning line when chi2_nu > :data:`WARN_CHI2` and the runs z < :data:`WARN_RUNS_Z`: both
  at once, because a large chi2_nu alone may be a too small stated noise (white residuals, no
  structure to name) and a low runs z alone with chi2_nu near 1 is a structure smaller than the
  noise (harmless); 2 and -3 keep white noise of a few hundred rows quiet (chi2_nu's sd is
  sqrt(2 / (n - p)), 0.08 at 300 rows; the runs z is standard normal) and catch a misfit of
  about the noise;
* sigma inflation: every parameter sigma x sqrt(chi2_nu) when chi2_nu > 1 (the misfit is taken
  as extra noise), and identifiability judged again with the fit's rule: sigma below
  IDENTIFIABLE_STD (1/3) of the parameter's typical deviation.

Pure: returns a dataclass and the warning's text; prints nothing.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from mst_cli.calibration.branches import LOADING, UNLOADING
from mst_cli.calibration.fit import IDENTIFIABLE_STD
from mst_cli.sensor.as_printed import PARAMETERS

WARN_CHI2 = 2.0
WARN_RUNS_Z = -3.0
CAUSE_T = 4.0  # |t| of a branch difference or a trend that names the cause


@dataclass(frozen=True)
class FitQuality:
    n: int
    p: int
    chi2_nu: float
    runs: int
    runs_expected: float
    runs_z: float
    lag1: float
    branch_t: float  # Welch t of mean(loading) - mean(unloading); NaN without labels
    trend_t: float  # t of the residuals' slope against time (or row)
    structured: bool  # chi2_nu > WARN_CHI2 and runs_z < WARN_RUNS_Z
    cause: str | None  # "hysteresis" / "drift" / "model" when structured
    warning: str | None
    sigma: dict[str, float] = field(default_factory=dict)  # inflated
    identifiable: dict[str, bool] = field(default_factory=dict)


def runs_test(r: np.ndarray) -> tuple[int, float, float]:
    """(runs, expected runs, z) of the signs of ``r`` (zeros dropped)."""
    s = np.sign(np.asarray(r, float))
    s = s[s != 0]
    n_pos, n_neg = int((s > 0).sum()), int((s < 0).sum())
    n = n_pos + n_neg
    if n_pos == 0 or n_neg == 0:
        return (1 if n else 0), float("nan"), float("-inf") if n > 1 else float("nan")
    runs = 1 + int(np.count_nonzero(s[1:] != s[:-1]))
    mu = 2.0 * n_pos * n_neg / n + 1.0
    var = (mu - 1.0) * (mu - 2.0) / (n - 1.0)
    return runs, mu, (runs - mu) / math.sqrt(var) if var > 0 else float("nan")


def lag1_autocorrelation(r: np.ndarray) -> float:
    r = np.asarray(r, float)
    den = float(np.sum(r**2))
    return float(np.sum(r[1:] * r[:-1]) / den) if den > 0 else float("nan")


def branch_t(r: np.ndarray, label: Sequence[str] | np.ndarray) -> float:
    """Welch t of the mean residual on loading rows minus on unloading rows."""
    lab = np.asarray(label, dtype=object)
    a, b = r[lab == LOADING], r[lab == UNLOADING]
    if len(a) < 2 or len(b) < 2:
        return float("nan")
    se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
    return float((a.mean() - b.mean()) / se) if se > 0 else float("nan")


def trend_t(r: np.ndarray, time_s: np.ndarray | None = None) -> float:
    """t of the least-squares slope of the residuals against time (row index without times)."""
    t = np.arange(len(r), dtype=float) if time_s is None else np.asarray(time_s, float)
    if len(r) < 3 or np.ptp(t) <= 0:
        return float("nan")
    tc = t - t.mean()
    slope = float(np.sum(tc * (r - r.mean())) / np.sum(tc**2))
    resid = r - r.mean() - slope * tc
    se = math.sqrt(float(np.sum(resid**2)) / (len(r) - 2) / float(np.sum(tc**2)))
    return slope / se if se > 0 else float("inf")


def _cause(b_t: float, tr_t: float) -> str:
    if math.isfinite(b_t) and abs(b_t) > CAUSE_T:
        return "hysteresis"
    if abs(tr_t) > CAUSE_T:
        return "drift"
    return "model"


_ADVICE = {
    "hysteresis": "the loading and unloading rows differ: calibrate per branch (hysteresis model) or on loading only",
    "drift": "the residuals trend with time: re-zero the chip, check its temperature, shorten the test",
    "model": "the model misses the data's shape: check the design file, or fit a dearer mechanics rung",
}


def fit_quality(
    residual: Sequence[float] | np.ndarray,
    n_parameters: int,
    label: Sequence[str] | np.ndarray | None = None,
    time_s: Sequence[float] | np.ndarray | None = None,
    sigma: Mapping[str, float] | None = None,
) -> FitQuality:
    """Quality of a fit from its normalised residuals in row order (module doc). ``sigma``:
    the fitted parameters' 1-sigma (parameter units, not yet scaled by chi2_nu)."""
    r = np.asarray(residual, float)
    n, p = len(r), int(n_parameters)
    chi2_nu = float(np.sum(r**2) / max(n - p, 1))
    runs, mu, z = runs_test(r)
    b_t = branch_t(r, label) if label is not None else float("nan")
    tr_t = trend_t(r, None if time_s is None else np.asarray(time_s, float))
    structured = bool(chi2_nu > WARN_CHI2 and z < WARN_RUNS_Z)
    cause = _cause(b_t, tr_t) if structured else None
    warning = None
    if structured:
        warning = (
            f"the fit misses the load test beyond its noise (chi2_nu {chi2_nu:.2f}, runs z {z:.1f}): "
            f"likely {cause}; {_ADVICE[str(cause)]}; parameter sigmas inflated x{math.sqrt(chi2_nu):.2f}"
        )
    inflated, ident = inflate_sigmas(sigma or {}, chi2_nu)
    return FitQuality(
        n, p, chi2_nu, runs, mu, z, lag1_autocorrelation(r), b_t, tr_t, structured, cause, warning, inflated, ident
    )


def inflate_sigmas(sigma: Mapping[str, float], chi2_nu: float) -> tuple[dict[str, float], dict[str, bool]]:
    """Sigmas x sqrt(chi2_nu) when chi2_nu > 1, and identifiability by the fit's rule."""
    k = math.sqrt(chi2_nu) if chi2_nu > 1 else 1.0
    out = {nm: float(s) * k for nm, s in sigma.items()}
    return out, {nm: bool(s <= IDENTIFIABLE_STD * PARAMETERS[nm].scale) for nm, s in out.items()}
