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


def force_errors(
    F_model: ArrayLike,
    F_true: ArrayLike,
    range_N: float,
    flag: ArrayLike | None = None,
    upto_N: float = np.inf,
) -> dict:
    """Errors of ``F_model`` (N, NaN where a reading was flagged) against ``F_true`` (N, same
    shape) on the readings with ERROR_FROM_RANGE x ``range_N`` <= F_true < ``upto_N``: their
    count (``readings``), how many of them were flagged (NaN, or any ``flag`` but ok: a reading
    flagged above_calibrated keeps a force yet counts), and over the finite ones the median,
    95th percentile and largest relative error and the RMS error in N (those keys only when one
    is left)."""
    F_model, F_true = np.asarray(F_model, dtype=float), np.asarray(F_true, dtype=float)
    use = (F_true >= ERROR_FROM_RANGE * range_N) & (F_true > 0) & (F_true < upto_N)
    marked = ~np.isfinite(F_model) if flag is None else ~np.isfinite(F_model) | (np.asarray(flag) != "ok")
    flagged = int(np.sum(use & marked))
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


def force_errors_by_regime(F_model: ArrayLike, F_true: ArrayLike, edges_N: ArrayLike, flag: ArrayLike | None) -> list:
    """:func:`force_errors` per regime [edges[i], edges[i+1]) (the last one open above), each
    from ERROR_FROM_RANGE of its own top: the light-touch band is quoted on its own scale, not
    left out below a tenth of the whole range."""
    edges = np.asarray(edges_N, dtype=float)
    out = []
    for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        last = i == len(edges) - 2
        F_true = np.asarray(F_true, dtype=float)
        sub = np.where(F_true >= lo, F_true, -1.0)  # below the band: not used
        err = force_errors(F_model, sub, float(hi), flag, np.inf if last else float(hi))
        out.append({"regime": i + 1, "force_from_N": float(lo), "force_to_N": float(hi), **err})
    return out


def regime_error_lines(by_regime: list) -> list[str]:
    """One line per regime of :func:`force_errors_by_regime`'s result."""
    lines = []
    for e in by_regime:
        where = f"  regime {e['regime']} ({e['force_from_N']:.3g}-{e['force_to_N']:.4g} N"
        if "median_rel" in e:
            lines.append(
                f"{where}, F >= {max(e['from_force_N'], e['force_from_N']):.3g} N, {e['readings']} readings): "
                f"median {100 * e['median_rel']:.3g} %, 95th pct {100 * e['p95_rel']:.3g} %"
                + (f", {e['flagged']} flagged" if e["flagged"] else "")
            )
        else:
            lines.append(f"{where}): {e['readings']} readings" + (f", {e['flagged']} flagged" if e["readings"] else ""))
    return lines
