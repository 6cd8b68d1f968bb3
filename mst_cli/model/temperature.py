"""The part at another temperature than its calibration's (issue 38): the two linear laws every
reader applies and the calibration fits (:mod:`mst_cli.calibration.temperature`).

* the magnet: remanence x r(T) = 1 + alpha (T - T_ref), alpha the grade's reversible coefficient
  in %/K (:mod:`mst_cli.model.components`, -0.12 %/K for the N grades); the field is linear in
  the remanence, so the field at the chip scales by r(T) at a given deflection;
* the part: stiffness x m(T) = 1 + beta (T - T_ref), beta (1/K) a calibration parameter. Every
  layer law and every TPU member is linear in E at fixed nu, so a part of modulus x m deflects
  at F as the reference does at F / m.

Hence B(F, T) = r(T) B_ref(F / m(T)), and a reading B at T means the force
F = m(T) F_ref(B / r(T)), F_ref the calibration's inverse map (:func:`force_at_T`).

Pure: no I/O.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

REFERENCE_TEMPERATURE_C = 20.0  # datasheets state Br at room temperature, 20 degC


def remanence_scale(T_C, remanence_coeff_pct_per_K: float, T_ref_C: float = REFERENCE_TEMPERATURE_C) -> np.ndarray:
    """r(T): the remanence at T_C over its value at T_ref (alpha in %/K)."""
    return 1.0 + 0.01 * remanence_coeff_pct_per_K * (np.asarray(T_C, float) - T_ref_C)


def modulus_scale(T_C, modulus_coeff_per_K: float, T_ref_C: float = REFERENCE_TEMPERATURE_C) -> np.ndarray:
    """m(T): the part's stiffness at T_C over its value at T_ref (beta in 1/K)."""
    return 1.0 + modulus_coeff_per_K * (np.asarray(T_C, float) - T_ref_C)


def corrected_field_T(
    B_T, T_C, remanence_coeff_pct_per_K: float, T_ref_C: float = REFERENCE_TEMPERATURE_C
) -> np.ndarray:
    """The field (a component array or |B|) the magnet would give at T_ref: B / r(T)."""
    r = remanence_scale(T_C, remanence_coeff_pct_per_K, T_ref_C)
    B = np.asarray(B_T, float)
    return B / (r[..., None] if B.ndim > r.ndim else r)


def force_at_T(
    force_ref_N: Callable[[np.ndarray], np.ndarray],
    B_abs_T,
    T_C,
    remanence_coeff_pct_per_K: float,
    modulus_coeff_per_K: float,
    T_ref_C: float = REFERENCE_TEMPERATURE_C,
) -> np.ndarray:
    """Force of readings |B| at T_C from the calibration's inverse map at T_ref:
    F = m(T) F_ref(B / r(T))."""
    B_ref = corrected_field_T(B_abs_T, T_C, remanence_coeff_pct_per_K, T_ref_C)
    return modulus_scale(T_C, modulus_coeff_per_K, T_ref_C) * np.asarray(force_ref_N(B_ref), float)
