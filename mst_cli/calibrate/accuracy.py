"""How far forces read from a sensor's field are from the load cell's: the statistics
``calibration.json`` quotes for the load test and ``mst read`` for a file with a reference force.

Small forces are left out: near no load the relative error of any model is dominated by the
load cell's offset, so the errors are quoted on readings above :data:`ERROR_FROM_RANGE` of the
range.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

ERROR_FROM_RANGE = 0.1  # force errors are quoted on readings above this fraction of the range


def force_errors(F_model: ArrayLike, F_true: ArrayLike, range_N: float) -> dict:
    """Errors of ``F_model`` (N, NaN where a reading was flagged) against ``F_true`` (N, same
    shape) on the readings with F_true >= ERROR_FROM_RANGE x ``range_N``: their count
    (``readings``), how many of them were flagged, and over the rest the median, 95th percentile
    and largest relative error and the RMS error in N (those keys only when one is left)."""
    F_model, F_true = np.asarray(F_model, dtype=float), np.asarray(F_true, dtype=float)
    use = (F_true >= ERROR_FROM_RANGE * range_N) & (F_true > 0)
    flagged = int(np.sum(use & ~np.isfinite(F_model)))
    ok = use & np.isfinite(F_model)
    if not ok.any():
        return {"readings": int(use.sum()), "flagged": flagged}
    rel = np.abs(F_model[ok] - F_true[ok]) / F_true[ok]
    return {
        "readings": int(use.sum()),
        "flagged": flagged,
        "from_force_N": ERROR_FROM_RANGE * range_N,
        "median_rel": float(np.median(rel)),
        "p95_rel": float(np.percentile(rel, 95)),
        "max_rel": float(rel.max()),
        "rms_N": float(np.sqrt(np.mean((F_model[ok] - F_true[ok]) ** 2))),
    }
