"""The physical bounds of the fitted values ``mst read`` takes from a calibration.json (issue 46).

calibration.json sits beside the model, where a user may edit it. A value the reader applies
to every reading is checked where it is read, against the bound the physics sets, and refused
in one line naming its key (:class:`~mst_cli.errors.InputError`, exit 2): a missing or null
key is read as absent (the reader's default), anything else must be a number inside its bound.

The table :data:`BOUNDS` holds one :class:`Bound` per key (a new fitted key is one more row);
:func:`unloading_loop` checks the unloading model's terms together:

* ``temperature.modulus_temp_coeff_per_K`` (beta): the modulus scale m(T) = 1 + beta (T - 20)
  multiplies every force read at T. It must stay at least :data:`MIN_MODULUS_SCALE` over the
  MLX90393's operating range, -40 to 125 degC (datasheet; the range ``T_C`` is read in): a
  negative scale reads a press as a pull, and an elastomer that loses nine tenths of its
  stiffness over that range has left its rubbery plateau. Hence
  -(1 - 0.1) / 105 <= beta <= (1 - 0.1) / 60 per K (about -0.86 to +1.5 %/K);
* ``hysteresis.unloading_model`` (:class:`~mst_cli.calibration.hysteresis.UnloadingModel`):
  h = F_turn (c0 + c1 x + c2 x^2 + c3 x^3 [+ after_hold x^4]), x = F_load / F_turn, is what
  unloading takes off the loading force (mst 0.17 wrote h = F_turn x (1 - x) (a + b x), read as
  that polynomial). The loop may take either sign and stay open at its ends, but it is never
  wider than the press that made it: an unloading reading means a force F_load - h between none
  and F_turn, to within LOOP_MARGIN of F_turn (the fit's noise at the loop's ends), with and
  without the hold's term (:func:`unloading_loop`); each coefficient within +-MAX_LOOP_TERM;
  ``residual_rms_N`` is a spread (finite, >= 0, at most MAX_FORCE_N), ``rows`` a count
  (0 to the load test's MAX_ROWS);
* ``zero`` (:func:`~mst_cli.calibration.zero_drift.zero_law_of`): fields within what the chip
  reads (MAX_FIELD_UT), a drift within MAX_DRIFT_UT_PER_MIN, ``rests`` a count; its
  ``rest_noise_uT`` (the chip's noise logged at rest, the reader's noise) within what it reads;
* ``tilt.lever_factor``: inside the bounds the fit searches (LEVER_FACTOR_BOUNDS).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from mst_cli.calibration.loadtest import MAX_ROWS, T_C_RANGE
from mst_cli.calibration.tilt_fit import LEVER_FACTOR_BOUNDS
from mst_cli.errors import InputError
from mst_cli.model.temperature import REFERENCE_TEMPERATURE_C
from mst_cli.sensor.as_printed import CALIBRATION_JSON

MIN_MODULUS_SCALE = 0.1  # the least m(T) over the chip's range (module docstring)
LOOP_MARGIN = 0.05  # of F_turn: a fitted loop's ends within the rig's noise (measured loops are <= 3 % FS)
MAX_LOOP_TERM = 100.0  # a polynomial term of the loop; |h| <= F_turn bounds their sum (unloading_loop)
# |B| at the MLX90393's widest setting, 50 mT on each axis (datasheet: GAIN_SEL 0, RES 3): sqrt(3) x 50 mT
MAX_FIELD_UT = math.sqrt(3.0) * 50e3
MAX_DRIFT_UT_PER_MIN = 600.0  # 40 x the worst drift measured at rest on a real rig (15 uT/min, issue 47)
MAX_FORCE_N = 1e4  # a force spread no fingertip sensor reads (a kilonewton is a press, not a touch)
_BETA_LO = -(1.0 - MIN_MODULUS_SCALE) / (T_C_RANGE[1] - REFERENCE_TEMPERATURE_C)
_BETA_HI = (1.0 - MIN_MODULUS_SCALE) / (REFERENCE_TEMPERATURE_C - T_C_RANGE[0])


@dataclass(frozen=True)
class Bound:
    """What one key of calibration.json accepts: a number in [lo, hi] (``integer``: a whole one)."""

    key: str  # dotted path in calibration.json
    lo: float
    hi: float
    unit: str
    why: str
    integer: bool = False

    def allowed(self) -> str:
        kind = "a whole number" if self.integer else "a number"
        return f"must be {kind} from {self.lo:.4g} to {self.hi:.4g}{' ' + self.unit if self.unit else ''}: {self.why}"

    def check(self, value: Any) -> float:
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if not number or not math.isfinite(value) or not self.lo <= value <= self.hi:
            raise InputError(f"{CALIBRATION_JSON} {self.key}", value, self.allowed())
        if self.integer and value != int(value):
            raise InputError(f"{CALIBRATION_JSON} {self.key}", value, self.allowed())
        return float(value)


BOUNDS: dict[str, Bound] = {
    b.key: b
    for b in (
        Bound(
            "temperature.modulus_temp_coeff_per_K",
            _BETA_LO,
            _BETA_HI,
            "1/K",
            f"the modulus scale 1 + beta (T - {REFERENCE_TEMPERATURE_C:g}) stays >= {MIN_MODULUS_SCALE:g} over the "
            f"MLX90393's {T_C_RANGE[0]:g}..{T_C_RANGE[1]:g} degC",
        ),
        Bound("hysteresis.unloading_model.a", -1.0, 1.0, "", "the loop is never wider than the load"),
        Bound("hysteresis.unloading_model.b", -8.0, 8.0, "", "the loop is never wider than the load"),
        Bound("hysteresis.unloading_model.coefficients", -MAX_LOOP_TERM, MAX_LOOP_TERM, "", "a term of the loop"),
        Bound("hysteresis.unloading_model.after_hold", -MAX_LOOP_TERM, MAX_LOOP_TERM, "", "a term of the loop"),
        Bound("hysteresis.unloading_model.residual_rms_N", 0.0, MAX_FORCE_N, "N", "a spread of forces"),
        Bound("hysteresis.unloading_model.rows", 0, MAX_ROWS, "", "a count of load-test rows", integer=True),
        Bound("zero.rested_zero_uT", 0.0, MAX_FIELD_UT, "uT", "a |B| the MLX90393 can read"),
        Bound("zero.drift_uT_per_min", -MAX_DRIFT_UT_PER_MIN, MAX_DRIFT_UT_PER_MIN, "uT/min", "a slow drift"),
        Bound("zero.offset_after_unloading_uT", -MAX_FIELD_UT, MAX_FIELD_UT, "uT", "a |B| the MLX90393 can read"),
        Bound("zero.offset_after_first_press_uT", -MAX_FIELD_UT, MAX_FIELD_UT, "uT", "a |B| the MLX90393 can read"),
        Bound("zero.recovery_uT_per_decade", -MAX_FIELD_UT, MAX_FIELD_UT, "uT", "a |B| the MLX90393 can read"),
        Bound("zero.span_uT", 0.0, MAX_FIELD_UT, "uT", "a |B| the MLX90393 can read"),
        Bound("zero.rests", 0, MAX_ROWS, "", "a count of rests", integer=True),
        Bound("zero.rest_noise_uT", 0.0, MAX_FIELD_UT, "uT", "a noise the MLX90393 can read"),
        Bound("tilt.lever_factor", *LEVER_FACTOR_BOUNDS, "", "the range the tilt fit searches"),
    )
}


def checked(section: object, path: str, name: str) -> float | None:
    """The value of ``name`` in ``section``, the mapping at the dotted ``path`` of calibration.json
    (its key ``path.name`` a row of BOUNDS): None when missing or null (or ``section`` is not a
    mapping), else checked against its bound (InputError naming the key)."""
    value = section.get(name) if isinstance(section, dict) else None
    return None if value is None else BOUNDS[f"{path}.{name}"].check(value)


def checked_list(section: object, path: str, name: str, most: int = 8) -> list[float] | None:
    """Like :func:`checked` for a list of numbers (at most ``most`` of them), each within the
    bound of ``path.name``: None when missing or null, InputError naming the key otherwise."""
    value = section.get(name) if isinstance(section, dict) else None
    if value is None:
        return None
    bound = BOUNDS[f"{path}.{name}"]
    if not isinstance(value, list) or not 1 <= len(value) <= most:
        raise InputError(f"{CALIBRATION_JSON} {bound.key}", value, f"must be a list of 1 to {most} numbers")
    return [bound.check(v) for v in value]


def unloading_loop(coefficients: list[float], after_hold: float = 0.0) -> None:
    """The unloading force F_load - h stays within [-LOOP_MARGIN, 1 + LOOP_MARGIN] F_turn over
    0 <= F_load <= F_turn, with and without the hold's term, else InputError naming the model's
    terms. The extremes of x - c(x) are at the ends and at the real roots of its derivative
    inside (0, 1), so the check is exact."""
    lo, hi = 0.0, 0.0
    for hold in (0.0, after_hold):
        c = np.zeros(max(len(coefficients), 5))
        c[: len(coefficients)] = coefficients
        c[4] += hold
        c[1] -= 1.0  # h / F_turn - x: minus the unloading force over F_turn
        poly = -np.polynomial.Polynomial(c)
        roots = poly.deriv().trim(1e-12).roots()  # a term under 1e-12 moves nothing on [0, 1]
        inside = roots.real[(np.abs(roots.imag) < 1e-7) & (roots.real > 0.0) & (roots.real < 1.0)]
        values = poly(np.concatenate(([0.0, 1.0], inside)))
        lo, hi = min(lo, float(values.min())), max(hi, float(values.max()))
    if lo < -LOOP_MARGIN or hi > 1.0 + LOOP_MARGIN:
        raise InputError(
            f"{CALIBRATION_JSON} hysteresis.unloading_model.coefficients",
            [*coefficients, after_hold],
            f"an unloading reading would mean {lo:.3g} to {hi:.3g} x the turn's force: it lies between no force and "
            f"the turn's, to within {LOOP_MARGIN:g} of it",
        )
