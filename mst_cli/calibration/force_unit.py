"""A load test's force column in a known other unit (issue 46): kgf, lbf, grams or millinewtons
logged under ``force_N``.

The design as drawn gives a force at every field the load test measured. A print misses its
drawing by tens of percent (its modulus, walls and gap), so the load test's forces are the
design's times a factor near 1. When that factor is instead within :data:`UNIT_TOLERANCE` of
1 / (newtons per unit) of a known unit, and further than :data:`PRINT_FACTOR` from 1, the
column is in that unit: refused naming it, with the conversion (the fit would otherwise read
a sensor 10 times softer than drawn as a modulus at its bound and blame the model).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math

import numpy as np

from mst_cli.calibration.loadtest import FORCE_COLUMN, Readings
from mst_cli.errors import InputError

N_PER_UNIT = {"kgf": 9.80665, "lbf": 4.4482216152605, "g": 0.00980665, "mN": 0.001}
UNIT_TOLERANCE = 1.5  # the factor found within this of a unit's
PRINT_FACTOR = 2.0  # a print's forces within this factor of its drawing's are newtons, whatever else
FROM_FORCE_REL = 0.1  # rows where the design reads at least this share of its range (no-load noise aside)
MIN_ROWS = 3


def force_factor(lt: Readings, B_curve_T: np.ndarray, F_curve_N: np.ndarray) -> float | None:
    """The median ratio of the load test's forces to the design's at the same |B| (``B_curve_T``
    ascending against ``F_curve_N``), over rows inside the curve where the design reads at
    least FROM_FORCE_REL of its range; None with fewer than MIN_ROWS such rows."""
    B, F = lt.B_abs_T, lt.load_N
    inside = (B >= B_curve_T[0]) & (B <= B_curve_T[-1])
    F_model = np.interp(B[inside], B_curve_T, F_curve_N)
    use = F_model >= FROM_FORCE_REL * float(F_curve_N[-1])
    if use.sum() < MIN_ROWS:
        return None
    return float(np.median(F[inside][use] / F_model[use]))


def check_force_unit(lt: Readings, B_curve_T: np.ndarray, F_curve_N: np.ndarray) -> None:
    """InputError naming the unit when the load test's forces are the design's divided by a
    known unit's newtons (module docstring)."""
    ratio = force_factor(lt, B_curve_T, F_curve_N)
    if ratio is None or not ratio > 0 or abs(math.log(ratio)) <= math.log(PRINT_FACTOR):
        return
    for unit, newtons in N_PER_UNIT.items():
        if abs(math.log(ratio * newtons)) <= math.log(UNIT_TOLERANCE):
            raise InputError(
                f"{lt.source} {FORCE_COLUMN}",
                f"{ratio:.4g} x the design's force at the measured field",
                f"the forces look like {unit} (1 {unit} = {newtons:g} N; a print misses its drawing by less than "
                f"x{PRINT_FACTOR:g}): {FORCE_COLUMN} must be newtons (convert: x {newtons:g})",
            )
