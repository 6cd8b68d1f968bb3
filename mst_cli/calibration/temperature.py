"""The modulus temperature coefficient of a load test (issue 38): its identifiability and its fit.

It fits the part's modulus coefficient beta of :mod:`mst_cli.model.temperature`'s laws,
B(F, T) = r(T) B_ref(F / m(T)). A stiff insert (PLA, PETG, steel) in the cap softens far less
than the TPU, so beta is the part's effective coefficient: the one law the fit measures and every
reader applies.

beta is fixed by the data only when the load test spans enough temperature:
:func:`modulus_coeff_sigma` gives its 1-sigma from the forward model's Jacobian (together with
the other fitted parameters, so a spread that only shifts the modulus does not count) and
:func:`modulus_coeff_identifiable` compares it with a third of :data:`MODULUS_COEFF_SCALE_PER_K`,
the fit's rule. :func:`fit_modulus_coeff` fits beta (and modulus_factor) to a load test at
several temperatures with the forward model.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from mst_cli.calibration.fit import IDENTIFIABLE_STD
from mst_cli.errors import CalibrationFailed
from mst_cli.model.temperature import REFERENCE_TEMPERATURE_C, modulus_scale, remanence_scale
from mst_cli.sensor.as_printed import PARAMETERS, full_values

# A typical size of TPU's modulus temperature coefficient near room temperature: the unit beta's
# identifiability is judged in (an assumption of scale, not a datasheet value: measure it).
MODULUS_COEFF_SCALE_PER_K = 0.005
STEP = 1e-3  # relative finite-difference step, in units of each parameter's scale

FieldAbs = Callable[[np.ndarray, dict], np.ndarray]  # |B| (T) of forces (N) at parameter values


def _predict(field_abs_T: FieldAbs, F: np.ndarray, T: np.ndarray, values: dict, alpha: float, beta: float, T_ref_C):
    """|B| of every row at its own temperature, r(T) B_ref(F / m(T)) (the model run once per
    distinct temperature)."""
    out = np.empty(len(F))
    for temp in np.unique(np.round(T, 3)):
        rows = np.round(T, 3) == temp
        m = float(modulus_scale(temp, beta, T_ref_C))
        out[rows] = float(remanence_scale(temp, alpha, T_ref_C)) * field_abs_T(F[rows] / m, values)
    return out


def _jacobian(field_abs_T: FieldAbs, F, T, values, alpha, beta, names, sigma_T, T_ref_C) -> np.ndarray:
    """Columns d(|B| / sigma) / d(parameter / scale) for ``names`` and then beta."""
    base = _predict(field_abs_T, F, T, values, alpha, beta, T_ref_C)
    cols = []
    for nm in names:
        v = dict(values)
        v[nm] = v[nm] + STEP * PARAMETERS[nm].scale
        cols.append((_predict(field_abs_T, F, T, v, alpha, beta, T_ref_C) - base) / STEP / sigma_T)
    h = STEP * MODULUS_COEFF_SCALE_PER_K
    cols.append((_predict(field_abs_T, F, T, values, alpha, beta + h, T_ref_C) - base) / STEP / sigma_T)
    return np.stack(cols, -1)


def modulus_coeff_sigma(
    field_abs_T: FieldAbs,
    force_N: Sequence[float] | np.ndarray,
    T_C: Sequence[float] | np.ndarray,
    values: dict,
    sigma_T: float,
    remanence_coeff_pct_per_K: float,
    names: Sequence[str] = ("modulus_factor",),
    T_ref_C: float = REFERENCE_TEMPERATURE_C,
) -> float:
    """1-sigma of beta (1/K) a load test at these forces and temperatures would give, fitted
    together with ``names`` (inf when the temperatures do not fix it at all)."""
    F, T = np.asarray(force_N, float), np.asarray(T_C, float)
    J = _jacobian(field_abs_T, F, T, full_values(values), remanence_coeff_pct_per_K, 0.0, names, sigma_T, T_ref_C)
    _, s, vt = np.linalg.svd(J, full_matrices=False)
    if s.min() <= 1e-9 * s.max():
        return float("inf")
    cov = (vt.T / s**2) @ vt
    return float(np.sqrt(cov[-1, -1]) * MODULUS_COEFF_SCALE_PER_K)


def modulus_coeff_identifiable(sigma_per_K: float) -> bool:
    """The fit's rule: sigma below a third of the coefficient's typical size."""
    return bool(sigma_per_K <= IDENTIFIABLE_STD * MODULUS_COEFF_SCALE_PER_K)


@dataclass(frozen=True)
class ModulusCoeffFit:
    modulus_coeff_per_K: float
    sigma_per_K: float
    modulus_factor: float
    modulus_factor_sigma: float
    identifiable: bool
    chi2_nu: float


def fit_modulus_coeff(
    field_abs_T: FieldAbs,
    force_N: Sequence[float] | np.ndarray,
    B_abs_T: Sequence[float] | np.ndarray,
    T_C: Sequence[float] | np.ndarray,
    values: dict,
    sigma_T: float,
    remanence_coeff_pct_per_K: float,
    T_ref_C: float = REFERENCE_TEMPERATURE_C,
) -> ModulusCoeffFit:
    """Least squares of beta and modulus_factor (the other values held) to |B| at several
    temperatures, in units of the noise; sigmas from the Jacobian x sqrt(chi2_nu) when above 1."""
    F, B, T = np.asarray(force_N, float), np.asarray(B_abs_T, float), np.asarray(T_C, float)
    v0 = full_values(values)
    s_m = PARAMETERS["modulus_factor"].scale

    def unpack(x):
        return {**v0, "modulus_factor": v0["modulus_factor"] + x[0] * s_m}, x[1] * MODULUS_COEFF_SCALE_PER_K

    def residual(x):
        v, beta = unpack(x)
        return (_predict(field_abs_T, F, T, v, remanence_coeff_pct_per_K, beta, T_ref_C) - B) / sigma_T

    res = least_squares(residual, np.zeros(2), x_scale=1.0, diff_step=STEP)
    if not res.success:
        raise CalibrationFailed(f"the modulus temperature coefficient fit failed: {res.message}")
    v, beta = unpack(res.x)
    chi2_nu = float(np.sum(res.fun**2) / max(len(F) - 2, 1))
    _, s, vt = np.linalg.svd(res.jac, full_matrices=False)
    cov = (vt.T / np.maximum(s, 1e-300) ** 2) @ vt * max(chi2_nu, 1.0)
    sd = np.sqrt(np.diag(cov))
    sig_beta = float(sd[1] * MODULUS_COEFF_SCALE_PER_K)
    return ModulusCoeffFit(
        float(beta),
        sig_beta,
        float(v["modulus_factor"]),
        float(sd[0] * s_m),
        modulus_coeff_identifiable(sig_beta),
        chi2_nu,
    )
