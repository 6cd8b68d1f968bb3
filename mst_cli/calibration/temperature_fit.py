"""Temperature in ``mst calibrate`` and ``mst read`` (issue 38), on the laws of
:mod:`~mst_cli.calibration.temperature`: B(F, T) = r(T) B_ref(F / m(T)) about the reference
temperature :data:`~mst_cli.model.components.REFERENCE_TEMPERATURE_C` (20 degC, the grades'
remanence is stated there), r from the magnet grade's coefficient, m from the modulus
coefficient ``modulus_temp_coeff_per_K``.

* calibrate, when the load test has a ``T_C`` column: every row is referred to 20 degC
  (:func:`referred`: |B| / r(T), force / m(T)) before the elastic fit; the modulus coefficient is
  fitted (:func:`~mst_cli.calibration.temperature.fit_modulus_coeff`, with the modulus factor, the
  other values held at the first fit's) and, when identifiable, the elastic fit repeated with it;
  otherwise it is held at 0 and named. calibration.json gets ``temperature``
  (:meth:`TemperatureCalibration.record`).
* read, when the readings have ``T_C``: each reading's |B| is divided by r(T) and its force
  multiplied by m(T) (:func:`reading_scales`), the coefficient from calibration.json's
  ``temperature`` (0 without one).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from mst_cli.calibration.loadtest import Readings, rig_column
from mst_cli.calibration.record_bounds import checked
from mst_cli.calibration.temperature import fit_modulus_coeff
from mst_cli.errors import CalibrationFailed
from mst_cli.model.components import (
    MAGNET_REMANENCE_COEFF_PCT_PER_K,
    NDFEB_REMANENCE_COEFF_PCT_PER_K,
    REFERENCE_TEMPERATURE_C,
)
from mst_cli.model.temperature import modulus_scale, remanence_scale
from mst_cli.sensor.document import Document

T_COLUMN = "T_C"
KEY = "modulus_temp_coeff_per_K"


def remanence_coeff_of(doc: Document) -> float:
    """The magnet's reversible remanence coefficient (%/K): its grade's (NdFeB's without one)."""
    return MAGNET_REMANENCE_COEFF_PCT_PER_K.get(doc.magnet.grade, NDFEB_REMANENCE_COEFF_PCT_PER_K)


def referred(lt: Readings, alpha_pct_per_K: float, beta_per_K: float) -> Readings:
    """The rows as at the reference temperature: field / r(T), force / m(T) (unchanged without T_C)."""
    T = rig_column(lt, T_COLUMN)
    if T is None:
        return lt
    r = remanence_scale(T, alpha_pct_per_K)
    out = replace(lt, B_T=lt.B_T / r[:, None])
    if beta_per_K and lt.force_N is not None:
        out = replace(out, force_N=lt.force_N / modulus_scale(T, beta_per_K))
    return out


@dataclass(frozen=True)
class TemperatureCalibration:
    """What calibrate made of the load test's temperatures."""

    span_C: tuple[float, float]
    remanence_coeff_pct_per_K: float
    modulus_coeff_per_K: float
    sigma_per_K: float | None
    fitted: bool
    why: str

    def record(self) -> dict:
        """calibration.json's ``temperature``."""
        return {
            "reference_C": REFERENCE_TEMPERATURE_C,
            "load_test_T_C": list(self.span_C),
            "remanence_coeff_pct_per_K": self.remanence_coeff_pct_per_K,
            KEY: self.modulus_coeff_per_K,
            "sigma_per_K": self.sigma_per_K,
            "fitted": self.fitted,
            "why": self.why,
            "law": "B(F, T) = r(T) B_20(F / m(T)), r = 1 + alpha (T - 20), m = 1 + beta (T - 20): "
            "mst read corrects readings with a T_C column",
        }

    def line(self) -> str:
        """The terminal line of ``mst calibrate``."""
        lo, hi = self.span_C
        sd = f" +- {self.sigma_per_K * 100:.2g}" if self.sigma_per_K is not None else ""
        state = "fitted" if self.fitted else "held"
        return (
            f"temperature {lo:g}-{hi:g} degC, referred to {REFERENCE_TEMPERATURE_C:g} degC: remanence "
            f"{self.remanence_coeff_pct_per_K:+.3g} %/K (the grade's); {KEY} {self.modulus_coeff_per_K * 100:+.3g}"
            f"{sd} %/K {state}" + ("" if self.fitted else f" ({self.why})")
        )


def calibrate_temperature(
    doc: Document, lt: Readings, fit_values: dict, field_abs_T: Callable, sigma_T: float
) -> TemperatureCalibration | None:
    """The modulus coefficient of a load test with a T_C column (None without one): fitted with
    the modulus factor to the raw rows at the first fit's values, kept when identifiable."""
    T = rig_column(lt, T_COLUMN)
    if T is None:
        return None
    alpha = remanence_coeff_of(doc)
    span = (float(T.min()), float(T.max()))
    if np.ptp(T) == 0:
        return TemperatureCalibration(span, alpha, 0.0, None, False, "one temperature: held at 0")
    try:
        got = fit_modulus_coeff(field_abs_T, lt.load_N, lt.B_abs_T, T, fit_values, sigma_T, alpha)
    except CalibrationFailed as exc:
        return TemperatureCalibration(span, alpha, 0.0, None, False, f"held at 0: {exc}")
    sd = got.sigma_per_K if math.isfinite(got.sigma_per_K) else None
    if not got.identifiable:
        why = "held at 0: the load test's temperatures do not fix it to a third of 0.5 %/K"
        return TemperatureCalibration(span, alpha, 0.0, sd, False, why)
    return TemperatureCalibration(span, alpha, got.modulus_coeff_per_K, sd, True, "fitted to the load test's T_C")


def reading_scales(rd: Readings, doc: Document, temperature: object) -> tuple[np.ndarray, np.ndarray] | None:
    """(r(T), m(T)) of each reading with a T_C column, None without one; the modulus coefficient
    from calibration.json's ``temperature`` (0 without a usable one)."""
    T = rig_column(rd, T_COLUMN)
    if T is None:
        return None
    beta = checked(temperature, "temperature", KEY) or 0.0  # InputError beyond its physical bound
    return remanence_scale(T, remanence_coeff_of(doc)), modulus_scale(T, beta)
