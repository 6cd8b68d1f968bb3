"""Is a calibration fit's misfit noise, or structure? (issue 38)

Given the normalised residuals r_i = (data - model) / sigma of a fit with p free parameters, in
row (time) order:

* the reduced chi-square chi2_nu = sum r^2 / (n - p): 1 for a right model and a right noise;
* a Wald-Wolfowitz runs test on the residuals' signs: R runs against the expectation
  mu = 2 n+ n- / n + 1 and variance (mu - 1)(mu - 2) / (n - 1), z = (R - mu) / sd; a model that
  misses the data leaves long runs of one sign (z strongly negative);
* the lag-1 autocorrelation sum r_i r_(i+1) / sum r_i^2;
* the branch and trend t: one least-squares fit of the residuals on a constant, the time (or
  row order) and an unloading-row indicator; the t of the indicator's coefficient (the unloading
  rows' mean offset from the loading rows', the trend held) and of the time's (the trend, the
  branch offset held). Fitted together because in a load test every unloading follows its
  loading: a drift alone offsets the unloading rows' mean by half a branch's drift, a Welch t
  near 4 on a 4-cycle rig (named "hysteresis" on 45 noise seeds of 200), and the fit apportions it;
* the cause, when the residuals are structured: "hysteresis" when the branch t is beyond
  :data:`CAUSE_T`, else "drift" when the trend t is, else "model" (an unmodelled nonlinearity, or
  the wrong design);
* one warning line when chi2_nu > :data:`WARN_CHI2` and the residuals show structure: the runs z
  < :data:`WARN_RUNS_Z`, or the branch or trend t beyond CAUSE_T. Both, because a large chi2_nu
  alone may be a too small stated noise (white residuals, no structure to name) and structure
  with chi2_nu near 1 is smaller than the noise (harmless); 2 and -3 keep white noise of a few
  hundred rows quiet (chi2_nu's sd is sqrt(2 / (n - p)), 0.08 at 300 rows; the runs z is
  standard normal) and catch a misfit of about the noise. The t's are scale-free (white noise of
  any size gives |t| > 4 once in 16 000) and catch what the runs test, which counts sign changes
  given the signs' numbers, misses: residuals mostly of one sign (a trend or a loop that no
  fitted parameter centres), where a 3 % loop (chi2_nu 210) or a 40-sigma trend gave a runs z
  above -3 on 5 and 46 noise seeds of 200 (studies/rig_seeds.py);
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
    branch_t: float  # t of the unloading rows' offset, the trend held (module doc); NaN without both branches
    trend_t: float  # t of the residuals' slope against time (or row), the branch offset held
    structured: bool  # chi2_nu > WARN_CHI2 and (runs_z < WARN_RUNS_Z or a t beyond CAUSE_T)
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


def branch_and_trend_t(
    r: np.ndarray, label: Sequence[str] | np.ndarray | None = None, time_s: np.ndarray | None = None
) -> tuple[float, float]:
    """(branch t, trend t) of ``r``: the t's of the unloading indicator's and the time's (row
    index without times) coefficients in one least-squares fit with a constant (module doc).
    The branch t is NaN without 2 rows of each branch; both NaN without 3 rows or a time span."""
    r = np.asarray(r, float)
    t = np.arange(len(r), dtype=float) if time_s is None else np.asarray(time_s, float)
    if len(r) < 3 or np.ptp(t) <= 0:
        return float("nan"), float("nan")
    lab = np.asarray(label, dtype=object) if label is not None else np.full(len(r), None)
    up, down = lab == LOADING, lab == UNLOADING
    both = up.sum() >= 2 and down.sum() >= 2
    cols = [np.ones_like(r), t - t.mean()] + ([down.astype(float)] if both else [])
    A = np.stack(cols, -1)
    if len(r) <= A.shape[1] or np.linalg.matrix_rank(A) < A.shape[1]:
        return float("nan"), float("nan")
    coef, *_ = np.linalg.lstsq(A, r, rcond=None)
    s2 = float(np.sum((r - A @ coef) ** 2)) / (len(r) - A.shape[1])
    se = np.sqrt(s2 * np.diag(np.linalg.inv(A.T @ A)))
    t_of = [float(c / e) if e > 0 else float("inf") * np.sign(c) for c, e in zip(coef, se)]
    # sign as before: mean(loading) - mean(unloading)
    return (-t_of[2] if both else float("nan")), t_of[1]


def _cause(b_t: float, tr_t: float) -> str:
    if math.isfinite(b_t) and abs(b_t) > CAUSE_T:
        return "hysteresis"
    if math.isfinite(tr_t) and abs(tr_t) > CAUSE_T:
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
    b_t, tr_t = branch_and_trend_t(r, label, None if time_s is None else np.asarray(time_s, float))
    shows = z < WARN_RUNS_Z or any(math.isfinite(x) and abs(x) > CAUSE_T for x in (b_t, tr_t))
    structured = bool(chi2_nu > WARN_CHI2 and shows)
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
