"""The force that lags the field (issue 47): estimate the lag from the load test itself, and fit
each logged force against the field at the force's own time.

A load cell's filter, a USB logger or a robot's controller write the force late: the force of a
row is the true force ``lag`` seconds earlier. Read as it is, the lag opens the loop (loading rows
read less force at a field, unloading rows more) and biases the loading fit by the force's rate
times the lag. The lag is the time shift that best lines up the two streams' rates:
the field's and the force's, each resampled on one even time grid (rows may be uneven, and a
row's force may be missing), smoothed over :data:`RATE_SMOOTH_S`, and the correlation of the
rates is largest at the lag (a parabola through the best shift and its neighbours gives the
fraction of a step). The field enters as a force first (|B|'s quantiles mapped onto the
force's, a map no time shift changes): the rates of |B| itself are the force's times the
curve's slope, which the part's stiffening changes along every press, so their correlation
peaked away from the lag by an amount that moved with the curve's shape (-32 ms on the part,
+5 ms on the layers-only stack, for the same rig). Grid points whose smoothed rate reaches
into a gap are left out (the rate there is the line interpolated across it). Its sigma: the
spread of the lag over :data:`LAG_BLOCKS` equal blocks of the test / sqrt(blocks), with a row
period's quantisation (step / sqrt(12)) added in quadrature. Rates, not levels: every press
reverses both streams at the same instant whatever the loop's shape, so hysteresis and softening
move the rates' correlation little, while the levels' correlation has a flat top. What still
moves it: a loop that reaches the rested field before the force reaches 0 (+15 ms for -3 % of the
turning force near no load) and the zero's offset after each unloading (-6 ms).

A lag within :data:`LAG_SIGNIFICANCE` sigma of 0 is not applied (the test cannot tell it from
none: a rig sampled once a second gives +-0.4 s). A row with a force is fitted against the
field interpolated at its time minus the lag (the field is on every row); a row without a force
is never fitted. A time step longer than
:data:`MAX_GAP_S` (or 5 median steps) is a gap: nothing is interpolated across it.

Without ``time_s`` nothing is shifted: the row order gives no seconds, so a lag reads as
hysteresis (the note says so).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from mst_cli.calibration.loadtest import Readings, rig_column

MAX_LAG_S = 1.0  # lags searched: -1..+1 s
LAG_STEP_S = 0.005
RATE_SMOOTH_S = 0.1  # the rates are smoothed over this window (the field's noise on a 50 Hz row)
LAG_BLOCKS = 5
MAX_GAP_S = 0.25
GAP_STEPS = 5.0
LAG_SIGNIFICANCE = 2.0
QUANTILES = 200  # the field-to-force map's knots
NO_TIME_NOTE = (
    "no time_s: the lag between the force and the field is neither measured nor removed (a lag of "
    "0.2 s reads as a loop of several % of full scale); log time_s with every row"
)


@dataclass(frozen=True)
class Alignment:
    """The lag of the force behind the field, and the rows a logger left without a force."""

    lag_s: float | None  # None: no time_s, or too few rows with a force
    sigma_s: float | None
    rows: int  # every row of the load test
    rows_without_force: int  # skipped (never fitted)
    rows_in_gaps: int  # rows with a force whose shifted time falls in a gap of the field
    gaps: int  # time steps longer than the gap limit
    note: str | None = None
    applied: bool = True

    def record(self) -> dict:
        """calibration.json's ``time_alignment``."""
        return {
            "lag_s": self.lag_s,
            "lag_sigma_s": self.sigma_s,
            "applied": self.lag_s is not None and self.applied,
            "rule": "the force of a row is fitted against the field at its time minus lag_s (the lag that "
            f"best lines up the rates of force and |B|, sigma from {LAG_BLOCKS} blocks of the test)",
            "rows": self.rows,
            "rows_without_force": self.rows_without_force,
            "rows_in_gaps": self.rows_in_gaps,
            "gaps": self.gaps,
            "note": self.note,
        }

    def line(self) -> str:
        """The summary's line."""
        skipped = f"; {self.rows_without_force} of {self.rows} rows without a force skipped, never fitted"
        if self.lag_s is None or not self.applied:
            why = f"not measured ({self.note})" if self.lag_s is None else str(self.note)
            return f"force lag: {why}{skipped if self.rows_without_force else ''}"
        return (
            f"force lag: the force is {1e3 * self.lag_s:.0f} +- {1e3 * (self.sigma_s or math.nan):.0f} ms behind "
            f"the field, removed{skipped if self.rows_without_force else ''}"
            + (f"; {self.gaps} gap(s) in the log" if self.gaps else "")
        )


def _max_gap(t: np.ndarray) -> float:
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    return max(MAX_GAP_S, GAP_STEPS * step)


def _bracketed(t_rows: np.ndarray, t_query: np.ndarray, gap_s: float) -> np.ndarray:
    """Whether each query time lies between two rows no further apart than ``gap_s``."""
    j = np.searchsorted(t_rows, t_query)
    inside = (j > 0) & (j < len(t_rows))
    jj = np.clip(j, 1, max(len(t_rows) - 1, 1))
    return inside & (t_rows[jj] - t_rows[jj - 1] <= gap_s) | np.isin(t_query, t_rows)


def _smoothed_rate(y: np.ndarray, step: float) -> np.ndarray:
    w = max(1, int(round(RATE_SMOOTH_S / step)))
    rate = np.gradient(y, step)
    return np.convolve(rate, np.ones(w) / w, mode="same")


def _force_equivalent(B: np.ndarray, F: np.ndarray) -> np.ndarray:
    """The field as a force: the monotone map that sends |B|'s quantiles over the test to the
    force's (rows with a force). A time shift moves neither distribution, so the map does not
    depend on the lag; it makes the field's rate proportional to the force's whatever the
    curve's shape (a stiffening part's |B| rises slower at high force, which otherwise
    weights the correlation towards the low-force ends of every press and tilts it)."""
    has = np.isfinite(F)
    q = np.linspace(0.0, 1.0, QUANTILES + 1)
    B_q, F_q = np.quantile(B, q), np.quantile(F[has], q)
    if np.corrcoef(B[has], F[has])[0, 1] < 0:  # |B| may fall as the force rises
        F_q = F_q[::-1]
    keep = np.r_[True, np.diff(B_q) > 0]  # flat stretches of |B| (quantised) map to one force
    return np.interp(B, B_q[keep], F_q[keep])


def _eroded(ok: np.ndarray, step: float) -> np.ndarray:
    """``ok`` less the grid points whose smoothed rate reaches into a gap (the rate across a
    gap is the straight line interpolated over it, not the streams')."""
    w = max(1, int(round(RATE_SMOOTH_S / step))) + 1
    return np.convolve((~ok).astype(float), np.ones(2 * w + 1), mode="same") == 0


def _best_lag(grid, B_grid, B_ok, tF, F, gap_s, step) -> float | None:
    """The shift of the force stream that best correlates its rate with the field's on ``grid``."""
    dB = _smoothed_rate(B_grid, step)
    lags = np.arange(-MAX_LAG_S, MAX_LAG_S + 1e-9, LAG_STEP_S)
    corr = np.full(len(lags), np.nan)
    for i, lag in enumerate(lags):
        q = grid + lag
        ok = _eroded(B_ok & _bracketed(tF, q, gap_s), step)
        if ok.sum() < 20:
            continue
        dF = _smoothed_rate(np.interp(q, tF, F), step)
        a, b = dB[ok] - dB[ok].mean(), dF[ok] - dF[ok].mean()
        denom = math.sqrt(float(np.sum(a * a) * np.sum(b * b)))
        corr[i] = float(np.sum(a * b)) / denom if denom > 0 else np.nan
    if not np.isfinite(corr).any():
        return None
    sign = 1.0 if np.nanmax(corr) >= -np.nanmin(corr) else -1.0  # |B| may fall as the force rises
    c = sign * np.where(np.isfinite(corr), corr, -np.inf)
    k = int(np.argmax(c))
    if 0 < k < len(c) - 1 and np.all(np.isfinite(c[k - 1 : k + 2])):
        den = c[k - 1] - 2 * c[k] + c[k + 1]
        return float(lags[k] + (0.5 * (c[k - 1] - c[k + 1]) / den * LAG_STEP_S if den < 0 else 0.0))
    return float(lags[k])


def estimate_lag(time_s, B_abs_T, force_N) -> tuple[float | None, float | None]:
    """(lag s, its sigma s) of the force behind the field; the force NaN where a row has none."""
    t, B, F = np.asarray(time_s, float), np.asarray(B_abs_T, float), np.asarray(force_N, float)
    has = np.isfinite(F)
    if has.sum() < 20 or len(t) < 20 or np.ptp(t) <= 0:
        return None, None
    step = float(np.median(np.diff(t)))
    if step <= 0:
        step = float(np.ptp(t)) / len(t)
    gap = _max_gap(t)
    grid = np.arange(t[0], t[-1], step)
    B_grid, B_ok = np.interp(grid, t, B), _bracketed(t, grid, gap)
    tF, FF = t[has], F[has]
    B_grid = np.interp(grid, t, _force_equivalent(B, F))
    lag = _best_lag(grid, B_grid, B_ok, tF, FF, gap, step)
    blocks = []
    for part in np.array_split(np.arange(len(grid)), LAG_BLOCKS):
        if len(part) > 40:
            g = grid[part]
            got = _best_lag(g, B_grid[part], B_ok[part], tF, FF, gap, step)
            if got is not None:
                blocks.append(got)
    # the blocks' spread, and a row period's uniform quantisation (the streams are sampled)
    spread = float(np.std(blocks, ddof=1) / math.sqrt(len(blocks))) if len(blocks) >= 2 else None
    sigma = None if spread is None else math.hypot(spread, step / math.sqrt(12.0))
    return lag, sigma


def align(lt: Readings, measure: bool = True) -> tuple[Readings, Alignment | None]:
    """(the rows with a force, each with the field at its time minus the lag; the alignment).
    Without time_s: the rows with a force as they are, and the note; ``measure=False``: as
    they are, no alignment."""
    F = lt.load_N
    has = np.isfinite(F)
    if not measure:
        return lt.subset(has), None
    t = rig_column(lt, "time_s")
    n_missing = int((~has).sum())
    if t is None:
        return lt.subset(has), Alignment(None, None, len(lt), n_missing, 0, 0, NO_TIME_NOTE)
    gap = _max_gap(t)
    gaps = int(np.sum(np.diff(t) > gap))
    lag, sigma = estimate_lag(t, lt.B_abs_T, F)
    if lag is None or sigma is None:
        note = "too few rows with a force to measure the lag"
        return lt.subset(has), Alignment(None, None, len(lt), n_missing, 0, gaps, note)
    if abs(lag) <= LAG_SIGNIFICANCE * sigma:
        note = f"{1e3 * lag:.0f} +- {1e3 * sigma:.0f} ms, within {LAG_SIGNIFICANCE:g} sigma of 0: not applied"
        return lt.subset(has), Alignment(lag, sigma, len(lt), n_missing, 0, gaps, note, applied=False)
    q = t[has] - lag
    ok = _bracketed(t, q, gap)
    B = np.stack([np.interp(q, t, lt.B_T[:, i]) for i in range(3)], -1)
    out = replace(lt.subset(has), B_T=B).subset(ok)
    return out, Alignment(lag, sigma, len(lt), n_missing, int((~ok).sum()), gaps)
