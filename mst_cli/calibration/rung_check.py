"""Another rung than the calibration's (issue 38): a calibration fits the print's parameters
with one mechanics rung (calibration.json ``models.mechanics``); read or designed with another,
the fitted values describe a sensor the other rung draws differently. :func:`rung_warning` says
so in one line, with how far apart the two rungs read forces on the calibrated design: the
largest relative difference of the force at equal |B| from a tenth of the calibrated range to its
top (:func:`rung_difference`: two inverse maps, each one simulation of the design).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import numpy as np

from mst_cli.errors import CalibrationFailed
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.model.mechanics import MODELS
from mst_cli.sensor.document import Document

FROM_FRACTION = 0.1  # the comparison starts at this fraction of the calibrated range (as the force errors)


def rung_difference(doc: Document, rung_a: str, rung_b: str, top_N: float | None = None) -> tuple[float, float]:
    """(largest |F_b - F_a| / F_a at equal |B|, the force F_a where it is) over F_a from
    :data:`FROM_FRACTION` of ``top_N`` (the calibrated range; default and at most both rungs'
    last lock) to ``top_N``. CalibrationFailed when a rung has no monotone map."""
    a, _ = inverse_map(doc, rung_a)
    b, _ = inverse_map(doc, rung_b)
    top = min(float(a.force_N[-1]), float(b.force_N[-1]), top_N if top_N else np.inf)
    F = np.linspace(FROM_FRACTION * top, top, 400)
    B = np.interp(F, a.force_N, a.B_abs_T)
    rel = np.abs(np.interp(B, b.B_abs_T, b.force_N) - F) / F
    i = int(np.argmax(rel))
    return float(rel[i]), float(F[i])


def rung_warning(
    calibrated_rung: object, used_rung: str, doc: Document | None, top_N: float | None, verb: str
) -> str | None:
    """One line when ``used_rung`` is not the calibration's (None when it is, or the record names
    no known rung); ``doc``: the calibrated design the difference is computed on (None: not said)."""
    if not isinstance(calibrated_rung, str) or calibrated_rung not in MODELS or calibrated_rung == used_rung:
        return None
    apart = ""
    if doc is not None:
        try:
            rel, at_N = rung_difference(doc, calibrated_rung, used_rung, top_N)
            apart = (
                f"; on this design the two read forces up to {100 * rel:.2g} % apart at equal |B| "
                f"(at {at_N:.3g} N, from {FROM_FRACTION:g} of the calibrated range to its top)"
            )
        except CalibrationFailed:
            apart = "; the two rungs could not be compared on this design"
    return (
        f"the calibration was fitted with the {calibrated_rung} rung and {verb} uses {used_rung}{apart}: "
        f"use --mechanics {calibrated_rung} (or calibrate again with --mechanics {used_rung})"
    )


def record_rung(record: object) -> str | None:
    """The rung a calibration record was fitted with (``models.mechanics``), None when it names none."""
    models = getattr(record, "models", None)
    rung = models.get("mechanics") if isinstance(models, dict) else None
    return rung if isinstance(rung, str) else None


def read_rung_warning(record, mechanics: str, doc: Document) -> str | None:
    """``mst read``'s warning when it reads with another rung than its calibration's: then the
    curve differs from the recorded one by the rung, not by a change of the model code."""
    return rung_warning(record_rung(record), mechanics, doc, record.calibrated_top_N(), "mst read")
